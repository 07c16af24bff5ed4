#include "relaxed_connectivity/core/hash_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

// Primes of Teschner et al. (3.17).
constexpr uint64_t kP1 = 73856093, kP2 = 19349663, kP3 = 83492791;
// Cell coordinates must stay where doubles still resolve cells exactly.
constexpr double kMaxCellCoord = 4503599627370496.0;  // 2^52

bool isPrime(size_t n) {
  if (n < 2) return false;
  if (n % 2 == 0) return n == 2;
  for (size_t f = 3; f * f <= n; f += 2)
    if (n % f == 0) return false;
  return true;
}

size_t nextPrime(size_t n) {
  while (!isPrime(n)) ++n;
  return n;
}

struct HeapLess {
  bool operator()(const Neighbor& a, const Neighbor& b) const { return a.sq_dist < b.sq_dist; }
};

/// Max-heap of the k best candidates in heap[0, count).
inline void offerKnn(Neighbor* heap, size_t k, size_t& count, Neighbor candidate) {
  if (count < k) {
    heap[count++] = candidate;
    std::push_heap(heap, heap + count, HeapLess());
  } else if (candidate.sq_dist < heap[0].sq_dist) {
    std::pop_heap(heap, heap + k, HeapLess());
    heap[k - 1] = candidate;
    std::push_heap(heap, heap + k, HeapLess());
  }
}

}  // namespace

HashGrid::HashGrid(double max_radius, size_t expected_points) : max_radius_(max_radius) {
  if (!(max_radius > 0.0) || !std::isfinite(max_radius))
    throw std::invalid_argument("HashGrid: max_radius must be positive and finite, got " +
                                std::to_string(max_radius));
  cell_size_ = 2.0 * max_radius;  // Fig. 3.7c
  inv_cell_size_ = 1.0 / cell_size_;
  rehash(nextPrime(std::max<size_t>(97, expected_points / 2)));
  clear();
}

void HashGrid::cellOf(const Vec3& p, int64_t cell[3]) const {
  for (int a = 0; a < 3; ++a) {
    const double s = std::floor(p[a] * inv_cell_size_);  // (3.16); floor, not truncation, for negatives
    if (!(std::abs(s) < kMaxCellCoord))
      throw std::invalid_argument("HashGrid: position coordinate " + std::to_string(p[a]) +
                                  " is not finite or too far from the origin for cell size " +
                                  std::to_string(cell_size_));
    cell[a] = static_cast<int64_t>(s);
  }
}

uint32_t HashGrid::bucketOf(int64_t i, int64_t j, int64_t k) const {
  const uint64_t h = (static_cast<uint64_t>(i) * kP1) ^ (static_cast<uint64_t>(j) * kP2) ^
                     (static_cast<uint64_t>(k) * kP3);  // (3.17)
  return static_cast<uint32_t>(h % buckets_.size());
}

void HashGrid::rehash(size_t table_size) {
  std::vector<std::vector<Entry>> old;
  old.swap(buckets_);
  buckets_.resize(table_size);
  for (auto& bucket : old)
    for (const Entry& e : bucket) {
      int64_t c[3];
      cellOf(e.position, c);
      const uint32_t b = bucketOf(c[0], c[1], c[2]);
      slots_[e.id] = {b, static_cast<uint32_t>(buckets_[b].size())};
      buckets_[b].push_back(e);
    }
}

void HashGrid::clear() {
  for (auto& bucket : buckets_) bucket.clear();
  slots_.clear();
  size_ = 0;
  for (int a = 0; a < 3; ++a) {
    cell_min_[a] = std::numeric_limits<int64_t>::max();
    cell_max_[a] = std::numeric_limits<int64_t>::min();
  }
}

void HashGrid::build(const std::vector<Vec3>& points) {
  if (points.size() >= kAbsent) throw std::invalid_argument("HashGrid::build: too many points");
  clear();
  const size_t wanted = std::max<size_t>(97, points.size() / 2);
  if (buckets_.size() < wanted / 2 || buckets_.size() > wanted * 4) rehash(nextPrime(wanted));
  slots_.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) insert(static_cast<uint32_t>(i), points[i]);
}

