// Fibers of a point-sampled thin shell (thesis 7.2.1, appendix B): natural cubic splines through a node and
// two of its neighbours, their arc length (B.4) and signed tangent angle with analytic gradients.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/shell/shell_nodes.h"

namespace rc {

/// A natural spline through three points of a circle turns its end tangents by 3/4 of the true arc angle: the
/// fiber curvature is kappa = theta / (3/4 l) (ShellEnergy).
constexpr double kFiberSplineAngleScale = 0.75;

/// One fiber x1 -> x -> x2 centred on node `center`; `local1`/`local2` index the centre's neighbour list.
struct Fiber {
  uint32_t center = 0, end1 = 0, end2 = 0;
  uint8_t local1 = 0, local2 = 0;
  double rest_length = 0.0;  ///< l^0 (B.4)
  double rest_angle = 0.0;   ///< theta^0 (signed normal turning angle, see fiberNormalAngle)
  double weight = 0.0;       ///< directional weight at the centre; the weights of one node sum to 1
  /// Per-fiber stiffness factors (7.3.4, anisotropic / inhomogeneous material): K_s and K_b of this fiber are
  /// the material's times these (see ShellEnergy).
  double stretch_scale = 1.0;
  double bend_scale = 1.0;
};

/// Fibers grouped by centre node: node i owns fibers[node_offsets[i] .. node_offsets[i+1]).
struct ShellFibers {
  std::vector<Fiber> fibers;
  std::vector<size_t> node_offsets;
  size_t size() const { return fibers.size(); }
};

/// Builds one fiber per neighbour j with j' the most opposite neighbour (7.4; measured by the direction
/// cosine (x_j' - x_i)^ . (x_j - x_i)^ rather than the dot product of (7.4)), drops duplicates, sets the rest
/// length and angle, and gives each node's fibers weights that make their directions isotropic (second and
/// fourth angular moments of an even distribution, as far as the fibers allow; weights stay >= 0.2 of the
/// mean). Throws std::invalid_argument if a node ends with fewer than 3 fibers.
ShellFibers buildShellFibers(const ShellNodes& nodes);

/// The fibers of node i alone, as buildShellFibers makes them (rest state from nodes.rest_positions), but
/// without the minimum count: a node cut off by cracks may get fewer than 3 fibers (or none). Fibers whose
/// rest length is below `min_rest_length` are left out before the weights are computed.
std::vector<Fiber> buildNodeFibers(const ShellNodes& nodes, size_t i, double min_rest_length = 0.0);

/// Natural cubic spline coefficients (B.2, B.3) of the two segments, knots at x1, x, x2 (uniform).
struct FiberSpline {
  Vec3 a1, b1, c1, d1, a2, b2, c2, d2;
};
FiberSpline fiberSpline(const Vec3& x1, const Vec3& x, const Vec3& x2);

/// Arc length of the fiber, 3-point Gauss-Legendre per segment (B.4 with Gauss points in place of i/n);
/// `grad` (optional) receives d l / d(x1, x, x2) (B.6).
double fiberArcLength(const Vec3& x1, const Vec3& x, const Vec3& x2, std::array<Vec3, 3>* grad = nullptr);

/// The raw tangent angle of (B.9): arccos of the end tangents' cosine, unsigned.
double fiberTangentAngle(const Vec3& x1, const Vec3& x, const Vec3& x2);

/// Signed normal turning angle theta = asin(N . t0^) - asin(N . t1^) of the end tangents t0, t1 (B.9 with the
/// angle measured in the normal direction, so in-plane kinks of a fiber do not count and the sign follows
/// (7.10): positive when the fiber bends away from N). `grad` receives d theta / d(x1, x, x2) at fixed N,
/// `grad_normal` d theta / d N.
double fiberNormalAngle(const Vec3& x1, const Vec3& x, const Vec3& x2, const Vec3& normal,
                        std::array<Vec3, 3>* grad = nullptr, Vec3* grad_normal = nullptr);

/// Arc length (B.4) and signed normal angle (fiberNormalAngle) of one fiber in a single pass, from the edge
/// vectors e1 = x1 - x, e2 = x2 - x (both quantities are translation invariant). With `gradients`, also
/// d l / d(x1, x2), d theta / d(x1, x2) at fixed N (the derivatives for x are minus their sums) and
/// d theta / d N. Equals fiberArcLength and fiberNormalAngle up to round-off.
struct FiberMeasure {
  double length = 0.0, angle = 0.0;
  Vec3 grad_length[2], grad_angle[2], grad_normal;
};
void measureFiber(const Vec3& e1, const Vec3& e2, const Vec3& normal, bool gradients, FiberMeasure* out);
/// measureFiber for two fibers with the same normal at once (one per SIMD lane): e1[0..1], e2[0..1] in,
/// out[0..1] out; the same results as two measureFiber calls.
void measureFiberPair(const Vec3* e1, const Vec3* e2, const Vec3& normal, bool gradients, FiberMeasure* out);

}  // namespace rc
