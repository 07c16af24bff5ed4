// Accumulates surfels of many views into one cloud, keeping at most one surfel per voxel (the first that
// arrived) and at most a fixed number of surfels (ROS-free; owned by the surfel_estimator node).
#pragma once

#include <array>
#include <cstdint>
#include <unordered_map>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

class SurfelAccumulator {
 public:
  /// voxel_size > 0 (metres), max_surfels >= 1; throws std::invalid_argument naming the bad value.
  SurfelAccumulator(double voxel_size, size_t max_surfels);

  /// Adds every surfel of `view` whose voxel is still empty, until the cap is reached. Channels/attributes
  /// must agree with the surfels already accumulated (else std::invalid_argument). Returns the number added.
  size_t add(const SurfelCloud& view);
  /// Drops everything; returns how many surfels were dropped.
  size_t reset();

  const SurfelCloud& cloud() const { return cloud_; }
  size_t size() const { return cloud_.size(); }
  bool full() const { return cloud_.size() >= max_surfels_; }
  double voxelSize() const { return voxel_size_; }
  size_t maxSurfels() const { return max_surfels_; }
  /// Surfels not added because the cap was reached (since the last reset).
  size_t overflow() const { return overflow_; }

 private:
  struct VoxelHash {
    size_t operator()(const std::array<int64_t, 3>& v) const {
      return size_t(v[0] * 73856093LL) ^ size_t(v[1] * 19349663LL) ^ size_t(v[2] * 83492791LL);  // (3.17)
    }
  };
  double voxel_size_;
  size_t max_surfels_;
  size_t overflow_ = 0;
  SurfelCloud cloud_;
  std::unordered_map<std::array<int64_t, 3>, uint32_t, VoxelHash> occupied_;
};

}  // namespace rc
