// The brush skeleton of thesis 5.4: linear springs (5.1) between handle points, which follow the device
// rigidly, and active masses integrated with Verlet (or, as the fast setting, linearised backward Euler).
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/block_envelope_cholesky.h"
#include "relaxed_connectivity/paint/brush_preset.h"

namespace rc {

struct BrushSpring {
  int a, b;  ///< node indices (handle points first, then active masses)
  double rest_length;
  double stiffness;  ///< K_s [N/m]
  double damping;    ///< [N s/m]
};

/// Thrown when the skeleton blows up (non-finite or runaway positions): names the step and the cause.
class BrushInstability : public std::runtime_error {
 public:
  explicit BrushInstability(const std::string& message) : std::runtime_error(message) {}
};

/// Skeleton state. Node i < handleCount() is a handle point, the rest are active masses. Rest positions are
/// in the brush frame (see BrushPreset), current positions in the world frame.
class BrushSkeleton {
 public:
  explicit BrushSkeleton(const BrushPreset& preset);

  int handleCount() const { return handle_count_; }
  int nodeCount() const { return int(rest_.size()); }
  int activeCount() const { return nodeCount() - handle_count_; }
  bool isHandle(int node) const { return node < handle_count_; }
  const std::vector<Vec3>& restPositions() const { return rest_; }
  const std::vector<Vec3>& positions() const { return x_; }
  /// Node velocities over the last step (handles: the device's motion).
  const std::vector<Vec3>& velocities() const { return v_; }
  const std::vector<BrushSpring>& springs() const { return springs_; }
  /// Handle points in the brush frame (the contract with the haptic driver: handle point i of a preset).
  std::vector<Vec3> handleOffsets() const;
  const Eigen::Isometry3d& handlePose() const { return pose_; }

  /// Places the brush at `world_T_brush` in its rest shape, at rest (no velocity).
  void reset(const Eigen::Isometry3d& world_T_brush);
  /// One step of length dt with the preset's integrator: the handle points jump rigidly to `world_T_brush`
  /// (the caller interpolates the device pose over substeps), the active masses integrate spring (5.1),
  /// damping and gravity forces. Throws BrushInstability on non-finite or runaway positions (farther than 10
  /// bristle lengths from the handle), naming the step and the likely cause.
  void step(double dt, const Eigen::Isometry3d& world_T_brush);
  /// Overwrites the position of an active mass (collision projection (5.5)); its velocity keeps the
  /// tangential part and loses the part along `normal` that points into the surface.
  void projectActive(int node, const Vec3& position, const Vec3& normal);
  /// Contact planes the implicit integrator keeps active masses on within its steps: a stiff penalty along
  /// `normal` towards the plane through `point`, linearised in the solve, so that a long step lets a bristle
  /// slide along the surface instead of relaxing through it. Index = active mass; cleared by reset().
  /// Verlet ignores them (its steps are short; the caller projects).
  struct ContactPlane {
    bool active = false;
    Vec3 point = Vec3::Zero(), normal = Vec3::UnitZ();
  };
  void setContactPlanes(const std::vector<ContactPlane>& planes) { planes_ = planes; }
  /// Sum of the spring forces the active masses exert on the handle points [N], world frame.
  Vec3 bristleForce() const;
  /// Kinetic energy of the active masses [J].
  double kineticEnergy() const;

  /// Largest stable step of the explicit (Verlet) integration at the rest shape: 2 / omega_max with
  /// omega_max^2 the largest eigenvalue of M^-1 K (handle points fixed), reduced for the dashpots by the
  /// damped oscillator factor sqrt(1 + zeta^2) - zeta. Undamped it is sharp to 1 % (deformed springs stiffen
  /// a little); with dashpots it is conservative (blow-up measured from 1.10-1.24x it, test_brush_skeleton).
  double stepLimit() const;

 private:
  Vec3 springForce(const BrushSpring& s, const std::vector<Vec3>& x, const std::vector<Vec3>& v) const;
  void stepVerlet(double dt, const Eigen::Isometry3d& world_T_brush);
  void stepImplicitEuler(double dt, const Eigen::Isometry3d& world_T_brush);
  /// Throws BrushInstability if active mass `node` is not finite or ran away from the handle.
  void checkActive(int node, double dt, const Eigen::Isometry3d& world_T_brush) const;

  BrushPreset preset_;
  int handle_count_ = 0;
  double mass_ = 0;
  std::vector<Vec3> rest_;
  std::vector<BrushSpring> springs_;
  std::vector<Vec3> x_, x_prev_, v_;
  std::vector<Vec3> force_;  // scratch of step()
  std::vector<ContactPlane> planes_;
  // Scratch of stepImplicitEuler(): M - h C - h^2 K over the active masses in 3x3 blocks; its envelope: each
  // active mass's row starts at its lowest-numbered spring partner.
  BlockEnvelopeCholesky system_;
  std::vector<double> inverse_length_;  // per spring
  Eigen::VectorXd rhs_;
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
  double last_dt_ = 0;
  long steps_ = 0;
};

}  // namespace rc
