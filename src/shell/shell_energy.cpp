#include "relaxed_connectivity/shell/shell_energy.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {
namespace {
// Below this node count a parallel loop costs more than it saves.
constexpr size_t kParallelNodes = 2048;
}  // namespace

ShellEnergy::ShellEnergy(const ShellNodes& nodes, const ShellFibers& fibers, const ShellMaterial& material,
                         const ShellBendingFormsReuse* previous)
    : nodes_(&nodes), fibers_(&fibers), material_(material) {
  const size_t n = nodes.size();
  if (fibers.node_offsets.size() != n + 1) {
    throw std::invalid_argument("ShellEnergy: the fibers were built for another node set");
  }
  if (!(material.stretch_stiffness >= 0.0) || !(material.bending_stiffness >= 0.0) ||
      !(material.areal_density > 0.0) || !(material.damping >= 0.0) || !(material.bending_fit > 0.0)) {
    throw std::invalid_argument(
        "ShellMaterial: stiffnesses and damping must be >= 0, areal_density and bending_fit > 0");
  }
  masses_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    if (!(nodes.rest_areas[i] > 0.0)) {
      throw std::invalid_argument("ShellEnergy: node " + std::to_string(i) + " has no rest area");
    }
    masses_[i] = material.areal_density * nodes.rest_areas[i];
  }
  slot_offsets_.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) slot_offsets_[i + 1] = slot_offsets_[i] + 1 + nodes.neighborCount(i);
  std::vector<size_t> count(n + 1, 0);
  auto target = [&](size_t i, size_t s) { return s == 0 ? i : nodes.neighborsOf(i)[s - 1]; };
  for (size_t i = 0; i < n; ++i) {
    for (size_t s = 0; s <= nodes.neighborCount(i); ++s) ++count[target(i, s) + 1];
  }
  gather_offsets_.assign(n + 1, 0);
  for (size_t p = 0; p < n; ++p) gather_offsets_[p + 1] = gather_offsets_[p] + count[p + 1];
  gather_slots_.resize(gather_offsets_[n]);
  std::vector<size_t> fill(gather_offsets_.begin(), gather_offsets_.end() - 1);
  for (size_t i = 0; i < n; ++i) {
    for (size_t s = 0; s <= nodes.neighborCount(i); ++s)
      gather_slots_[fill[target(i, s)]++] = slot_offsets_[i] + s;
  }
  slot_values_.resize(slot_offsets_[n]);
  bending_forms_ = buildShellBendingForms(nodes, fibers, material.bending_fit, previous);
}

