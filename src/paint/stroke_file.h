// Recorded strokes of a haptic device (config/paint/strokes/*.csv), the input of the haptic_driver's replay
// device. Format: CSV, '#' starts a comment line, blank lines are skipped, the first other line is the header
//   t,x,y,z,qx,qy,qz,qw,buttons
// then one sample per line: time [s] (strictly increasing), stylus position [m] and orientation (unit
// quaternion, |q| within 1e-3 of 1; normalised on reading) in the device base frame, and the button bitmask
// (bit i: button i held; bit 0 paints).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

struct StrokeSample {
  double t = 0;
  Vec3 position = Vec3::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  uint32_t buttons = 0;
  /// The stylus pose as a transform (device base <- stylus).
  Eigen::Isometry3d pose() const {
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    p.linear() = orientation.toRotationMatrix();
    p.translation() = position;
    return p;
  }
};

class StrokeFileError : public std::runtime_error {
 public:
  explicit StrokeFileError(const std::string& message) : std::runtime_error(message) {}
};

/// Throws StrokeFileError "<file>:<line>: <problem>" (wrong column count, not a number, NaN, time not
/// increasing, non-unit quaternion, bad bitmask, missing header, no samples).
std::vector<StrokeSample> readStrokeFile(const std::string& path);
/// The same from text; `source_name` names it in errors.
std::vector<StrokeSample> parseStroke(const std::string& text, const std::string& source_name);
/// Writes the header, an optional comment (each line prefixed with '#') and the samples with 17 significant
/// digits (reading gives the same doubles back). Throws StrokeFileError when the file cannot be written.
void writeStrokeFile(const std::string& path, const std::vector<StrokeSample>& samples,
                     const std::string& comment = "");
std::string formatStroke(const std::vector<StrokeSample>& samples, const std::string& comment = "");

/// Deterministic sampling of a stroke at any time: position linear and orientation slerp between the
/// neighbouring samples, the buttons of the last sample at or before t; clamped to the first / last sample.
class StrokeSampler {
 public:
  explicit StrokeSampler(std::vector<StrokeSample> samples);  ///< at least one sample, times increasing
  StrokeSample at(double t) const;
  double duration() const { return samples_.back().t - samples_.front().t; }
  double startTime() const { return samples_.front().t; }
  const std::vector<StrokeSample>& samples() const { return samples_; }

 private:
  std::vector<StrokeSample> samples_;
};

}  // namespace rc
