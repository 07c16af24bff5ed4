#include "core/kd_tree.h"

#include <algorithm>
#include <limits>
#include <nanoflann.hpp>

namespace rc {

namespace {

struct PointAdaptor {
  const std::vector<Vec3>* pts;
  size_t kdtree_get_point_count() const { return pts->size(); }
  double kdtree_get_pt(size_t i, size_t dim) const { return (*pts)[i][dim]; }
  template <class Bbox>
  bool kdtree_get_bbox(Bbox&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointAdaptor>,
                                                 PointAdaptor, 3, uint32_t>;

/// Radius result set writing into a reusable std::vector<Neighbor> (nanoflann's own allocates pairs).
class NeighborRadiusSet {
 public:
  NeighborRadiusSet(double sq_radius, std::vector<Neighbor>& out) : sq_radius_(sq_radius), out_(out) {
    out_.clear();
  }
  void init() { out_.clear(); }
  void clear() { out_.clear(); }
  size_t size() const { return out_.size(); }
  bool full() const { return true; }
  bool addPoint(double dist, uint32_t index) {
    if (dist < sq_radius_ || (dist == sq_radius_)) out_.push_back({index, dist});
    return true;
  }
  double worstDist() const { return sq_radius_; }

 private:
  double sq_radius_;
  std::vector<Neighbor>& out_;
};

}  // namespace

struct KdTree::Impl {
  PointAdaptor adaptor;
  Tree tree;
  Impl(const std::vector<Vec3>* pts, int leaf)
      : adaptor{pts}, tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(leaf)) {
    tree.buildIndex();
  }
};

KdTree::KdTree(const std::vector<Vec3>& points, int max_leaf_size)
    : points_(&points), max_leaf_size_(max_leaf_size) {
  rebuild();
}

KdTree::~KdTree() = default;

void KdTree::rebuild() { impl_ = std::make_unique<Impl>(points_, max_leaf_size_); }

size_t KdTree::size() const { return points_->size(); }

size_t KdTree::knn(const Vec3& query, size_t k, Neighbor* out) const {
  const size_t n = std::min(k, size());
  if (n == 0) return 0;
  // nanoflann's KNNResultSet needs separate index and distance arrays; write them into `out` in place.
  constexpr size_t kStack = 64;
  uint32_t idx_buf[kStack];
  double dist_buf[kStack];
  std::vector<uint32_t> idx_heap;
  std::vector<double> dist_heap;
  uint32_t* idx = idx_buf;
  double* dist = dist_buf;
  if (n > kStack) {
    idx_heap.resize(n);
    dist_heap.resize(n);
    idx = idx_heap.data();
    dist = dist_heap.data();
  }
  nanoflann::KNNResultSet<double, uint32_t> rs(n);
  rs.init(idx, dist);
  impl_->tree.findNeighbors(rs, query.data(), nanoflann::SearchParams());
  const size_t found = rs.size();
  for (size_t i = 0; i < found; ++i) out[i] = {idx[i], dist[i]};
  return found;
}

size_t KdTree::radius(const Vec3& query, double radius, std::vector<Neighbor>& out, bool sorted) const {
  NeighborRadiusSet rs(radius * radius, out);
  if (size() == 0) return 0;
  impl_->tree.findNeighbors(rs, query.data(), nanoflann::SearchParams());
  if (sorted)
    std::sort(out.begin(), out.end(), [](const Neighbor& a, const Neighbor& b) { return a.sq_dist < b.sq_dist; });
  return out.size();
}

void KdTree::knnBatch(const std::vector<Vec3>& queries, size_t k, std::vector<Neighbor>& out) const {
  out.assign(queries.size() * k, Neighbor{std::numeric_limits<uint32_t>::max(),
                                          std::numeric_limits<double>::infinity()});
#pragma omp parallel for schedule(dynamic, 256)
  for (long i = 0; i < static_cast<long>(queries.size()); ++i) knn(queries[i], k, out.data() + i * k);
}

}  // namespace rc