void HashGrid::insert(uint32_t id, const Vec3& position) {
  if (id == kAbsent) throw std::invalid_argument("HashGrid::insert: id UINT32_MAX is reserved");
  if (contains(id)) throw std::invalid_argument("HashGrid::insert: id " + std::to_string(id) + " is present");
  int64_t c[3];
  cellOf(position, c);
  if (id >= slots_.size()) slots_.resize(static_cast<size_t>(id) + 1, Slot{kAbsent, 0});
  const uint32_t b = bucketOf(c[0], c[1], c[2]);
  slots_[id] = {b, static_cast<uint32_t>(buckets_[b].size())};
  buckets_[b].push_back({position, id});
  ++size_;
  for (int a = 0; a < 3; ++a) {
    cell_min_[a] = std::min(cell_min_[a], c[a]);
    cell_max_[a] = std::max(cell_max_[a], c[a]);
  }
  if (size_ > 4 * buckets_.size()) rehash(nextPrime(2 * size_));
}

void HashGrid::remove(uint32_t id) {
  if (!contains(id)) throw std::invalid_argument("HashGrid::remove: id " + std::to_string(id) + " is absent");
  const Slot s = slots_[id];
  auto& bucket = buckets_[s.bucket];
  if (s.index + 1 != bucket.size()) {  // swap-remove; the moved entry gets its new slot
    bucket[s.index] = bucket.back();
    slots_[bucket[s.index].id].index = s.index;
  }
  bucket.pop_back();
  slots_[id].bucket = kAbsent;
  --size_;
}

void HashGrid::move(uint32_t id, const Vec3& position) {
  if (!contains(id)) throw std::invalid_argument("HashGrid::move: id " + std::to_string(id) + " is absent");
  int64_t c[3];
  cellOf(position, c);
  const uint32_t b = bucketOf(c[0], c[1], c[2]);
  for (int a = 0; a < 3; ++a) {
    cell_min_[a] = std::min(cell_min_[a], c[a]);
    cell_max_[a] = std::max(cell_max_[a], c[a]);
  }
  const Slot s = slots_[id];
  if (b == s.bucket) {
    buckets_[b][s.index].position = position;
    return;
  }
  remove(id);
  slots_[id] = {b, static_cast<uint32_t>(buckets_[b].size())};
  buckets_[b].push_back({position, id});
  ++size_;
}

const Vec3& HashGrid::position(uint32_t id) const {
  if (!contains(id))
    throw std::invalid_argument("HashGrid::position: id " + std::to_string(id) + " is absent");
  const Slot s = slots_[id];
  return buckets_[s.bucket][s.index].position;
}

size_t HashGrid::radius(const Vec3& query, double radius, std::vector<Neighbor>& out, bool sorted) const {
  out.clear();
  if (!(radius >= 0.0) || radius > max_radius_)
    throw std::invalid_argument("HashGrid::radius: radius " + std::to_string(radius) + " is not in [0, " +
                                std::to_string(max_radius_) + "]");
  if (!query.allFinite()) throw std::invalid_argument("HashGrid::radius: query point is not finite");
  if (size_ == 0) return 0;
  // Cell range per axis; the slack covers rounding so that every point passing the distance test is in range.
  // With radius <= r_max = d/2 this is 2 cells per axis (the 8 nearest cells), rarely 3 when at a boundary.
  int64_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const double ext = radius + 4.0 * std::numeric_limits<double>::epsilon() * (std::abs(query[a]) + radius);
    const double l = std::floor((query[a] - ext) * inv_cell_size_),
                 h = std::floor((query[a] + ext) * inv_cell_size_);
    if (h < -kMaxCellCoord || l > kMaxCellCoord) return 0;  // beyond every storable point
    lo[a] = static_cast<int64_t>(std::max(l, -kMaxCellCoord));
    hi[a] = static_cast<int64_t>(std::min(h, kMaxCellCoord));
  }
  uint32_t visited[27];
  int num_visited = 0;
  const double r2 = radius * radius;
  for (int64_t i = lo[0]; i <= hi[0]; ++i)
    for (int64_t j = lo[1]; j <= hi[1]; ++j)
      for (int64_t k = lo[2]; k <= hi[2]; ++k) {
        const uint32_t b = bucketOf(i, j, k);
        // Colliding cells share a bucket: scan each bucket once (the distance test rejects foreign points).
        if (std::find(visited, visited + num_visited, b) != visited + num_visited) continue;
        visited[num_visited++] = b;
        for (const Entry& e : buckets_[b]) {
          const double d2 = (e.position - query).squaredNorm();
          if (d2 <= r2) out.push_back({e.id, d2});
        }
      }
  if (sorted) std::sort(out.begin(), out.end(), HeapLess());
  return out.size();
}