double ShellEnergy::evaluateNode(size_t i, const std::vector<Vec3>& x, Vec3* slots, double* membrane,
                                 double* bending, double* fiber_length, double* fiber_angle) const {
  const ShellNodes& nodes = *nodes_;
  const uint32_t* nb = nodes.neighborsOf(i);
  const size_t k = nodes.neighborCount(i);
  const size_t f0 = fibers_->node_offsets[i], f1 = fibers_->node_offsets[i + 1];
  const Fiber* fib = fibers_->fibers.data() + f0;
  const double area = nodes.rest_areas[i];
  const double ks = material_.stretch_stiffness, kb = material_.bending_stiffness;
  constexpr double inv_beta = 1.0 / kSplineAngleScale;
  const size_t m = f1 - f0;
  if (m == 0) {  // cut off by cracks: no fibers, no energy
    if (membrane) *membrane = 0.0;
    if (bending) *bending = 0.0;
    if (slots)
      for (size_t q = 0; q <= k; ++q) slots[q].setZero();
    return 0.0;
  }
  const Vec3 xc = x[i];
  Vec3 normal_sum = Vec3::Zero();  // fanNormal, inlined on edge vectors
  for (size_t p = nodes.fan_offsets[i]; p < nodes.fan_offsets[i + 1]; ++p) {
    const auto& pr = nodes.fan_pairs[p];
    normal_sum += (x[nb[pr.first]] - xc).cross(x[nb[pr.second]] - xc);
  }
  const double normal_length = normal_sum.norm();
  const Vec3 normal = normal_length > 0.0 ? Vec3(normal_sum / normal_length) : nodes.rest_normals[i];

  // Per-fiber terms on the stack (heap only for unusually large neighbourhoods).
  constexpr size_t kStackFibers = 32;
  FiberMeasure stack_terms[kStackFibers];
  thread_local std::vector<FiberMeasure> heap_terms;
  FiberMeasure* terms = stack_terms;
  if (m > kStackFibers) {
    heap_terms.resize(m);
    terms = heap_terms.data();
  }
  const bool want_gradient = slots != nullptr;

  // Per-fiber factors (7.3.4): the fiber term of fiber k is scaled by stretch_scale, the area term by their
  // weighted mean; bending uses g_k = sqrt(bend_scale) d_k in place of d_k (stays >= 0 by Cauchy-Schwarz).
  double s = 0.0, s0 = 0.0, fiber_stretch = 0.0, mean_scale = 0.0;
  // Per fiber: d_k, 1 / l_k, 1 / (l_k^0)^2 (two divisions per fiber instead of six).
  double stack_scratch[4 * kStackFibers];
  thread_local std::vector<double> heap_scratch;
  double* dk = stack_scratch;
  if (m > kStackFibers) {
    heap_scratch.resize(4 * m);
    dk = heap_scratch.data();
  }
  double* inv_len = dk + m;
  double* inv_l0sq = inv_len + m;
  double* q_dk = inv_l0sq + m;             // Q_i d
  for (size_t q = 0; q + 1 < m; q += 2) {  // two fibers per call (SIMD lanes)
    const Fiber &fa = fib[q], &fb = fib[q + 1];
    const Vec3 e1[2] = {x[fa.end1] - xc, x[fb.end1] - xc}, e2[2] = {x[fa.end2] - xc, x[fb.end2] - xc};
    measureFiberPair(e1, e2, normal, want_gradient, terms + q);
  }
  if (m % 2)
    measureFiber(x[fib[m - 1].end1] - xc, x[fib[m - 1].end2] - xc, normal, want_gradient, terms + m - 1);
  for (size_t q = 0; q < m; ++q) {
    const Fiber& f = fib[q];
    const FiberMeasure& t = terms[q];
    if (fiber_length) fiber_length[q] = t.length;
    if (fiber_angle) fiber_angle[q] = t.angle;
    const double sqrt_bend = f.bend_scale == 1.0 ? 1.0 : std::sqrt(f.bend_scale);
    const double inv_l = 1.0 / t.length, inv_l0 = 1.0 / f.rest_length;
    inv_len[q] = inv_l;
    inv_l0sq[q] = inv_l0 * inv_l0;
    dk[q] = sqrt_bend * (t.angle * inv_l - f.rest_angle * inv_l0) * inv_beta;  // (7.9), calibrated
    const double l0sq = f.rest_length * f.rest_length;
    const double lsq = t.length * t.length;
    s += f.weight * lsq;
    s0 += f.weight * l0sq;
    const double e = lsq * inv_l0sq[q] - 1.0;  // A_k / A_k^0 - 1 (7.5)
    fiber_stretch += f.weight * f.stretch_scale * e * e;
    mean_scale += f.weight * f.stretch_scale;
  }
  const double* form = bending_forms_.values.data() + bending_forms_.offsets[i];
  double form_value = 0.0;
  for (size_t a = 0; a < m; ++a) {
    double row = 0.0;
    for (size_t b = 0; b < m; ++b) row += form[a * m + b] * dk[b];
    q_dk[a] = row;
    form_value += dk[a] * row;
  }
  const double r = s / s0 - 1.0;                                                // A_i / A_i^0 - 1 (7.6)
  const double e_mem = 0.5 * area * ks * (mean_scale * r * r + fiber_stretch);  // (7.7)
  const double e_bend = 0.5 * area * kb * form_value;  // (7.3), (7.11); shell_bending_form.h
  if (membrane) *membrane = e_mem;
  if (bending) *bending = e_bend;
  if (!slots) return e_mem + e_bend;

  for (size_t q = 0; q <= k; ++q) slots[q].setZero();
  Vec3 dn = Vec3::Zero();
  const double area_kb = area * kb, area_ks2 = 2.0 * area * ks, area_term = mean_scale * r / s0;
  for (size_t q = 0; q < m; ++q) {  // (7.16), (7.17)
    const Fiber& f = fib[q];
    const FiberMeasure& t = terms[q];
    const double sqrt_bend = f.bend_scale == 1.0 ? 1.0 : std::sqrt(f.bend_scale);
    const double de_dkappa = area_kb * q_dk[q] * sqrt_bend;
    const double de_dtheta = de_dkappa * inv_len[q] * inv_beta;
    const double de_dl =
        area_ks2 * f.weight * t.length *
            (area_term + f.stretch_scale * (t.length * t.length * inv_l0sq[q] - 1.0) * inv_l0sq[q]) -
        de_dtheta * t.angle * inv_len[q];
    const Vec3 g1 = de_dl * t.grad_length[0] + de_dtheta * t.grad_angle[0];
    const Vec3 g2 = de_dl * t.grad_length[1] + de_dtheta * t.grad_angle[1];
    slots[1 + f.local1] += g1;
    slots[1 + f.local2] += g2;
    slots[0] -= g1 + g2;  // translation invariance of l and theta at fixed N
    dn += de_dtheta * t.grad_normal;
  }
  if (normal_length > 0.0) {  // through N = n / |n|, n = sum (x_a - x_i) x (x_b - x_i)
    const Vec3 g = (dn - normal * normal.dot(dn)) / normal_length;
    for (size_t p = nodes.fan_offsets[i]; p < nodes.fan_offsets[i + 1]; ++p) {
      const auto& pr = nodes.fan_pairs[p];
      const Vec3 ea = x[nb[pr.first]] - xc, eb = x[nb[pr.second]] - xc;
      const Vec3 ga = eb.cross(g), gb = g.cross(ea);
      slots[1 + pr.first] += ga;
      slots[1 + pr.second] += gb;
      slots[0] -= ga + gb;
    }
  }
  return e_mem + e_bend;
}

