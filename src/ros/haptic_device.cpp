#include "relaxed_connectivity/ros/haptic_device.h"

namespace rc {

void HeldPoseDevice::setPose(double stamp, const Vec3& position, const Eigen::Quaterniond& orientation) {
  std::lock_guard<std::mutex> lock(mutex_);
  state_ = velocity_.update(stamp, position, orientation.normalized());
  has_pose_ = true;
}

void HeldPoseDevice::setButtons(uint32_t buttons) {
  std::lock_guard<std::mutex> lock(mutex_);
  buttons_ = buttons;
}

bool HeldPoseDevice::sample(double, DeviceState& state, uint32_t& buttons) {
  std::lock_guard<std::mutex> lock(mutex_);
  state = state_;
  buttons = buttons_;
  return has_pose_;
}

}  // namespace rc
