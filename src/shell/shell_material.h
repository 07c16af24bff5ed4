// Material behaviour of point-sampled thin shells (thesis 7.3): plasticity with yield and creep (7.19-7.23),
// fracture by stretch or bending thresholds with crack planes and visibility-based re-neighbouring (7.24,
// 7.3.2), weakening under repeated plastic bending (7.25), per-fiber anisotropic / inhomogeneous stiffness
// (7.3.4), and inflation pressure for closed balloons.
//
// Departures from the thesis:
//  * The stretch yield (7.20) and fracture (7.24) thresholds are strains, |l - l^0| > beta_s l_orig and
//    l / l^0 - 1 > gamma_s, so they do not depend on the node spacing (F.1 lists gamma_s = 0.02, 0.04, which
//    only make sense as strains). Bending thresholds are angles in radians, as printed.
//  * Fibers that a crack makes new get their rest state from the rest positions (as in the thesis), their
//    thresholds from the weakest old fiber of the same node, and no plastic history.
//  * A node hosts at most one crack: overloaded fibers of a node that already has one do not start another
//    (two crossing discs through one node would cut it off from everything); the crack grows at the nodes
//    around it instead.
//  * Short fibers: re-neighbouring after a crack drops new fibers shorter than min_fiber_length (a fraction
//    of the node spacing) before weighting (clamp, not an adaptive step): the bending stiffness of a fiber
//    grows as 1/l^4, so one very short fiber would otherwise collapse the stable step.
#pragma once

#include <functional>
#include <limits>
#include <set>
#include <utility>
#include <vector>

#include "relaxed_connectivity/shell/shell_crack.h"
#include "relaxed_connectivity/shell/shell_fibers.h"
#include "relaxed_connectivity/shell/shell_nodes.h"
#include "relaxed_connectivity/shell/shell_solver.h"

namespace rc {

struct ShellPlasticity {
  double stretch_yield = std::numeric_limits<double>::infinity();  ///< beta_s (7.20), strain
  double bend_yield = std::numeric_limits<double>::infinity();     ///< beta_b (7.21), radians
  double stretch_creep = 0.0;                                      ///< alpha_s (7.22), 1/s
  double bend_creep = 0.0;                                         ///< alpha_b (7.23), 1/s
  double weakening = 0.0;  ///< chi (7.25): gamma_b -= chi gamma_b |d theta_plastic| per step
};

struct ShellFracture {
  double stretch_threshold = std::numeric_limits<double>::infinity();  ///< gamma_s (7.24), strain l/l0 - 1
  double bend_threshold = std::numeric_limits<double>::infinity();     ///< gamma_b (7.24), radians
  size_t max_cracks_per_step =
      1;  ///< most-overloaded fibers first, at least a crack radius apart, one per node
  double min_fiber_length = 0.5;  ///< new fibers shorter than this times the node spacing are dropped
  /// Crack speed limit (rest-length units per second): a crack is not placed within two crack radii of a
  /// crack made less than (distance / max_crack_speed) earlier, so a tear grows no faster than this (a real
  /// crack front stays below the Rayleigh wave speed, here about sqrt(K_s / rho)). Infinity: one crack per
  /// tip and step, however short the step. Cracks away from all recent ones (new initiations) are not
  /// limited.
  double max_crack_speed = std::numeric_limits<double>::infinity();
};

struct ShellMaterialOptions {
  ShellPlasticity plasticity;
  ShellFracture fracture;
};

/// Per-fiber material state, parallel to ShellFibers::fibers. Fiber::rest_length / rest_angle hold
/// l^0 = l_orig + l_plastic and theta^0 = theta_orig + theta_plastic (7.19).
struct FiberMaterialState {
  double original_length = 0.0;     ///< l_orig
  double original_angle = 0.0;      ///< theta_orig
  double stretch_threshold = 0.0;   ///< gamma_s of this fiber
  double bend_threshold = 0.0;      ///< gamma_b of this fiber (lowered by 7.25)
  double plastic_bend_total = 0.0;  ///< sum over steps of |d theta_plastic|
};

struct ShellMaterialReport {
  size_t stretch_yielding = 0;  ///< fibers whose rest length crept this step
  size_t bend_yielding = 0;     ///< fibers whose rest angle crept this step
  size_t new_cracks = 0;
  size_t recomputed_nodes = 0;  ///< neighbourhoods recomputed for the new cracks
  long fiber_delta = 0;         ///< fibers after minus fibers before re-neighbouring
};

/// Stiffness factors (stretch_scale, bend_scale) of a fiber from its centre's rest position and its unit rest
/// direction (end1 -> end2).
using FiberStiffnessField =
    std::function<std::pair<double, double>(const Vec3& center, const Vec3& direction)>;

/// Sets Fiber::stretch_scale / bend_scale of every fiber from `field` (7.3.4). Throws std::invalid_argument
/// for a negative or non-finite factor.
void setFiberStiffness(const ShellNodes& nodes, ShellFibers& fibers, const FiberStiffnessField& field);

/// Current arc length and signed normal angle (with the current fan normal) of every fiber.
void measureFibers(const ShellNodes& nodes, const ShellFibers& fibers, const std::vector<Vec3>& x,
                   std::vector<double>* length, std::vector<double>* angle);

/// Inflation pressure p of a closed balloon (rest normals outward): force p a_i n_i on node i, with n_i the
/// fan normal and a_i = a_i^0 A_i / A_i^0 the current area from the fibers (7.5, 7.6). Nodes and fibers must
/// outlive the returned function (ShellSolver's own: solver.nodes(), solver.fibers()).
ShellExternalForce balloonPressure(const ShellNodes& nodes, const ShellFibers& fibers, double pressure);

/// Enclosed volume 1/3 sum_i a_i n_i . x_i with a_i and n_i as in balloonPressure.
double balloonVolume(const ShellNodes& nodes, const ShellFibers& fibers, const std::vector<Vec3>& x);

/// Plasticity, weakening and fracture of one shell. Call update() after every solver step.
class ShellMaterialModel {
 public:
  /// Takes l_orig, theta_orig from the fibers' current rest state and the thresholds from `options`.
  ShellMaterialModel(const ShellNodes& nodes, const ShellFibers& fibers, const ShellMaterialOptions& options);

