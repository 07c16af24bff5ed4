#include "relaxed_connectivity/shell/shell_bending_form.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace rc {
namespace {

constexpr double kResidualPenalty = 4.0;  // the isotropic formula's weight on the unexplained part

// d_k of node i's fibers with the node at local[0] and its neighbours at local[1..k] (the energy's
// measurement: fan normal, then each fiber's arc length and normal angle).
void localCurvatureChanges(const ShellNodes& nodes, const Fiber* fib, size_t m, size_t i, const Vec3* local,
                           double* d) {
  Vec3 normal_sum = Vec3::Zero();
  for (size_t p = nodes.fan_offsets[i]; p < nodes.fan_offsets[i + 1]; ++p) {
    const auto& pr = nodes.fan_pairs[p];
    normal_sum += (local[1 + pr.first] - local[0]).cross(local[1 + pr.second] - local[0]);
  }
  const double length = normal_sum.norm();
  const Vec3 normal = length > 0.0 ? Vec3(normal_sum / length) : nodes.rest_normals[i];
  constexpr double inv_beta = 1.0 / kFiberSplineAngleScale;
  for (size_t q = 0; q < m; ++q) {
    FiberMeasure t;
    measureFiber(local[1 + fib[q].local1] - local[0], local[1 + fib[q].local2] - local[0], normal, false, &t);
    d[q] = (t.angle / t.length - fib[q].rest_angle / fib[q].rest_length) * inv_beta;
  }
}

// The isotropic formula 4 W - 2 w w^T.
void isotropicForm(const Fiber* fib, size_t m, double* form) {
  for (size_t a = 0; a < m; ++a)
    for (size_t b = 0; b < m; ++b)
      form[a * m + b] = (a == b ? 4.0 * fib[a].weight : 0.0) - 2.0 * fib[a].weight * fib[b].weight;
}

// Fills node i's form; returns true if the fit was used.
bool nodeForm(const ShellNodes& nodes, const Fiber* fib, size_t m, size_t i, double min_response,
              double* form, double* bound) {
  isotropicForm(fib, m, form);
  *bound = 4.0;
  if (m < 3) return false;
  const size_t k = nodes.neighborCount(i);
  const uint32_t* nb = nodes.neighborsOf(i);
  const Vec3 n = nodes.rest_normals[i];
  const Vec3 u = n.cross(std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).normalized();
  const Vec3 v = n.cross(u);
  std::vector<Vec3> rest(k + 1), local(k + 1);
  rest[0] = nodes.rest_positions[i];
  double reach = 0.0;
  for (size_t s = 0; s < k; ++s) {  // the stencil flattened onto the tangent plane
    const Vec3 e = nodes.rest_positions[nb[s]] - rest[0];
    rest[1 + s] = rest[0] + e.dot(u) * u + e.dot(v) * v;
    reach = std::max(reach, (rest[1 + s] - rest[0]).norm());
  }
  if (!(reach > 0.0)) return false;
  // Curvature step: neighbours move by about 1e-5 of their distance.
  const double eps = 2e-5 / reach;
  Eigen::MatrixXd a(m, 3);
  std::vector<double> plus(m), minus(m);
  for (int c = 0; c < 3; ++c) {
    for (double sign : {1.0, -1.0}) {
      for (size_t s = 0; s <= k; ++s) {
        const Vec3 e = rest[s] - rest[0];
        const double eu = e.dot(u), ev = e.dot(v);
        const double height = c == 0 ? 0.5 * eu * eu : c == 1 ? eu * ev : 0.5 * ev * ev;  // S_uu, S_uv, S_vv
        local[s] = rest[s] + (sign * eps * height) * n;
      }
      localCurvatureChanges(nodes, fib, m, i, local.data(), sign > 0.0 ? plus.data() : minus.data());
    }
    for (size_t q = 0; q < m; ++q) a(q, c) = (plus[q] - minus[q]) / (2.0 * eps);
  }
  Eigen::VectorXd w(m);
  for (size_t q = 0; q < m; ++q) w(q) = fib[q].weight;
  if (!(w.minCoeff() > 0.0) || !a.allFinite()) return false;
  // In scaled components t = D^1/2 s (|t|^2 = |s|_F^2): d ~ B t, B = A D^-1/2. Components the fibers barely
  // see (eigenvalues of B^T W B at or below min_response; at an edge node the curvature across the edge) are
  // left out of the fit: their part of d stays in the residual.
  const Eigen::Vector3d d_inv_sqrt(1.0, std::sqrt(0.5), 1.0);
  const Eigen::MatrixXd b = a * d_inv_sqrt.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(b.transpose() * w.asDiagonal() * b);
  Eigen::Matrix3d pseudo_inverse = Eigen::Matrix3d::Zero();
  for (int c = 0; c < 3; ++c) {
    const double lambda = eig.eigenvalues()(c);
    if (lambda > min_response)
      pseudo_inverse += eig.eigenvectors().col(c) * eig.eigenvectors().col(c).transpose() / lambda;
  }
  if (pseudo_inverse.isZero()) return false;
  // t = G d with G = (B^T W B)^+ B^T W; r = (I - B G) d.
  const Eigen::MatrixXd g = pseudo_inverse * b.transpose() * w.asDiagonal();
  const Eigen::MatrixXd residual = Eigen::MatrixXd::Identity(m, m) - b * g;
  Eigen::MatrixXd q = g.transpose() * g + kResidualPenalty * residual.transpose() * w.asDiagonal() * residual;
  q = 0.5 * (q + q.transpose()).eval();
  const Eigen::VectorXd w_inv_sqrt = w.cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd relative = w_inv_sqrt.asDiagonal() * q * w_inv_sqrt.asDiagonal();
  *bound =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(relative, Eigen::EigenvaluesOnly).eigenvalues()(m - 1);
  for (size_t r = 0; r < m; ++r)
    for (size_t c = 0; c < m; ++c) form[r * m + c] = q(r, c);
  return true;
}

// True if node i has the same neighbours and fibers (ends, weights) in both topologies.
bool sameStencil(const ShellNodes& nodes, const ShellFibers& fibers, const ShellNodes& old_nodes,
                 const ShellFibers& old_fibers, size_t i) {
  const size_t k = nodes.neighborCount(i);
  if (old_nodes.neighborCount(i) != k ||
      !std::equal(nodes.neighborsOf(i), nodes.neighborsOf(i) + k, old_nodes.neighborsOf(i)))
    return false;
  const size_t f0 = fibers.node_offsets[i], m = fibers.node_offsets[i + 1] - f0;
  const size_t o0 = old_fibers.node_offsets[i];
  if (old_fibers.node_offsets[i + 1] - o0 != m) return false;
  for (size_t q = 0; q < m; ++q) {
    const Fiber &a = fibers.fibers[f0 + q], &b = old_fibers.fibers[o0 + q];
    if (a.end1 != b.end1 || a.end2 != b.end2 || a.weight != b.weight) return false;
  }
  return true;
}

}  // namespace