void ShellEnergy::gatherSlots(const std::vector<Vec3>& slot_values, std::vector<Vec3>& out) const {
  const size_t n = nodes_->size();
  out.resize(n);
#pragma omp parallel for schedule(static) if (n >= kParallelNodes)
  for (size_t p = 0; p < n; ++p) {
    Vec3 sum = Vec3::Zero();
    for (size_t g = gather_offsets_[p]; g < gather_offsets_[p + 1]; ++g) sum += slot_values[gather_slots_[g]];
    out[p] = sum;
  }
}

ShellEnergyValue ShellEnergy::evaluate(const std::vector<Vec3>& x, std::vector<Vec3>* gradient) const {
  return evaluate(x, gradient, nullptr, nullptr);
}

ShellEnergyValue ShellEnergy::evaluate(const std::vector<Vec3>& x, std::vector<Vec3>* gradient,
                                       std::vector<double>* fiber_length,
                                       std::vector<double>* fiber_angle) const {
  const size_t n = nodes_->size();
  if (x.size() != n)
    throw std::invalid_argument("ShellEnergy::evaluate: position count differs from node count");
  node_membrane_.resize(n);
  node_bending_.resize(n);
  if (fiber_length) fiber_length->resize(fibers_->size());
  if (fiber_angle) fiber_angle->resize(fibers_->size());
  double* lengths = fiber_length ? fiber_length->data() : nullptr;
  double* angles = fiber_angle ? fiber_angle->data() : nullptr;
  const size_t* offsets = fibers_->node_offsets.data();
#pragma omp parallel for schedule(static) if (n >= kParallelNodes)
  for (size_t i = 0; i < n; ++i) {
    evaluateNode(i, x, gradient ? slot_values_.data() + slot_offsets_[i] : nullptr, &node_membrane_[i],
                 &node_bending_[i], lengths ? lengths + offsets[i] : nullptr,
                 angles ? angles + offsets[i] : nullptr);
  }
  if (gradient) gatherSlots(slot_values_, *gradient);
  ShellEnergyValue value;
  for (size_t i = 0; i < n; ++i) value.membrane += node_membrane_[i], value.bending += node_bending_[i];
  return value;  // fixed summation order: deterministic for any thread count
}

