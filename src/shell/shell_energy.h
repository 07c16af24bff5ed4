// Elastic energy of a point-sampled thin shell (thesis 7.2.1-7.2.2): membrane energy from fiber area
// estimates (7.5-7.7) and bending energy from calibrated fiber curvatures (7.9-7.11, B.9), with analytic
// gradients (7.14-7.17, B.5-B.12) and a stable explicit time step.
//
// Units and deviations from the thesis, chosen so that the discrete energy converges to a
// sampling-independent continuum energy:
//  * Each node's energy is an energy density times its rest area a_i^0 (tangent-plane Voronoi area,
//  ShellNodes),
//    so K_s is a 2D stretching modulus (energy / area) and K_b a bending modulus (energy).
//  * Membrane (7.7) uses relative area changes: U_s = K_s/2 [(A_i/A_i^0 - 1)^2 + sum_k w_k (A_k/A_k^0 -
//  1)^2],
//    A_k = pi/4 l_k^2 (7.5), A_i = sum_k w_k A_k (7.6). Uniform stretch by s stores K_s (s^2 - 1)^2 per area.
//  * Fiber curvature kappa_k = theta_k / (3/4 l_k): theta_k is the signed normal turning angle of the end
//    tangents (fiberNormalAngle); a natural spline through three points of a circle turns its end tangents by
//    3/4 of the true arc angle, hence the 3/4.
//  * Bending uses (7.3) with the Frobenius norm, U_b = K_b/2 |S - S^0|_F^2 = K_b/2 (dk1^2 + dk2^2), written
//    with the fiber curvature changes d_k as U_b = K_b/2 d^T Q_i d (shell_bending_form.h: the curvature
//    tensor fitted to the fibers' calibrated responses, exact for constant curvature also at open
//    boundaries; for isotropic fiber directions Q_i = 4 W - 2 w w^T, i.e. 4 sum_k w_k d_k^2 -
//    2 (sum_k w_k d_k)^2, sum_k w_k d_k the mean-curvature change of (7.9)). Unlike (7.8) it also resists
//    twist (saddle) modes, which have no mean-curvature change.
//  * Per-fiber stiffness factors (Fiber::stretch_scale, bend_scale; 7.3.4) scale each fiber's stretch term by
//    s_k and the node's area term by sum_k w_k s_k; bending uses sqrt(b_k) d_k in place of d_k. Nodes left
//    without fibers (cut off by cracks) store no energy.
#pragma once

#include <vector>

#include "relaxed_connectivity/shell/shell_bending_form.h"
#include "relaxed_connectivity/shell/shell_fibers.h"
#include "relaxed_connectivity/shell/shell_nodes.h"

namespace rc {

struct ShellMaterial {
  double stretch_stiffness = 25.0;  ///< K_s (energy / area)
  double bending_stiffness = 25.0;  ///< K_b (energy)
  double areal_density = 1.0;       ///< rho (mass / area); node mass m_i = rho a_i^0
  double damping = 0.0;             ///< D (1/s): damping force -D m_i v_i (7.18)
  /// Curvature components whose fiber response is below this are not fitted (shell_bending_form.h): lower
  /// fits more at open edges (0.05: twist there within 10 %) at a smaller stable step; 2 or more keeps the
  /// isotropic formula everywhere. bench_shell_bending_fit prints the trade.
  double bending_fit = 0.15;
};

struct ShellEnergyValue {
  double membrane = 0.0;
  double bending = 0.0;
  double total() const { return membrane + bending; }
};

/// Verlet stability limits 2 / omega_max, omega_max^2 bounded by Gershgorin row sums of M^-1 times the
/// Gauss-Newton Hessian of each energy (an upper bound, so the steps are safe).
struct ShellStableStep {
  double membrane = 0.0;
  double bending = 0.0;
  double combined = 0.0;  ///< 2 / sqrt(lambda_membrane + lambda_bending)
};

/// Energy over fixed nodes and fibers (both must outlive the object). evaluate() is not thread-safe (it uses
/// internal scratch); it parallelises internally and is deterministic for any thread count.
class ShellEnergy {
 public:
  static constexpr double kSplineAngleScale = kFiberSplineAngleScale;

  /// `previous`: forms of an earlier topology to copy where nodes kept their stencils (shell_bending_form.h).
  ShellEnergy(const ShellNodes& nodes, const ShellFibers& fibers, const ShellMaterial& material,
              const ShellBendingFormsReuse* previous = nullptr);

  /// Total energies at positions x; if `gradient` is given it receives dE/dx (size nodes).
  ShellEnergyValue evaluate(const std::vector<Vec3>& x, std::vector<Vec3>* gradient = nullptr) const;
  /// The same, and every fiber's current arc length and signed normal angle in `fiber_length` /
  /// `fiber_angle` (resized to the fiber count; as measureFibers gives them), measured in the same pass.
  ShellEnergyValue evaluate(const std::vector<Vec3>& x, std::vector<Vec3>* gradient,
                            std::vector<double>* fiber_length, std::vector<double>* fiber_angle) const;

  /// Per-node membrane and bending energies (either output may be null).
  void nodeEnergies(const std::vector<Vec3>& x, std::vector<double>* membrane,
                    std::vector<double>* bending) const;

  /// Mean curvature estimate H_i = sum_k w_k kappa_k (7.9) per node.
  std::vector<double> nodeMeanCurvature(const std::vector<Vec3>& x) const;

  /// Fiber curvature kappa_k = theta_k / (3/4 l_k) of every fiber (l_k the current arc length).
  std::vector<double> fiberCurvatures(const std::vector<Vec3>& x) const;

  ShellStableStep stableStep(const std::vector<Vec3>& x) const;

  const std::vector<double>& masses() const { return masses_; }
  const ShellNodes& nodes() const { return *nodes_; }
  const ShellFibers& fibers() const { return *fibers_; }
  const ShellMaterial& material() const { return material_; }
  /// Per-node bending forms (shell_bending_form.h), built from the rest state with the energy.
  const ShellBendingForms& bendingForms() const { return bending_forms_; }

 private:
  double evaluateNode(size_t i, const std::vector<Vec3>& x, Vec3* slots, double* membrane, double* bending,
                      double* fiber_length = nullptr, double* fiber_angle = nullptr) const;
  void gatherSlots(const std::vector<Vec3>& slot_values, std::vector<Vec3>& out) const;

  const ShellNodes* nodes_;
  const ShellFibers* fibers_;
  ShellMaterial material_;
  std::vector<double> masses_;
  ShellBendingForms bending_forms_;
  std::vector<size_t> slot_offsets_;  ///< node i owns slots [slot_offsets_[i], +1+k): itself, then neighbours
  std::vector<size_t> gather_offsets_;
  std::vector<size_t> gather_slots_;  ///< slots referring to node p, in ascending owner order
  mutable std::vector<Vec3> slot_values_;
  mutable std::vector<double> node_membrane_, node_bending_;  ///< evaluate() scratch
};

}  // namespace rc
