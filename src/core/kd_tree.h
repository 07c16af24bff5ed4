// kd-tree (thesis 3.4.1) over a point array, backed by nanoflann, for k-nearest and range queries.
#pragma once

#include <memory>
#include <vector>

#include "relaxed_connectivity/core/neighbor.h"
#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// Static kd-tree over `points`. The tree references the caller's array: it must outlive the tree and not
/// change (call rebuild() after it changes). Internally the points are copied in leaf order so that a leaf is
/// one contiguous block of memory (results still carry the caller's indices). Distances returned are SQUARED;
/// a point at exactly the query radius is included. Leaves hold up to `max_leaf_size` points: with contiguous
/// leaves, 24 is faster than nanoflann's default of 10 for both kNN and radius queries. All queries are const
/// and thread-safe; the single-query functions write into caller-provided storage and do not allocate once
/// that storage has grown to its working size.
class KdTree {
 public:
  explicit KdTree(const std::vector<Vec3>& points, int max_leaf_size = 24);
  ~KdTree();
  KdTree(const KdTree&) = delete;
  KdTree& operator=(const KdTree&) = delete;

  void rebuild();
  size_t size() const;
  const std::vector<Vec3>& points() const { return *points_; }

  /// The k nearest points, sorted by increasing distance. Writes min(k, size()) entries to `out` (which must
  /// hold k entries); `Neighbor::sq_dist` is the squared distance. Returns the number written.
  size_t knn(const Vec3& query, size_t k, Neighbor* out) const;

  /// The nearest point if it lies within sqrt(bound_sq) (inclusive): a known upper bound, such as the
  /// distance to a point found near the query before, prunes the search from the start. Returns false,
  /// leaving `out` unspecified, when no point is that close.
  bool nearestWithin(const Vec3& query, double bound_sq, Neighbor* out) const;

  /// All points with distance <= radius (the radius is NOT squared). `out` is cleared first and keeps its
  /// capacity. Sorted by distance only if `sorted`. Returns out.size().
  size_t radius(const Vec3& query, double radius, std::vector<Neighbor>& out, bool sorted = false) const;

  /// Batched k-nearest: row i of the result (k entries starting at i*k) belongs to query i; rows of queries
  /// with fewer than k candidates are padded with {UINT32_MAX, inf}. Multi-threaded.
  void knnBatch(const std::vector<Vec3>& queries, size_t k, std::vector<Neighbor>& out) const;

  /// For each point of the tree, the distance to its k-th nearest other point (the (k + 1)-th nearest
  /// counting the point itself; the sample spacing for k = 1); infinity when the tree has no more than k
  /// points. Multi-threaded.
  std::vector<double> kthNeighborDistances(size_t k) const;
  /// Batched radius queries in CSR form: the neighbours of query i are out[offsets[i] .. offsets[i+1]),
  /// unsorted, with squared distances. Multi-threaded (OpenMP); `offsets` and `out` keep their capacity.
  void radiusBatch(const std::vector<Vec3>& queries, double radius, std::vector<size_t>& offsets,
                   std::vector<Neighbor>& out) const;

 private:
  struct Impl;
  const std::vector<Vec3>* points_;
  int max_leaf_size_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rc