void ShellEnergy::nodeEnergies(const std::vector<Vec3>& x, std::vector<double>* membrane,
                               std::vector<double>* bending) const {
  const size_t n = nodes_->size();
  std::vector<double> mem(n), bend(n);
#pragma omp parallel for schedule(static) if (n >= kParallelNodes)
  for (size_t i = 0; i < n; ++i) evaluateNode(i, x, nullptr, &mem[i], &bend[i]);
  if (membrane) *membrane = std::move(mem);
  if (bending) *bending = std::move(bend);
}

std::vector<double> ShellEnergy::fiberCurvatures(const std::vector<Vec3>& x) const {
  std::vector<double> kappa(fibers_->size());
  const size_t n = nodes_->size();
#pragma omp parallel for schedule(static) if (n >= kParallelNodes)
  for (size_t i = 0; i < n; ++i) {
    const Vec3 normal = fanNormal(*nodes_, i, x);
    for (size_t q = fibers_->node_offsets[i]; q < fibers_->node_offsets[i + 1]; ++q) {
      const Fiber& f = fibers_->fibers[q];
      kappa[q] = fiberNormalAngle(x[f.end1], x[i], x[f.end2], normal) /
                 (kSplineAngleScale * fiberArcLength(x[f.end1], x[i], x[f.end2]));
    }
  }
  return kappa;
}

std::vector<double> ShellEnergy::nodeMeanCurvature(const std::vector<Vec3>& x) const {
  const std::vector<double> kappa = fiberCurvatures(x);
  std::vector<double> h(nodes_->size(), 0.0);
  for (size_t i = 0; i < h.size(); ++i) {
    for (size_t q = fibers_->node_offsets[i]; q < fibers_->node_offsets[i + 1]; ++q) {
      h[i] += fibers_->fibers[q].weight * kappa[q];
    }
  }
  return h;
}

