// The `replay` backend of the haptic_driver: a recorded stroke (src/paint/stroke_file.h) played from loop
// time 0, at real time or as fast as possible (virtual time), deterministic: the pose at tick k depends on k
// only when unpaced, on the loop time only when paced.
#pragma once

#include <string>

#include "relaxed_connectivity/paint/stroke_file.h"
#include "relaxed_connectivity/ros/haptic_device.h"

namespace rc {

class ReplayHapticDevice : public HapticDevice {
 public:
  /// Reads the stroke file (throws StrokeFileError naming file:line).
  ReplayHapticDevice(const std::string& stroke_path, bool real_time);

  bool sample(double t, DeviceState& state, uint32_t& buttons) override;
  bool publishesPose() const override { return true; }
  bool paced() const override { return real_time_; }
  /// Unpaced replays end after the last sample; paced ones hold the last pose.
  bool finished(double t) const override { return !real_time_ && t > sampler_.duration(); }
  double duration() const { return sampler_.duration(); }

 private:
  StrokeSampler sampler_;
  bool real_time_;
  DeviceVelocityEstimator velocity_;
};

}  // namespace rc