  /// Re-applied to the fibers that fracture creates (set it on the solver's fibers too).
  void setStiffnessField(FiberStiffnessField field) { stiffness_field_ = std::move(field); }

  /// Plasticity (7.20-7.23) and weakening (7.25) of the fibers at positions x over time dt; changes their
  /// rest state. Throws std::invalid_argument if alpha dt > 1 (the creep would overshoot).
  ShellMaterialReport updatePlasticity(const ShellNodes& nodes, ShellFibers& fibers,
                                       const std::vector<Vec3>& x, double dt);

  /// Fracture test (7.24) at positions x and simulation time `time`: adds crack planes for the most
  /// overloaded fibers, recomputes the neighbourhoods under the visibility rule and rebuilds the fibers of
  /// the recomputed nodes.
  ShellMaterialReport updateFracture(ShellNodes& nodes, ShellFibers& fibers, const std::vector<Vec3>& x,
                                     double time = 0.0);

  /// Both on a solver after its step of length dt (fracture replaces the solver's topology).
  ShellMaterialReport update(ShellSolver& solver, double dt);

  std::vector<FiberMaterialState>& states() { return states_; }
  const std::vector<FiberMaterialState>& states() const { return states_; }
  const std::vector<ShellCrack>& cracks() const { return cracks_; }
  const ShellMaterialOptions& options() const { return options_; }

 private:
  ShellMaterialReport applyPlasticity(ShellFibers& fibers, const std::vector<double>& length,
                                      const std::vector<double>& angle, double dt);
  bool anyOverloaded(const ShellFibers& fibers, const std::vector<double>& length,
                     const std::vector<double>& angle) const;
  /// Appends the cracks of the most overloaded fibers (7.24) made at `time` to cracks_; returns how many.
  size_t selectCracks(const ShellNodes& nodes, const ShellFibers& fibers, const std::vector<double>& length,
                      const std::vector<double>& angle, double time);
  /// False if `crack` lies within two crack radii of a crack too young for max_crack_speed at `time`.
  bool withinCrackSpeed(const ShellCrack& crack, double time) const;
  /// Re-neighbouring and fiber rebuild for cracks_[first_new ..] (fills recomputed_nodes, fiber_delta).
  void rebuildAfterCracks(ShellNodes& nodes, ShellFibers& fibers, size_t first_new, ShellMaterialReport* out);

  ShellMaterialOptions options_;
  std::vector<FiberMaterialState> states_;
  std::vector<ShellCrack> cracks_;
  std::set<uint32_t> crack_nodes_;
  FiberStiffnessField stiffness_field_;
  size_t neighbor_count_ = 8;
  std::vector<double> length_, angle_;
};

}  // namespace rc
