// All-pairs fixed-radius neighbour lists (the SPH hot path, thesis 3.4.2 and chapter 8) built on a sorted
// grid.
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/sorted_cell_grid.h"
#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// For n points and radius h, the lists of all j != i with |x_i - x_j| <= h in CSR form: the neighbours of
/// point i are indices()[offsets()[i] .. offsets()[i+1]). Rows and entries use the ORIGINAL point indices
/// (the internal reordering is undone), entries of a row are in no particular order, and the relation is
/// symmetric. Optional sqDists() runs parallel to indices() and holds SQUARED distances.
///
/// Method: "sorted grid". Points are counting-sorted by their cell (cell size >= h, linear order with x
/// fastest), so the 27 cells around a point form 9 contiguous runs of memory; every point scans those runs.
/// All buffers are members and only grow: rebuilding for a similar n allocates nothing.
class NeighborLists {
 public:
  struct Options {
    bool store_sq_dists = false;
    /// Threads for the build (OpenMP): 1 = single-threaded, 0 = all available.
    int num_threads = 1;
  };

  /// Rebuilds the lists. Throws std::invalid_argument for a negative or non-finite radius or a non-finite
  /// point (naming its index), and std::length_error if the lists would exceed 2^32 - 1 entries.
  void build(const std::vector<Vec3>& points, double radius, const Options& options);
  void build(const std::vector<Vec3>& points, double radius) { build(points, radius, Options()); }

  size_t numPoints() const { return num_points_; }
  /// Total number of entries (each unordered pair counts twice).
  size_t numEntries() const { return num_points_ == 0 ? 0 : offsets_[num_points_]; }
  double meanCount() const { return num_points_ == 0 ? 0.0 : double(numEntries()) / double(num_points_); }
  double radius() const { return radius_; }

  const std::vector<uint32_t>& offsets() const { return offsets_; }  ///< size numPoints() + 1
  const std::vector<uint32_t>& indices() const { return indices_; }  ///< size >= numEntries() (capacity kept)
  const std::vector<double>& sqDists() const { return sq_dists_; }   ///< empty unless Options::store_sq_dists

  size_t count(size_t i) const { return offsets_[i + 1] - offsets_[i]; }
  const uint32_t* begin(size_t i) const { return indices_.data() + offsets_[i]; }
  const uint32_t* end(size_t i) const { return indices_.data() + offsets_[i + 1]; }
  const double* sqDistsBegin(size_t i) const { return sq_dists_.data() + offsets_[i]; }

 private:
  struct SortedPoint {
    double x, y, z;
    uint32_t id;
  };
  struct ThreadBuffer {
    std::vector<uint32_t> indices;
    std::vector<double> sq_dists;
    size_t used = 0;
  };
  template <bool kStoreDists>
  void scanChunk(size_t first, size_t last, ThreadBuffer& buffer);

  size_t num_points_ = 0;
  double radius_ = 0.0;
  double sq_radius_ = 0.0;
  // Work buffers (reused across builds)
  SortedCellGrid grid_;
  std::vector<SortedPoint> sorted_;  // positions in grid order, with their original index
  std::vector<uint32_t> row_count_;  // by sorted position
  std::vector<ThreadBuffer> threads_;
  std::vector<size_t> thread_first_;
  // Result
  std::vector<uint32_t> offsets_, indices_;
  std::vector<double> sq_dists_;
};

}  // namespace rc
