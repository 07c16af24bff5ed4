// Uniform grid with points counting-sorted by cell: the all-pairs fixed-radius neighbour searches
// (NeighborLists, the SPH solver; thesis 8.1.1) walk the sorted points cell by cell.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// Points are counting-sorted by their cell (cells at least `cell_size` wide plus a rounding slack, linear
/// cell order with x fastest), so the 27 cells around a cell form at most 9 runs of contiguous sorted
/// positions. The sort is serial and stable, so the order (and everything computed in it) does not depend on
/// the thread count. Buffers are members and only grow.
class SortedCellGrid {
 public:
  /// A run [begin, end) of sorted positions.
  struct Run {
    uint32_t begin, end;
  };

  /// Sorts `points` into cells of at least `cell_size` (coarsened if the box would need more than about
  /// 8 cells per point). Throws std::invalid_argument naming `caller` for a non-finite point (with its index)
  /// or a cell size that is not finite and >= 0, std::length_error for more than 2^32 - 1 points.
  void build(const std::vector<Vec3>& points, double cell_size, int num_threads,
             const std::string& caller = "SortedCellGrid::build");

  size_t size() const { return order_.size(); }
  /// order()[s] = original index of the point at sorted position s.
  const std::vector<uint32_t>& order() const { return order_; }
  /// Cell of the point at sorted position s.
  uint32_t cellOfSorted(size_t s) const { return sorted_cell_[s]; }
  /// The runs of sorted positions in the (up to) 27 cells around `cell`; returns their number (<= 9).
  int neighborRuns(uint32_t cell, Run runs[9]) const;
  /// Cells per axis, and whether a cell (linear index, x fastest) holds a point.
  size_t dim(int axis) const { return dims_[axis]; }
  bool occupied(size_t cell) const { return cell_start_[cell] != cell_start_[cell + 1]; }
  /// The (unclamped) cell coordinates of q, and the Euclidean distance from q to the grid's box (0 inside).
  void cellCoordinates(const Vec3& q, double coordinates[3], double* outside_distance) const;
  /// Width of a cell: the cell size given to build(), or coarser.
  double cellWidth() const { return 1.0 / inv_cell_; }
  /// The runs of sorted positions in the cells within one cell of the one containing `q` along each axis
  /// (q may lie outside the grid); returns their number (<= 9). Every point outside them is at least
  /// cellWidth() from q. Requires a finite q.
  int runsAround(const Vec3& q, Run runs[9]) const;

 private:
  double origin_[3] = {0, 0, 0};
  double inv_cell_ = 1.0;
  size_t dims_[3] = {1, 1, 1};
  std::vector<uint32_t> cell_of_point_, cell_start_, order_, sorted_cell_;
};

}  // namespace rc