void HashGrid::scanBucketKnn(uint32_t bucket, const Vec3& query, size_t k, Neighbor* heap,
                             size_t& count) const {
  for (const Entry& e : buckets_[bucket]) {
    const double d2 = (e.position - query).squaredNorm();
    if (count == k && d2 >= heap[0].sq_dist) continue;
    offerKnn(heap, k, count, {e.id, d2});
  }
}

size_t HashGrid::knnBruteForce(const Vec3& query, size_t k, Neighbor* out) const {
  size_t count = 0;
  for (uint32_t b = 0; b < buckets_.size(); ++b) scanBucketKnn(b, query, k, out, count);
  std::sort_heap(out, out + count, HeapLess());
  return count;
}

size_t HashGrid::knn(const Vec3& query, size_t k, Neighbor* out) const {
  if (!query.allFinite()) throw std::invalid_argument("HashGrid::knn: query point is not finite");
  k = std::min(k, size_);
  if (k == 0) return 0;
  int64_t base[3];
  for (int a = 0; a < 3; ++a) {
    const double s = std::floor(query[a] * inv_cell_size_ - 0.5);  // lower corner of the 8 nearest cells
    if (!(std::abs(s) < 4.0 * kMaxCellCoord)) return knnBruteForce(query, k, out);
    base[a] = static_cast<int64_t>(s);
  }
  // Start at the first shell that reaches the occupied cells (queries far outside skip the empty shells).
  int64_t radius_cells = 0;
  for (int a = 0; a < 3; ++a)
    radius_cells = std::max({radius_cells, cell_min_[a] - (base[a] + 1), base[a] - cell_max_[a]});
  const size_t budget = 4 * (buckets_.size() + size_) + 64;
  size_t cells_visited = 0, count = 0;
  const double slack = 1e-10 * (query.cwiseAbs().maxCoeff() + cell_size_);
  for (;; ++radius_cells) {
    int64_t lo[3], hi[3], clo[3], chi[3];
    bool covers_all = true, empty = false;
    for (int a = 0; a < 3; ++a) {
      lo[a] = base[a] - radius_cells;
      hi[a] = base[a] + 1 + radius_cells;
      clo[a] = std::max(lo[a], cell_min_[a]);
      chi[a] = std::min(hi[a], cell_max_[a]);
      covers_all = covers_all && lo[a] <= cell_min_[a] && hi[a] >= cell_max_[a];
      empty = empty || clo[a] > chi[a];
    }
    if (!empty) {
      // Shell = block [lo, hi]^3 minus its interior, clipped to the occupied cells.
      auto visit = [&](int64_t i, int64_t j, int64_t kk) {
        for (const Entry& e : buckets_[bucketOf(i, j, kk)]) {
          const double d2 = (e.position - query).squaredNorm();
          if (count == k && d2 >= out[0].sq_dist) continue;
          int64_t c[3];
          cellOf(e.position, c);
          if (c[0] != i || c[1] != j || c[2] != kk) continue;  // hash collision: another cell's point
          offerKnn(out, k, count, {e.id, d2});
        }
      };
      for (int64_t i = clo[0]; i <= chi[0]; ++i)
        for (int64_t j = clo[1]; j <= chi[1]; ++j) {
          const bool side = i == lo[0] || i == hi[0] || j == lo[1] || j == hi[1];
          cells_visited += side ? static_cast<size_t>(chi[2] - clo[2] + 1) : 2;
          if (cells_visited > budget) return knnBruteForce(query, k, out);
          if (side) {
            for (int64_t kk = clo[2]; kk <= chi[2]; ++kk) visit(i, j, kk);
          } else {
            if (clo[2] == lo[2]) visit(i, j, lo[2]);
            if (chi[2] == hi[2] && hi[2] != lo[2]) visit(i, j, hi[2]);
          }
        }
    }
    if (covers_all) break;
    if (count == k) {
      // Distance from the query to the boundary of the searched block bounds every unvisited point.
      double covered = std::numeric_limits<double>::infinity();
      for (int a = 0; a < 3; ++a)
        covered = std::min({covered, query[a] - static_cast<double>(lo[a]) * cell_size_,
                            static_cast<double>(hi[a] + 1) * cell_size_ - query[a]});
      covered -= slack;
      if (covered > 0.0 && out[0].sq_dist <= covered * covered) break;
    }
  }
  std::sort_heap(out, out + count, HeapLess());
  return count;
}

}  // namespace rc
