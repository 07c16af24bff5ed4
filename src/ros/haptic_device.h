// The device side of the haptic_driver (thesis 5.4.2): where the stylus pose comes from and where the force
// goes. One interface, three backends chosen by ~device: replay (a stroke file), marker (an rviz interactive
// marker), topic (<device>/pose from a real device driver or a bag). sample() and command() run in the 1 kHz
// force loop: no allocation, no blocking beyond a short mutex.
#pragma once

#include <cstdint>
#include <mutex>

#include "relaxed_connectivity/paint/device_state.h"
#include "relaxed_connectivity/paint/force_low_pass.h"

namespace rc {

class HapticDevice {
 public:
  virtual ~HapticDevice() = default;
  /// The device at loop time t [s]: false while it has no pose yet.
  virtual bool sample(double t, DeviceState& state, uint32_t& buttons) = 0;
  /// The filtered force [N] and torque [N m] of this tick, in the pose frame (a hardware backend sends it).
  virtual void command(const Wrench& /*wrench*/) {}
  /// Whether the driver publishes the sampled pose and buttons on <device>/pose and <device>/button (the
  /// simulated devices) or somebody else does (a real driver, a bag).
  virtual bool publishesPose() const = 0;
  /// false: the loop runs as fast as possible on virtual time (tick / rate).
  virtual bool paced() const { return true; }
  /// true once there is nothing more to play (the loop then stops).
  virtual bool finished(double /*t*/) const { return false; }
};

/// Holds the latest pose handed in from outside (setPose, from a ROS callback) with its backward-difference
/// velocity; the `topic` backend, and the base of the `marker` one.
class HeldPoseDevice : public HapticDevice {
 public:
  /// `stamp` [s]: the pose's time (header stamp), used for the velocity only. The pose must have passed
  /// checkDevicePose; the quaternion is normalised here.
  void setPose(double stamp, const Vec3& position, const Eigen::Quaterniond& orientation);
  void setButtons(uint32_t buttons);
  bool sample(double t, DeviceState& state, uint32_t& buttons) override;
  bool publishesPose() const override { return false; }

 private:
  std::mutex mutex_;
  DeviceVelocityEstimator velocity_;
  DeviceState state_;
  uint32_t buttons_ = 0;
  bool has_pose_ = false;
};

}  // namespace rc
