#include "relaxed_connectivity/core/kd_tree.h"

#include <omp.h>
#include <algorithm>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");

/// Flat xyz array; during the build it is the caller's array, afterwards the copy in leaf order.
struct PointAdaptor {
  const double* xyz = nullptr;
  size_t count = 0;
  size_t kdtree_get_point_count() const { return count; }
  double kdtree_get_pt(size_t i, size_t dim) const { return xyz[3 * i + dim]; }
  template <class Bbox>
  bool kdtree_get_bbox(Bbox&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointAdaptor>,
                                                 PointAdaptor, 3, uint32_t>;

/// k-nearest result set writing straight into caller storage (sorted insertion as nanoflann's KNNResultSet);
/// tree positions are mapped back to the caller's indices at the end.
class NeighborKnnSet {
 public:
  NeighborKnnSet(size_t k, Neighbor* out, double worst = std::numeric_limits<double>::max())
      : out_(out), capacity_(k) {
    out_[capacity_ - 1].sq_dist = worst;
  }
  size_t size() const { return count_; }
  bool full() const { return count_ == capacity_; }
  bool addPoint(double dist, uint32_t index) {
    size_t i = count_;
    for (; i > 0 && out_[i - 1].sq_dist > dist; --i)
      if (i < capacity_) out_[i] = out_[i - 1];
    if (i < capacity_) out_[i] = {index, dist};
    if (count_ < capacity_) ++count_;
    return true;
  }
  double worstDist() const { return out_[capacity_ - 1].sq_dist; }

 private:
  Neighbor* out_;
  size_t capacity_, count_ = 0;
};

/// Radius result set appending to a reusable std::vector<Neighbor> (nanoflann's own allocates pairs).
/// worstDist() is just above r^2 because nanoflann's leaf test is strict: points at exactly r are included.
class NeighborRadiusSet {
 public:
  NeighborRadiusSet(double sq_radius, std::vector<Neighbor>& out)
      : sq_radius_(sq_radius),
        worst_(std::nextafter(sq_radius, std::numeric_limits<double>::infinity())),
        out_(out) {}
  size_t size() const { return out_.size(); }
  bool full() const { return true; }
  bool addPoint(double dist, uint32_t index) {
    if (dist <= sq_radius_) out_.push_back({index, dist});
    return true;
  }
  double worstDist() const { return worst_; }

 private:
  double sq_radius_, worst_;
  std::vector<Neighbor>& out_;
};

}  // namespace

struct KdTree::Impl {
  PointAdaptor adaptor;
  Tree tree;
  std::vector<Vec3> leaf_ordered;     // points in tree order
  std::vector<uint32_t> original_id;  // tree position -> caller index

  Impl(const std::vector<Vec3>& pts, int leaf)
      : adaptor{pts.empty() ? nullptr : pts[0].data(), pts.size()},
        tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(leaf)) {
    tree.buildIndex();
    // Re-point the tree at a copy in leaf order so every leaf scan reads contiguous memory.
    original_id = tree.vAcc;
    leaf_ordered.resize(pts.size());
    for (size_t i = 0; i < pts.size(); ++i) {
      leaf_ordered[i] = pts[original_id[i]];
      tree.vAcc[i] = static_cast<uint32_t>(i);
    }
    adaptor.xyz = leaf_ordered.empty() ? nullptr : leaf_ordered[0].data();
  }
  void mapBack(Neighbor* begin, Neighbor* end) const {
    for (Neighbor* it = begin; it != end; ++it) it->index = original_id[it->index];
  }
};

KdTree::KdTree(const std::vector<Vec3>& points, int max_leaf_size)
    : points_(&points), max_leaf_size_(max_leaf_size) {
  if (max_leaf_size < 1)
    throw std::invalid_argument("KdTree: max_leaf_size must be >= 1, got " + std::to_string(max_leaf_size));
  rebuild();
}

KdTree::~KdTree() = default;

