// Dynamic spatial hash grid (thesis 3.4.2) for fixed-radius and k-nearest queries on moving points (SPH).
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/neighbor.h"
#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// Hash grid with cell size d = 2 r_max: a fixed-radius query with r <= r_max visits only the 8 cells nearest
/// to the query point (Fig. 3.7c). Cells (3.16) are hashed with Teschner's function (3.17) into a table of
/// prime size; the table grows (rehash, prime size) when it holds more than four points per slot on average.
///
/// Points are identified by caller-chosen ids (dense small integers work best: per-id storage is a flat array
/// indexed by id). insert / remove / move are O(1) on average and allocation-free once the buckets have
/// grown. Queries are const and thread-safe. ALL DISTANCES RETURNED ARE SQUARED (Neighbor::sq_dist); radii
/// passed in are not squared.
class HashGrid {
 public:
  /// `max_radius` > 0 is the largest radius a fixed-radius query may use; `expected_points` sizes the table.
  explicit HashGrid(double max_radius, size_t expected_points = 0);

  double maxRadius() const { return max_radius_; }
  double cellSize() const { return cell_size_; }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  size_t tableSize() const { return buckets_.size(); }

  /// Removes all points and inserts points[i] with id i.
  void build(const std::vector<Vec3>& points);
  void clear();

  /// Adds point `id` at `position`; throws std::invalid_argument if `id` is present or the position is not
  /// finite or too far out for 64-bit cell indices.
  void insert(uint32_t id, const Vec3& position);
  /// Removes point `id`; throws std::invalid_argument if it is absent.
  void remove(uint32_t id);
  /// Moves point `id` to `position` (re-buckets it only if its hash slot changes).
  void move(uint32_t id, const Vec3& position);
  bool contains(uint32_t id) const { return id < slots_.size() && slots_[id].bucket != kAbsent; }
  /// Stored position of point `id` (throws if absent).
  const Vec3& position(uint32_t id) const;

  /// All points with |p - query| <= radius (radius <= maxRadius(), else std::invalid_argument). `out` is
  /// cleared first and keeps its capacity; entries carry SQUARED distances, sorted increasingly if `sorted`.
  /// Returns out.size().
  size_t radius(const Vec3& query, double radius, std::vector<Neighbor>& out, bool sorted = false) const;

  /// The k nearest points, sorted by increasing SQUARED distance, written to `out` (room for k entries) by
  /// the expanding search of 3.4.2: the 8 nearest cells first, then shells of cells around them until the
  /// k-th distance is inside the searched block. Returns min(k, size()).
  size_t knn(const Vec3& query, size_t k, Neighbor* out) const;

 private:
  struct Entry {
    Vec3 position;
    uint32_t id;
  };
  struct Slot {
    uint32_t bucket;
    uint32_t index;  // position inside the bucket
  };
  static constexpr uint32_t kAbsent = UINT32_MAX;

  void cellOf(const Vec3& p, int64_t cell[3]) const;
  uint32_t bucketOf(int64_t i, int64_t j, int64_t k) const;
  void rehash(size_t table_size);
  void scanBucketKnn(uint32_t bucket, const Vec3& query, size_t k, Neighbor* heap, size_t& count) const;
  size_t knnBruteForce(const Vec3& query, size_t k, Neighbor* out) const;

  double max_radius_, cell_size_, inv_cell_size_;
  size_t size_ = 0;
  std::vector<std::vector<Entry>> buckets_;
  std::vector<Slot> slots_;  // by id
  // Grow-only bounding box of occupied cells (reset by clear/build); bounds the kNN shell expansion.
  int64_t cell_min_[3], cell_max_[3];
};

}  // namespace rc
