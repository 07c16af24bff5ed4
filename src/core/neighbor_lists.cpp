#include "relaxed_connectivity/core/neighbor_lists.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace rc {

void NeighborLists::build(const std::vector<Vec3>& points, double radius, const Options& options) {
  if (!(radius >= 0.0) || !std::isfinite(radius))
    throw std::invalid_argument("NeighborLists::build: radius must be finite and >= 0, got " +
                                std::to_string(radius));
  const size_t n = points.size();
  if (n >= std::numeric_limits<uint32_t>::max())
    throw std::length_error("NeighborLists::build: too many points (" + std::to_string(n) + ")");
  num_points_ = n;
  radius_ = radius;
  sq_radius_ = radius * radius;
  offsets_.assign(n + 1, 0);
  if (!options.store_sq_dists) sq_dists_.clear();
  if (n == 0) return;
  const int num_threads = options.num_threads > 0 ? options.num_threads : omp_get_max_threads();

  // Points sorted by cells at least h wide (all neighbours of a point lie in the 27 cells around its own).
  grid_.build(points, radius, num_threads, "NeighborLists::build");
  const std::vector<uint32_t>& order = grid_.order();
  sorted_.resize(n);
  for (size_t s = 0; s < n; ++s) {
    const Vec3& p = points[order[s]];
    sorted_[s] = {p.x(), p.y(), p.z(), order[s]};
  }

  // Lists in sorted order, one contiguous chunk of points per thread.
  row_count_.resize(n);
  if (threads_.size() < size_t(num_threads)) threads_.resize(num_threads);
  thread_first_.assign(num_threads + 1, 0);
  for (int t = 0; t <= num_threads; ++t) thread_first_[t] = n * t / num_threads;
#pragma omp parallel num_threads(num_threads)
  {
    const int t = omp_get_thread_num();
    if (options.store_sq_dists)
      scanChunk<true>(thread_first_[t], thread_first_[t + 1], threads_[t]);
    else
      scanChunk<false>(thread_first_[t], thread_first_[t + 1], threads_[t]);
  }

  // Offsets in original order, then every thread copies its rows to their final place.
  size_t total = 0;
  for (int t = 0; t < num_threads; ++t) total += threads_[t].used;
  if (total > std::numeric_limits<uint32_t>::max())
    throw std::length_error("NeighborLists::build: " + std::to_string(total) +
                            " entries exceed the 32-bit offsets; lower the radius");
  for (size_t s = 0; s < n; ++s) offsets_[sorted_[s].id + 1] = row_count_[s];
  for (size_t i = 0; i < n; ++i) offsets_[i + 1] += offsets_[i];
  if (indices_.size() < total) indices_.resize(total);
  if (options.store_sq_dists && sq_dists_.size() < total) sq_dists_.resize(total);
#pragma omp parallel num_threads(num_threads)
  {
    const int t = omp_get_thread_num();
    const ThreadBuffer& buffer = threads_[t];
    size_t local = 0;
    for (size_t s = thread_first_[t]; s < thread_first_[t + 1]; ++s) {
      const size_t dst = offsets_[sorted_[s].id], len = row_count_[s];
      if (len == 0) continue;  // (memcpy from an empty buffer's null data is undefined: UBSan)
      std::memcpy(indices_.data() + dst, buffer.indices.data() + local, len * sizeof(uint32_t));
      if (options.store_sq_dists)
        std::memcpy(sq_dists_.data() + dst, buffer.sq_dists.data() + local, len * sizeof(double));
      local += len;
    }
  }
}

template <bool kStoreDists>
void NeighborLists::scanChunk(size_t first, size_t last, ThreadBuffer& buffer) {
  buffer.used = 0;
  if (kStoreDists && buffer.sq_dists.size() < buffer.indices.size())
    buffer.sq_dists.resize(buffer.indices.size());
  const double r2 = sq_radius_;
  const SortedPoint* pts = sorted_.data();
  SortedCellGrid::Run runs[9];
  int num_runs = 0;
  size_t candidates = 0;
  uint32_t current_cell = std::numeric_limits<uint32_t>::max();
  for (size_t s = first; s < last; ++s) {
    const uint32_t c = grid_.cellOfSorted(s);
    if (c != current_cell) {  // the 27 cells around c as up to 9 runs of 3 consecutive cells along x
      current_cell = c;
      num_runs = grid_.neighborRuns(c, runs);
      candidates = 0;
      for (int r = 0; r < num_runs; ++r) candidates += runs[r].end - runs[r].begin;
    }
    // Room for every candidate, so the loop below appends without branching on the distance test.
    if (buffer.used + candidates > buffer.indices.size()) {
      const size_t grown = std::max(2 * buffer.indices.size(), buffer.used + candidates + 1024);
      buffer.indices.resize(grown);
      if (kStoreDists) buffer.sq_dists.resize(grown);
    }
    uint32_t* out_idx = buffer.indices.data() + buffer.used;
    double* out_dist = kStoreDists ? buffer.sq_dists.data() + buffer.used : nullptr;
    const double px = pts[s].x, py = pts[s].y, pz = pts[s].z;
    size_t found = 0;
    for (int r = 0; r < num_runs; ++r) {
      for (uint32_t j = runs[r].begin; j < runs[r].end; ++j) {
        const double dx = pts[j].x - px, dy = pts[j].y - py, dz = pts[j].z - pz;
        const double d2 = dx * dx + dy * dy + dz * dz;
        out_idx[found] = pts[j].id;
        if (kStoreDists) out_dist[found] = d2;
        found += (d2 <= r2) & (j != s);
      }
    }
    row_count_[s] = static_cast<uint32_t>(found);
    buffer.used += found;
  }
}

template void NeighborLists::scanChunk<true>(size_t, size_t, ThreadBuffer&);
template void NeighborLists::scanChunk<false>(size_t, size_t, ThreadBuffer&);

}  // namespace rc