ShellBendingForms buildShellBendingForms(const ShellNodes& nodes, const ShellFibers& fibers,
                                         double min_response, const ShellBendingFormsReuse* previous) {
  const size_t n = nodes.size();
  const bool can_reuse = previous && previous->forms && previous->nodes && previous->fibers &&
                         previous->forms->min_response == min_response && previous->nodes->size() == n &&
                         previous->forms->offsets.size() == n + 1;
  ShellBendingForms out;
  out.min_response = min_response;
  out.offsets.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    const size_t m = fibers.node_offsets[i + 1] - fibers.node_offsets[i];
    out.offsets[i + 1] = out.offsets[i] + m * m;
  }
  out.values.assign(out.offsets[n], 0.0);
  out.bound.assign(n, 4.0);
  out.fitted.assign(n, 0);
  std::vector<uint8_t> reused(n, 0);
#pragma omp parallel for schedule(dynamic, 64) if (n >= 1024)
  for (size_t i = 0; i < n; ++i) {
    const size_t f0 = fibers.node_offsets[i], m = fibers.node_offsets[i + 1] - f0;
    if (m == 0) continue;
    if (can_reuse && sameStencil(nodes, fibers, *previous->nodes, *previous->fibers, i)) {
      const ShellBendingForms& old = *previous->forms;
      std::copy(old.values.begin() + old.offsets[i], old.values.begin() + old.offsets[i + 1],
                out.values.begin() + out.offsets[i]);
      out.bound[i] = old.bound[i];
      out.fitted[i] = old.fitted[i];
      reused[i] = 1;
      continue;
    }
    out.fitted[i] = nodeForm(nodes, fibers.fibers.data() + f0, m, i, min_response,
                             out.values.data() + out.offsets[i], &out.bound[i]);
  }
  for (size_t i = 0; i < n; ++i) out.fitted_nodes += out.fitted[i], out.reused_nodes += reused[i];
  return out;
}

}  // namespace rc
