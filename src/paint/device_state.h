// The pose and velocity of a haptic device's stylus (thesis 5.4.2), the check every incoming pose passes, and
// the backward-difference velocity the friction (5.7) needs when a device reports poses only.
#pragma once

#include <Eigen/Geometry>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// The stylus frame (= the brush frame of BrushPreset) in the device's base frame, with the velocity of its
/// origin and its angular velocity, both in the base frame.
struct DeviceState {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Vec3 linear_velocity = Vec3::Zero();   ///< [m/s]
  Vec3 angular_velocity = Vec3::Zero();  ///< [rad/s]
};

/// Why a device pose is refused (kNone: accepted).
enum class PoseProblem { kNone, kNonFinite, kNonUnitQuaternion };
const char* poseProblemName(PoseProblem problem);

/// A pose is accepted when every value is finite and | |q| - 1 | <= unit_tolerance.
PoseProblem checkDevicePose(const Vec3& position, const Eigen::Quaterniond& orientation,
                            double unit_tolerance = 1e-3);

/// Velocity of the stylus from its last two poses (backward difference over their time stamps).
class DeviceVelocityEstimator {
 public:
  /// Poses closer than `min_interval` seconds to the previous one keep the previous velocity.
  explicit DeviceVelocityEstimator(double min_interval = 1e-5) : min_interval_(min_interval) {}

  /// Adds the pose at time `t` [s] (normalised quaternion) and returns the state with its velocity.
  /// A time not after the previous one (a restarted stream) restarts the estimate at zero velocity.
  DeviceState update(double t, const Vec3& position, const Eigen::Quaterniond& orientation);
  void reset() { has_previous_ = false; }

 private:
  double min_interval_;
  bool has_previous_ = false;
  double t_prev_ = 0;
  Vec3 p_prev_ = Vec3::Zero();
  Eigen::Quaterniond q_prev_ = Eigen::Quaterniond::Identity();
  Vec3 v_ = Vec3::Zero(), w_ = Vec3::Zero();
};

}  // namespace rc
