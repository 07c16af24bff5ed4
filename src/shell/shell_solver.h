// Explicit dynamics of a point-sampled thin shell (thesis 7.2.2): velocity Verlet on (7.18) with damping,
// gravity, pinned nodes and a ground-plane collider, a stable step from the stiffest fibers, and instability
// detection.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/shell/shell_energy.h"
#include "relaxed_connectivity/shell/shell_fibers.h"
#include "relaxed_connectivity/shell/shell_nodes.h"

namespace rc {

struct ShellSolverOptions {
  /// Fixed time step; 0 uses step_safety times the stable step (ShellEnergy::stableStep), recomputed every
  /// step_update_interval steps.
  double time_step = 0.0;
  double step_safety = 0.9;
  int step_update_interval = 1;
  Vec3 gravity = Vec3::Zero();
  bool ground = false;  ///< plane through ground_point with normal ground_normal; nodes stay above it
  Vec3 ground_point = Vec3::Zero();
  Vec3 ground_normal = Vec3::UnitZ();
  double ground_restitution = 0.0;  ///< normal velocity after contact = -restitution * before
  double ground_friction = 0.0;     ///< fraction of tangential velocity removed on contact, in [0, 1]
  /// Instability: kinetic + elastic energy above blowup_factor times the energy available since the start
  /// (initial kinetic + elastic energy + gravity work).
  double blowup_factor = 10.0;
};

struct ShellStepReport {
  size_t step = 0;  ///< 1-based index of the step just taken
  double time = 0.0;
  double dt = 0.0;
  ShellStableStep stable;  ///< stable limits at the start of the step
  ShellEnergyValue elastic;
  double kinetic = 0.0;
  double gravity_potential = 0.0;  ///< -sum m g . x
  double external_work = 0.0;      ///< work done by the external force since the start (trapezoidal)
};

/// Extra force on the nodes at positions x (e.g. balloon pressure): fills `force` (size of x).
using ShellExternalForce = std::function<void(const std::vector<Vec3>& x, std::vector<Vec3>& force)>;

/// Thrown when a step produces non-finite values or the energy blows up; names the step and the cause.
class ShellInstabilityError : public std::runtime_error {
 public:
  ShellInstabilityError(size_t step, const std::string& cause)
      : std::runtime_error("shell simulation unstable at step " + std::to_string(step) + ": " + cause),
        step_(step),
        cause_(cause) {}
  size_t step() const { return step_; }
  const std::string& cause() const { return cause_; }

 private:
  size_t step_;
  std::string cause_;
};

class ShellSolver {
 public:
  /// Builds the fibers of `nodes`; positions start at rest, velocities at zero.
  ShellSolver(ShellNodes nodes, const ShellMaterial& material, const ShellSolverOptions& options);

  void pin(size_t node);
  /// Holds the components of `node` whose bits are set in `mask` (bit d: component d; 7 = pin): their
  /// velocity stays 0 and their position where it is (a roller or a symmetry plane holds one).
  void hold(size_t node, uint8_t mask);
  /// The held components of every node (bit mask; pinned nodes 7).
  const std::vector<uint8_t>& heldMask() const { return held_; }
  /// Pins `node` and moves it with this velocity during the drift of every step (a pulled edge, 7.3.2
  /// experiments). The work the moving pins do on the shell counts as available energy (trapezoidal).
  void setPinVelocity(size_t node, const Vec3& velocity);
  bool pinned(size_t node) const { return held_.at(node) == 7; }
  void setPositions(const std::vector<Vec3>& x);
  void setVelocities(const std::vector<Vec3>& v);
  /// Adds a position-dependent external force (evaluated after every drift); its work is counted as
  /// available energy by the instability check. An empty function removes it.
  void setExternalForce(ShellExternalForce force);

  /// Rest state of the fibers, for material models (plasticity, 7.3.1) that change rest lengths and angles;
  /// call refreshForces() after changing it.
  ShellFibers& mutableFibers() { return fibers_; }
  /// Recomputes elastic energy and forces at the current positions (after the rest state changed).
  void refreshForces();
  /// Replaces neighbourhoods and fibers (fracture, 7.3.2); node count, rest positions and areas must be
  /// unchanged. Positions, velocities and pins are kept; an energy increase counts as available energy.
  void setTopology(ShellNodes nodes, ShellFibers fibers);

  /// One velocity Verlet step; throws ShellInstabilityError.
  ShellStepReport step();

  const std::vector<Vec3>& positions() const { return x_; }
  const std::vector<Vec3>& velocities() const { return v_; }
  const ShellNodes& nodes() const { return nodes_; }
  const ShellFibers& fibers() const { return fibers_; }
  const ShellEnergy& energy() const { return energy_; }
  /// dE/dx at positions() (the elastic forces are its negative), as the last force evaluation left it.
  const std::vector<Vec3>& elasticGradient() const { return gradient_; }
  /// E of the last force evaluation (at positions(), but for nodes the ground projected after it).
  const ShellEnergyValue& elasticEnergy() const { return elastic_; }
  const Vec3& gravity() const { return options_.gravity; }
  /// Arc length and signed normal angle of every fiber at positions() (as measureFibers), measured with the
  /// forces; valid after construction, every step and every change of positions, rest state or topology.
  const std::vector<double>& fiberLengths() const { return fiber_length_; }
  const std::vector<double>& fiberAngles() const { return fiber_angle_; }
  double time() const { return time_; }
  size_t stepCount() const { return step_count_; }

 private:
  void applyGround();
  double kineticEnergy() const;
  double gravityPotential() const;
  void resetReference();
  void evaluateForces();

  ShellNodes nodes_;
  ShellFibers fibers_;
  ShellEnergy energy_;
  ShellSolverOptions options_;
  std::vector<Vec3> x_, v_, gradient_, external_, external_next_, x_before_;
  ShellExternalForce external_force_;
  double external_work_ = 0.0;
  std::vector<double> fiber_length_, fiber_angle_;
  std::vector<uint8_t> held_;                         ///< per node: bit d = component d held (7: pinned)
  bool partly_held_ = false;                          ///< some node holds only some components
  std::vector<std::pair<size_t, Vec3>> moving_pins_;  ///< node, velocity
  std::vector<Vec3> pin_force_before_;                ///< gradient at the moving pins before the drift
  double pin_work_ = 0.0;
  ShellEnergyValue elastic_;
  ShellStableStep stable_;
  size_t step_count_ = 0;
  double time_ = 0.0;
  double reference_energy_ = 0.0, reference_gravity_ = 0.0, energy_floor_ = 0.0;
};

}  // namespace rc
