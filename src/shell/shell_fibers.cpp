#include "shell/shell_fibers.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>

namespace rc {
namespace {

// Gauss-Legendre points and weights on [0, 1].
constexpr double kGaussS[3] = {0.5 - 0.5 * 0.7745966692414834, 0.5, 0.5 + 0.5 * 0.7745966692414834};
constexpr double kGaussW[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};

// d t0 / d(x1, x, x2) and d t1 / d(x1, x, x2) for the end tangents t0 = b1, t1 = b2 + 2 c2 + 3 d2.
constexpr double kT0[3] = {-1.25, 1.5, -0.25};
constexpr double kT1[3] = {0.25, -1.5, 1.25};

// Isotropic directional weights (see buildShellFibers), for fiber directions given as angles.
std::vector<double> isotropicWeights(const std::vector<double>& angles) {
  const int m = static_cast<int>(angles.size());
  Eigen::MatrixXd b(5, m);
  for (int k = 0; k < m; ++k) {
    const double a = angles[k];
    b.col(k) << std::cos(2 * a), std::sin(2 * a), std::cos(4 * a), std::sin(4 * a), 1.0;
  }
  Eigen::VectorXd ones = Eigen::VectorXd::Ones(m);
  Eigen::VectorXd target = Eigen::VectorXd::Zero(5);
  target(4) = m;
  const Eigen::VectorXd delta = b.completeOrthogonalDecomposition().solve(target - b * ones);
  const double lowest = (ones + delta).minCoeff();
  const double keep = lowest < 0.2 ? (1.0 - 0.2) / (1.0 - lowest) : 1.0;
  Eigen::VectorXd w = ones + keep * delta;
  w /= w.sum();
  return std::vector<double>(w.data(), w.data() + m);
}

}  // namespace

FiberSpline fiberSpline(const Vec3& x1, const Vec3& x, const Vec3& x2) {
  // Natural spline with knots at 0, 1, 2: middle moment M = 3/2 (x1 - 2x + x2) (B.3).
  const Vec3 q = x1 - 2.0 * x + x2;
  FiberSpline s;
  s.a1 = x1;
  s.b1 = x - x1 - 0.25 * q;
  s.c1 = Vec3::Zero();
  s.d1 = 0.25 * q;
  s.a2 = x;
  s.b2 = 0.5 * (x2 - x1);
  s.c2 = 0.75 * q;
  s.d2 = -0.25 * q;
  return s;
}

double fiberArcLength(const Vec3& x1, const Vec3& x, const Vec3& x2, std::array<Vec3, 3>* grad) {
  const FiberSpline s = fiberSpline(x1, x, x2);
  double length = 0.0;
  if (grad) grad->fill(Vec3::Zero());
  for (int g = 0; g < 3; ++g) {
    const double t = kGaussS[g], w = kGaussW[g];
    const Vec3 d1 = s.b1 + 3.0 * s.d1 * t * t;                   // f1'(t)
    const Vec3 d2 = s.b2 + 2.0 * s.c2 * t + 3.0 * s.d2 * t * t;  // f2'(t)
    const double n1 = d1.norm(), n2 = d2.norm();
    length += w * (n1 + n2);
    if (!grad) continue;
    // (B.6): coefficients of x1, x, x2 in f1'(t) and f2'(t).
    const double c1[3] = {-1.25 + 0.75 * t * t, 1.5 - 1.5 * t * t, -0.25 + 0.75 * t * t};
    const double c2[3] = {-0.5 + 1.5 * t - 0.75 * t * t, -3.0 * t + 1.5 * t * t,
                          0.5 + 1.5 * t - 0.75 * t * t};
    const Vec3 u1 = n1 > 0.0 ? Vec3(d1 / n1) : Vec3::Zero();
    const Vec3 u2 = n2 > 0.0 ? Vec3(d2 / n2) : Vec3::Zero();
    for (int p = 0; p < 3; ++p) (*grad)[p] += w * (c1[p] * u1 + c2[p] * u2);
  }
  return length;
}

double fiberTangentAngle(const Vec3& x1, const Vec3& x, const Vec3& x2) {
  const Vec3 t0 = kT0[0] * x1 + kT0[1] * x + kT0[2] * x2;
  const Vec3 t1 = kT1[0] * x1 + kT1[1] * x + kT1[2] * x2;
  const double c = t0.dot(t1) / (t0.norm() * t1.norm());
  return std::acos(std::max(-1.0, std::min(1.0, c)));
}

double fiberNormalAngle(const Vec3& x1, const Vec3& x, const Vec3& x2, const Vec3& normal,
                        std::array<Vec3, 3>* grad, Vec3* grad_normal) {
  const Vec3 t0 = kT0[0] * x1 + kT0[1] * x + kT0[2] * x2;
  const Vec3 t1 = kT1[0] * x1 + kT1[1] * x + kT1[2] * x2;
  const double l0 = t0.norm(), l1 = t1.norm();
  const Vec3 h0 = t0 / l0, h1 = t1 / l1;
  constexpr double kMax = 1.0 - 1e-12;
  const double u0 = std::max(-kMax, std::min(kMax, normal.dot(h0)));
  const double u1 = std::max(-kMax, std::min(kMax, normal.dot(h1)));
  const double r0 = 1.0 / std::sqrt(1.0 - u0 * u0), r1 = 1.0 / std::sqrt(1.0 - u1 * u1);
  if (grad) {
    const Vec3 g0 = (normal - u0 * h0) * (r0 / l0);   // d theta / d t0
    const Vec3 g1 = -(normal - u1 * h1) * (r1 / l1);  // d theta / d t1
    for (int p = 0; p < 3; ++p) (*grad)[p] = kT0[p] * g0 + kT1[p] * g1;
  }
  if (grad_normal) *grad_normal = r0 * h0 - r1 * h1;
  return std::asin(u0) - std::asin(u1);
}

namespace {
// Coefficients of e1 = x1 - x and e2 = x2 - x in f1'(t) and f2'(t) at the Gauss points (B.6).
struct ArcBasis {
  double a1[3], b1[3], a2[3], b2[3];
};
constexpr ArcBasis makeArcBasis() {
  ArcBasis b{};
  for (int g = 0; g < 3; ++g) {
    const double t = kGaussS[g];
    b.a1[g] = -1.25 + 0.75 * t * t, b.b1[g] = -0.25 + 0.75 * t * t;
    b.a2[g] = -0.5 + 1.5 * t - 0.75 * t * t, b.b2[g] = 0.5 + 1.5 * t - 0.75 * t * t;
  }
  return b;
}
constexpr ArcBasis kArcBasis = makeArcBasis();
}  // namespace

void measureFiber(const Vec3& e1, const Vec3& e2, const Vec3& normal, bool gradients, FiberMeasure* out) {
  const ArcBasis& b = kArcBasis;
  double length = 0.0;
  Vec3 gl1 = Vec3::Zero(), gl2 = Vec3::Zero();
  for (int g = 0; g < 3; ++g) {  // (B.4), (B.6)
    const Vec3 d1 = b.a1[g] * e1 + b.b1[g] * e2, d2 = b.a2[g] * e1 + b.b2[g] * e2;
    const double n1 = d1.norm(), n2 = d2.norm(), w = kGaussW[g];
    length += w * (n1 + n2);
    if (!gradients) continue;
    const Vec3 u1 = n1 > 0.0 ? Vec3(d1 * (w / n1)) : Vec3::Zero();
    const Vec3 u2 = n2 > 0.0 ? Vec3(d2 * (w / n2)) : Vec3::Zero();
    gl1 += b.a1[g] * u1 + b.a2[g] * u2;
    gl2 += b.b1[g] * u1 + b.b2[g] * u2;
  }
  out->length = length;
  // End tangents t0 = b1, t1 = b2 + 2 c2 + 3 d2 (kT0, kT1 on x1 - x, x2 - x).
  const Vec3 t0 = kT0[0] * e1 + kT0[2] * e2, t1 = kT1[0] * e1 + kT1[2] * e2;
  const double l0 = t0.norm(), l1 = t1.norm();
  const Vec3 h0 = t0 / l0, h1 = t1 / l1;
  constexpr double kMax = 1.0 - 1e-12;
  const double u0 = std::max(-kMax, std::min(kMax, normal.dot(h0)));
  const double u1 = std::max(-kMax, std::min(kMax, normal.dot(h1)));
  out->angle = std::asin(u0) - std::asin(u1);
  if (!gradients) return;
  const double r0 = 1.0 / std::sqrt(1.0 - u0 * u0), r1 = 1.0 / std::sqrt(1.0 - u1 * u1);
  const Vec3 g0 = (normal - u0 * h0) * (r0 / l0);   // d theta / d t0
  const Vec3 g1 = -(normal - u1 * h1) * (r1 / l1);  // d theta / d t1
  out->grad_length[0] = gl1;
  out->grad_length[1] = gl2;
  out->grad_angle[0] = kT0[0] * g0 + kT1[0] * g1;
  out->grad_angle[1] = kT0[2] * g0 + kT1[2] * g1;
  out->grad_normal = r0 * h0 - r1 * h1;
}

std::vector<Fiber> buildNodeFibers(const ShellNodes& nodes, size_t i, double min_rest_length) {
  const std::vector<Vec3>& x = nodes.rest_positions;
  const uint32_t* nb = nodes.neighborsOf(i);
  const size_t k = nodes.neighborCount(i);
  std::vector<Fiber> out;
  std::set<std::pair<uint8_t, uint8_t>> seen;
  const Vec3 normal = fanNormal(nodes, i, x);
  for (size_t a = 0; a < k; ++a) {
    const Vec3 ej = x[nb[a]] - x[i];
    size_t best = k;
    double best_value = INFINITY;
    // Most opposite neighbour by direction. (7.4) minimises (x_j' - x_j) . (x_j - x_i), which prefers far
    // neighbours and leaves fibers kinked in the tangent plane; the kinks bias the curvature of cylinders
    // by -5 % (measured), the direction criterion by < 2 %.
    for (size_t b = 0; b < k; ++b) {
      if (b == a) continue;
      const double value = (x[nb[b]] - x[i]).normalized().dot(ej);
      if (value < best_value) best_value = value, best = b;
    }
    if (best == k) continue;
    const auto key =
        std::make_pair(static_cast<uint8_t>(std::min(a, best)), static_cast<uint8_t>(std::max(a, best)));
    if (!seen.insert(key).second) continue;
    Fiber f;
    f.center = static_cast<uint32_t>(i);
    f.local1 = static_cast<uint8_t>(a);
    f.local2 = static_cast<uint8_t>(best);
    f.end1 = nb[a];
    f.end2 = nb[best];
    f.rest_length = fiberArcLength(x[f.end1], x[i], x[f.end2]);
    if (f.rest_length < min_rest_length) continue;
    f.rest_angle = fiberNormalAngle(x[f.end1], x[i], x[f.end2], normal);
    out.push_back(f);
  }
  if (out.empty()) return out;
  Vec3 u = normal.cross(std::abs(normal.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).normalized();
  Vec3 v = normal.cross(u);
  std::vector<double> angles;
  for (const Fiber& f : out) {
    const Vec3 d = x[f.end2] - x[f.end1];
    angles.push_back(std::atan2(d.dot(v), d.dot(u)));
  }
  const std::vector<double> w = isotropicWeights(angles);
  for (size_t m = 0; m < w.size(); ++m) out[m].weight = w[m];
  return out;
}

ShellFibers buildShellFibers(const ShellNodes& nodes) {
  const size_t n = nodes.size();
  ShellFibers out;
  out.node_offsets.assign(n + 1, 0);
  std::vector<std::vector<Fiber>> per_node(n);
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; ++i) per_node[i] = buildNodeFibers(nodes, i);
  for (size_t i = 0; i < n; ++i) {
    if (per_node[i].size() < 3) {
      throw std::invalid_argument("buildShellFibers: node " + std::to_string(i) + " has only " +
                                  std::to_string(per_node[i].size()) +
                                  " distinct fibers (anisotropic neighbourhood)");
    }
  }
  for (size_t i = 0; i < n; ++i) {
    out.node_offsets[i + 1] = out.node_offsets[i] + per_node[i].size();
    out.fibers.insert(out.fibers.end(), per_node[i].begin(), per_node[i].end());
  }
  return out;
}

}  // namespace rc
