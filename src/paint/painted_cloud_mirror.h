// A viewer's copy of the paint model's active surfels (thesis 5.3), kept up to date from the full cloud and
// the deltas the paint model publishes (surfels/painted, surfels/painted_delta): the surfels are grouped by
// their `father` (the original they belong to), and a delta replaces the whole group of each listed original.
// Applying a delta reports the surfels that went and came, exactly as they were and are, which is what a
// differential renderer (5.7) un-splats and splats. Only the channels a renderer needs are kept: positions,
// normals, radii, colours and the reflectivity (kReflectivityAttribute) where the full cloud has it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

class PaintedCloudMirror {
 public:
  /// Replaces the state by a whole cloud with normals, radii and the uint32 column `father` (colours
  /// optional). Throws std::invalid_argument naming the missing channel; the state is then unchanged.
  void reset(const SurfelCloud& cloud);
  /// Replaces the surfels of each of `originals` by those of `surfels` (each with a `father` among
  /// `originals`, the same channels as the state). Appends the surfels taken out to `removed` and the new
  /// ones to `added` (either may be null). Throws std::invalid_argument naming the bad surfel or channel;
  /// the state is then unchanged.
  void applyDelta(const std::vector<uint32_t>& originals, const SurfelCloud& surfels, SurfelCloud* removed,
                  SurfelCloud* added);
  void clear();

  /// The surfels, in no particular order (a delta moves surfels around).
  const SurfelCloud& cloud() const { return cloud_; }
  size_t size() const { return cloud_.size(); }
  /// The surfels of one original (indices into cloud()).
  const std::vector<uint32_t>& surfelsOf(uint32_t original) const;

 private:
  /// The render channels of `from`, checked; the fathers into *fathers.
  static SurfelCloud renderChannels(const SurfelCloud& from, const char* what,
                                    std::vector<uint32_t>* fathers);
  void push(const SurfelCloud& from, size_t i, uint32_t father);
  void removeAt(uint32_t index);

  SurfelCloud cloud_;
  bool colors_ = false;                         ///< the surfels have colours
  std::vector<uint32_t> father_;                ///< per surfel
  std::vector<uint32_t> slot_;                  ///< per surfel: its place in members_[father]
  std::vector<std::vector<uint32_t>> members_;  ///< per original: its surfels
};

}  // namespace rc