ShellStableStep ShellEnergy::stableStep(const std::vector<Vec3>& x) const {
  const ShellNodes& nodes = *nodes_;
  const size_t n = nodes.size();
  const double ks = material_.stretch_stiffness, kb = material_.bending_stiffness;
  constexpr double beta = kSplineAngleScale;
  std::vector<double> row_mem(slot_offsets_[n], 0.0), row_bend(slot_offsets_[n], 0.0);
#pragma omp parallel if (n >= kParallelNodes)
  {
    std::vector<Vec3> g_area, g;  // per thread, sized to the largest neighbourhood seen
#pragma omp for schedule(static)
    for (size_t i = 0; i < n; ++i) {
      const uint32_t* nb = nodes.neighborsOf(i);
      const size_t k = nodes.neighborCount(i);
      const double area = nodes.rest_areas[i];
      double normal_length = 0.0;
      const Vec3 normal = fanNormal(nodes, i, x, &normal_length);
      double* rm = row_mem.data() + slot_offsets_[i];
      double* rb = row_bend.data() + slot_offsets_[i];
      g_area.assign(k + 1, Vec3::Zero());
      g.resize(k + 1);
      double s0 = 0.0, mean_scale = 0.0;
      for (size_t q = fibers_->node_offsets[i]; q < fibers_->node_offsets[i + 1]; ++q) {
        const Fiber& f = fibers_->fibers[q];
        s0 += f.weight * f.rest_length * f.rest_length;
        mean_scale += f.weight * f.stretch_scale;
      }
      if (s0 <= 0.0) continue;  // no fibers
      // Adds c |g_p| sum_q |g_q| to row p for a Gauss-Newton term c g g^T.
      auto add_term = [&](double c, const std::vector<Vec3>& gv, double* rows) {
        double norms[256], sum = 0.0;
        for (size_t p = 0; p <= k; ++p) sum += (norms[p] = gv[p].norm());
        for (size_t p = 0; p <= k; ++p) rows[p] += c * norms[p] * sum;
      };
      for (size_t q = fibers_->node_offsets[i]; q < fibers_->node_offsets[i + 1]; ++q) {
        const Fiber& f = fibers_->fibers[q];
        FiberMeasure fm;
        measureFiber(x[f.end1] - x[i], x[f.end2] - x[i], normal, true, &fm);
        const Vec3 gl[3] = {fm.grad_length[0], -(fm.grad_length[0] + fm.grad_length[1]), fm.grad_length[1]};
        const Vec3 gt[3] = {fm.grad_angle[0], -(fm.grad_angle[0] + fm.grad_angle[1]), fm.grad_angle[1]};
        const double l = fm.length, theta = fm.angle;
        const double l0sq = f.rest_length * f.rest_length;
        std::fill(g.begin(), g.end(), Vec3::Zero());
        g[1 + f.local1] = gl[0] * (2.0 * l / l0sq), g[0] = gl[1] * (2.0 * l / l0sq),
              g[1 + f.local2] = gl[2] * (2.0 * l / l0sq);
        add_term(area * ks * f.weight * f.stretch_scale, g, rm);
        g_area[1 + f.local1] += gl[0] * (2.0 * f.weight * l / s0);
        g_area[0] += gl[1] * (2.0 * f.weight * l / s0);
        g_area[1 + f.local2] += gl[2] * (2.0 * f.weight * l / s0);
        const double scale = 1.0 / (beta * l), scale_l = -theta / (beta * l * l);  // d kappa / d theta, d l
        std::fill(g.begin(), g.end(), Vec3::Zero());
        g[1 + f.local1] = gt[0] * scale + gl[0] * scale_l, g[0] = gt[1] * scale + gl[1] * scale_l;
        g[1 + f.local2] = gt[2] * scale + gl[2] * scale_l;
        if (normal_length > 0.0) {
          const Vec3 gamma = (fm.grad_normal - normal * normal.dot(fm.grad_normal)) * (scale / normal_length);
          for (size_t p = nodes.fan_offsets[i]; p < nodes.fan_offsets[i + 1]; ++p) {
            const auto& pr = nodes.fan_pairs[p];
            const Vec3 ea = x[nb[pr.first]] - x[i], eb = x[nb[pr.second]] - x[i];
            const Vec3 ga = eb.cross(gamma), gb = gamma.cross(ea);
            g[1 + pr.first] += ga, g[1 + pr.second] += gb, g[0] -= ga + gb;
          }
        }
        add_term(bending_forms_.bound[i] * area * kb * f.weight * f.bend_scale, g, rb);  // Q_i <= bound W
      }
      add_term(area * ks * mean_scale, g_area, rm);
    }
  }
  double lambda_mem = 0.0, lambda_bend = 0.0, lambda_sum = 0.0;
  for (size_t p = 0; p < n; ++p) {
    double sm = 0.0, sb = 0.0;
    for (size_t g = gather_offsets_[p]; g < gather_offsets_[p + 1]; ++g) {
      sm += row_mem[gather_slots_[g]], sb += row_bend[gather_slots_[g]];
    }
    lambda_mem = std::max(lambda_mem, sm / masses_[p]);
    lambda_bend = std::max(lambda_bend, sb / masses_[p]);
    lambda_sum = std::max(lambda_sum, (sm + sb) / masses_[p]);
  }
  ShellStableStep step;
  step.membrane = lambda_mem > 0.0 ? 2.0 / std::sqrt(lambda_mem) : INFINITY;
  step.bending = lambda_bend > 0.0 ? 2.0 / std::sqrt(lambda_bend) : INFINITY;
  step.combined = lambda_sum > 0.0 ? 2.0 / std::sqrt(lambda_sum) : INFINITY;
  return step;
}

}  // namespace rc
