#include "relaxed_connectivity/scan/surfel_accumulator.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

SurfelAccumulator::SurfelAccumulator(double voxel_size, size_t max_surfels)
    : voxel_size_(voxel_size), max_surfels_(max_surfels) {
  if (!(voxel_size > 0) || !std::isfinite(voxel_size))
    throw std::invalid_argument("surfel accumulator: accumulation_voxel must be a positive number (got " +
                                std::to_string(voxel_size) + ")");
  if (max_surfels < 1) throw std::invalid_argument("surfel accumulator: max_accumulated_points must be >= 1");
}

size_t SurfelAccumulator::add(const SurfelCloud& view) {
  std::vector<size_t> fresh;
  std::vector<std::array<int64_t, 3>> fresh_keys;
  fresh.reserve(view.size());
  const double inv = 1.0 / voxel_size_;
  for (size_t i = 0; i < view.size(); ++i) {
    const Vec3& p = view.positions[i];
    if (!p.allFinite()) continue;
    const Vec3 c = (p * inv).array().floor();
    if (!(c.cwiseAbs().maxCoeff() < 4e18)) continue;  // outside 64-bit voxel indices
    const std::array<int64_t, 3> key = {int64_t(c[0]), int64_t(c[1]), int64_t(c[2])};
    if (cloud_.size() + fresh.size() >= max_surfels_) {
      if (!occupied_.count(key)) ++overflow_;
      continue;
    }
    if (occupied_.emplace(key, uint32_t(cloud_.size() + fresh.size())).second) {
      fresh.push_back(i);
      fresh_keys.push_back(key);
    }
  }
  if (fresh.empty()) return 0;
  SurfelCloud part = view;
  part.select(fresh);
  if (cloud_.empty()) {
    const std::string frame = cloud_.frame_id;
    cloud_ = std::move(part);
    if (!frame.empty()) cloud_.frame_id = frame;
  } else {
    try {
      cloud_.append(part);
    } catch (...) {
      for (const auto& key : fresh_keys) occupied_.erase(key);  // keep the state consistent
      throw;
    }
  }
  cloud_.width = cloud_.height = 0;
  cloud_.stamp_ns = view.stamp_ns;
  return fresh.size();
}

size_t SurfelAccumulator::reset() {
  const size_t dropped = cloud_.size();
  cloud_ = SurfelCloud();
  occupied_.clear();
  overflow_ = 0;
  return dropped;
}

}  // namespace rc
