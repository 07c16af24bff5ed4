#include "relaxed_connectivity/ros/replay_haptic_device.h"

namespace rc {

ReplayHapticDevice::ReplayHapticDevice(const std::string& stroke_path, bool real_time)
    : sampler_(readStrokeFile(stroke_path)), real_time_(real_time) {}

bool ReplayHapticDevice::sample(double t, DeviceState& state, uint32_t& buttons) {
  const StrokeSample s = sampler_.at(sampler_.startTime() + t);
  state = velocity_.update(t, s.position, s.orientation);
  buttons = s.buttons;
  return true;
}

}  // namespace rc
