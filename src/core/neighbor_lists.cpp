#include "core/neighbor_lists.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace rc {

namespace {
constexpr size_t kMaxCells = size_t(1) << 31;
}

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

  // Bounding box and grid. Cells are at least h wide (plus a rounding slack), so all neighbours of a point
  // lie in the 27 cells around its own; the grid is coarsened if it would have too many cells.
  Vec3 lo = points[0], hi = points[0];
  for (size_t i = 0; i < n; ++i) {
    const Vec3& p = points[i];
    if (!p.allFinite())
      throw std::invalid_argument("NeighborLists::build: point " + std::to_string(i) + " is not finite");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 extent = hi - lo;
  const double max_abs = std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
  double cell = radius * (1.0 + 1e-12) + 16.0 * std::numeric_limits<double>::epsilon() * max_abs;
  if (!(cell > 0.0)) cell = std::max(extent.maxCoeff(), 1.0);
  const size_t max_cells = std::min(kMaxCells, std::max<size_t>(8 * n, 4096));
  for (;;) {
    double total = 1.0;
    for (int a = 0; a < 3; ++a) total *= std::floor(extent[a] / cell) + 1.0;
    if (total <= double(max_cells)) break;
    cell *= 1.25;
  }
  inv_cell_ = 1.0 / cell;
  size_t num_cells = 1;
  for (int a = 0; a < 3; ++a) {
    origin_[a] = lo[a];
    dims_[a] = static_cast<size_t>(std::floor(extent[a] * inv_cell_)) + 1;
    num_cells *= dims_[a];
  }

  // Counting sort by cell (linear order, x fastest).
  cell_of_point_.resize(n);
  auto clampCell = [](double s, size_t dim) {
    return static_cast<size_t>(std::min(std::max(s, 0.0), double(dim - 1)));
  };
#pragma omp parallel for num_threads(num_threads) schedule(static)
  for (long i = 0; i < static_cast<long>(n); ++i) {
    const Vec3& p = points[i];
    const size_t cx = clampCell((p.x() - origin_[0]) * inv_cell_, dims_[0]);
    const size_t cy = clampCell((p.y() - origin_[1]) * inv_cell_, dims_[1]);
    const size_t cz = clampCell((p.z() - origin_[2]) * inv_cell_, dims_[2]);
    cell_of_point_[i] = static_cast<uint32_t>(cx + dims_[0] * (cy + dims_[1] * cz));
  }
  cell_start_.assign(num_cells + 1, 0);
  for (size_t i = 0; i < n; ++i) ++cell_start_[cell_of_point_[i] + 1];
  for (size_t c = 0; c < num_cells; ++c) cell_start_[c + 1] += cell_start_[c];
  sorted_.resize(n);
  sorted_cell_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t c = cell_of_point_[i];
    const uint32_t s = cell_start_[c]++;
    sorted_[s] = {points[i].x(), points[i].y(), points[i].z(), static_cast<uint32_t>(i)};
    sorted_cell_[s] = c;
  }
  std::memmove(cell_start_.data() + 1, cell_start_.data(), num_cells * sizeof(uint32_t));
  cell_start_[0] = 0;

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
  const size_t nx = dims_[0], ny = dims_[1], nz = dims_[2];
  const double r2 = sq_radius_;
  const SortedPoint* pts = sorted_.data();
  const uint32_t* starts = cell_start_.data();
  uint32_t run_begin[9], run_end[9];
  int num_runs = 0;
  size_t candidates = 0;
  uint32_t current_cell = std::numeric_limits<uint32_t>::max();
  for (size_t s = first; s < last; ++s) {
    const uint32_t c = sorted_cell_[s];
    if (c != current_cell) {
      // The 27 cells around c as up to 9 runs of 3 consecutive cells along x.
      current_cell = c;
      const size_t cx = c % nx, cy = (c / nx) % ny, cz = c / (nx * ny);
      const size_t x0 = cx > 0 ? cx - 1 : 0, x1 = std::min(cx + 1, nx - 1);
      num_runs = 0;
      candidates = 0;
      for (size_t z = (cz > 0 ? cz - 1 : 0); z <= std::min(cz + 1, nz - 1); ++z)
        for (size_t y = (cy > 0 ? cy - 1 : 0); y <= std::min(cy + 1, ny - 1); ++y) {
          const size_t row = nx * (y + ny * z);
          const uint32_t b = starts[row + x0], e = starts[row + x1 + 1];
          if (b == e) continue;
          run_begin[num_runs] = b;
          run_end[num_runs] = e;
          ++num_runs;
          candidates += e - b;
        }
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
      for (uint32_t j = run_begin[r]; j < run_end[r]; ++j) {
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
