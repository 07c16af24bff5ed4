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

/// Velocity of the stylus by a backward difference between the newest pose and the newest earlier one at
/// least `baseline` seconds older (the oldest kept one while there is none). A baseline spanning several
/// poses keeps the velocity accurate when poses come irregularly: stamps rounded to 1 ns over a 2 ms baseline
/// give a relative error of at most 1e-6, over two poses 50 us apart it would be 4e-5.
class DeviceVelocityEstimator {
 public:
  explicit DeviceVelocityEstimator(double baseline = 2e-3) : baseline_(baseline) {}

  /// Adds the pose at time `t` [s] (normalised quaternion) and returns the state with its velocity.
  /// A time not after the previous one (a restarted stream) restarts the estimate at zero velocity.
  DeviceState update(double t, const Vec3& position, const Eigen::Quaterniond& orientation);
  void reset() { count_ = 0; }

 private:
  struct Stamped {
    double t = 0;
    Vec3 position = Vec3::Zero();
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  };
  static constexpr int kKept = 32;  // poses kept: the baseline at up to 16 kHz

  double baseline_;
  Stamped kept_[kKept];
  int newest_ = -1, count_ = 0;
};

}  // namespace rc