void KdTree::rebuild() {
  if (points_->size() >= std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("KdTree: too many points (" + std::to_string(points_->size()) + ")");
  impl_ = std::make_unique<Impl>(*points_, max_leaf_size_);
}

size_t KdTree::size() const {
  return impl_->adaptor.count;
}

size_t KdTree::knn(const Vec3& query, size_t k, Neighbor* out) const {
  const size_t n = std::min(k, size());
  if (n == 0) return 0;
  NeighborKnnSet rs(n, out);
  impl_->tree.findNeighbors(rs, query.data(), nanoflann::SearchParams());
  const size_t found = rs.size();
  impl_->mapBack(out, out + found);
  return found;
}

bool KdTree::nearestWithin(const Vec3& query, double bound_sq, Neighbor* out) const {
  if (size() == 0 || !(bound_sq >= 0)) return false;
  // The bound seeds the result set's worst distance, so the search prunes with it from the root down.
  NeighborKnnSet rs(1, out, std::nextafter(bound_sq, std::numeric_limits<double>::infinity()));
  impl_->tree.findNeighbors(rs, query.data(), nanoflann::SearchParams());
  if (rs.size() == 0) return false;
  impl_->mapBack(out, out + 1);
  return true;
}

size_t KdTree::radius(const Vec3& query, double radius, std::vector<Neighbor>& out, bool sorted) const {
  out.clear();
  if (!(radius >= 0.0))
    throw std::invalid_argument("KdTree::radius: radius " + std::to_string(radius) + " < 0");
  if (size() == 0) return 0;
  NeighborRadiusSet rs(radius * radius, out);
  impl_->tree.findNeighbors(rs, query.data(), nanoflann::SearchParams());
  impl_->mapBack(out.data(), out.data() + out.size());
  if (sorted)
    std::sort(out.begin(), out.end(),
              [](const Neighbor& a, const Neighbor& b) { return a.sq_dist < b.sq_dist; });
  return out.size();
}

void KdTree::knnBatch(const std::vector<Vec3>& queries, size_t k, std::vector<Neighbor>& out) const {
  out.assign(queries.size() * k,
             Neighbor{std::numeric_limits<uint32_t>::max(), std::numeric_limits<double>::infinity()});
#pragma omp parallel for schedule(dynamic, 256)
  for (long i = 0; i < static_cast<long>(queries.size()); ++i) knn(queries[i], k, out.data() + i * k);
}

std::vector<double> KdTree::kthNeighborDistances(size_t k) const {
  std::vector<Neighbor> rows;
  knnBatch(*points_, k + 1, rows);
  std::vector<double> distances(points_->size());
  for (size_t i = 0; i < distances.size(); ++i) {
    const Neighbor& kth = rows[i * (k + 1) + k];
    distances[i] = kth.index == UINT32_MAX ? std::numeric_limits<double>::infinity() : std::sqrt(kth.sq_dist);
  }
  return distances;
}

void KdTree::radiusBatch(const std::vector<Vec3>& queries, double radius, std::vector<size_t>& offsets,
                         std::vector<Neighbor>& out) const {
  if (!(radius >= 0.0))
    throw std::invalid_argument("KdTree::radiusBatch: radius " + std::to_string(radius) + " < 0");
  const long nq = static_cast<long>(queries.size());
  offsets.assign(queries.size() + 1, 0);
  out.clear();
  if (nq == 0) return;
  // Every thread answers one contiguous block of queries into a private buffer; the blocks are concatenated.
  std::vector<std::vector<Neighbor>> parts(omp_get_max_threads());
#pragma omp parallel num_threads(static_cast <int>(parts.size()))
  {
    const int t = omp_get_thread_num();
    const long nt = omp_get_num_threads();
    const long first = nq * t / nt, last = nq * (t + 1) / nt;
    std::vector<Neighbor>& part = parts[t];
    std::vector<Neighbor> scratch;
    for (long i = first; i < last; ++i) {
      KdTree::radius(queries[i], radius, scratch);
      offsets[i + 1] = scratch.size();
      part.insert(part.end(), scratch.begin(), scratch.end());
    }
  }
  for (size_t i = 0; i < queries.size(); ++i) offsets[i + 1] += offsets[i];
  out.resize(offsets.back());
  size_t pos = 0;
  for (const auto& part : parts) {
    std::copy(part.begin(), part.end(), out.begin() + pos);
    pos += part.size();
  }
}

}  // namespace rc
