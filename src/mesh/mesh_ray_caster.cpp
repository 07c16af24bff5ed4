#include "relaxed_connectivity/mesh/mesh_ray_caster.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

// Tolerance on barycentrics: rays through a shared edge or vertex hit at least one triangle even when the
// floating-point barycentrics of both neighbours come out slightly negative.
constexpr double kBarycentricTolerance = 1e-9;
constexpr int kMaxStackDepth = 128;
constexpr int kMedianSplitDepth = 64;  // below this depth the SAH split is replaced by an object-median split
constexpr double kTraversalCost = 1.0;  // SAH cost of visiting a node, relative to one triangle test
constexpr double kIntersectionCost = 1.0;

struct Box {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());
  void grow(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void grow(const Box& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  bool valid() const { return lo.x() <= hi.x(); }
  double halfArea() const {
    if (!valid()) return 0.0;
    const Vec3 e = hi - lo;
    return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
  }
};

struct BuildItem {
  Box box;
  Vec3 centroid;
};

// Precomputed slab-test data of one ray. Zero direction components get a huge finite inverse so that an
// origin lying exactly on a slab plane gives 0 * big = 0 instead of NaN. `near[k]` selects the box corner (0
// lower, 1 upper) the ray enters through on axis k.
struct RaySlab {
  double inv[3], origin_scaled[3];
  int near[3];
  explicit RaySlab(const Ray& ray) {
    for (int k = 0; k < 3; ++k) {
      const double d = ray.direction[k];
      inv[k] = std::abs(d) > 1e-300 ? 1.0 / d : std::copysign(1e300, d);
      origin_scaled[k] = ray.origin[k] * inv[k];
      near[k] = std::signbit(inv[k]) ? 1 : 0;
    }
  }
};

}  // namespace

MeshRayCaster::MeshRayCaster(const TriangleMesh& mesh) : MeshRayCaster(mesh, Options()) {}

MeshRayCaster::MeshRayCaster(const TriangleMesh& mesh, const Options& options)
    : mesh_(&mesh), options_(options) {
  if (options_.max_leaf_size < 1)
    throw std::invalid_argument("MeshRayCaster: max_leaf_size must be >= 1, got " +
                                std::to_string(options_.max_leaf_size));
  if (options_.sah_bins < 2)
    throw std::invalid_argument("MeshRayCaster: sah_bins must be >= 2, got " +
                                std::to_string(options_.sah_bins));
  rebuild();
}

void MeshRayCaster::rebuild() {
  const auto& positions = mesh_->vertices.positions;
  const auto& tris = mesh_->triangles;
  for (size_t i = 0; i < positions.size(); ++i)
    if (!positions[i].allFinite())
      throw std::invalid_argument("MeshRayCaster: vertex " + std::to_string(i) +
                                  " has a non-finite position");
  for (size_t i = 0; i < tris.size(); ++i)
    for (uint32_t index : tris[i])
      if (index >= positions.size())
        throw std::invalid_argument("MeshRayCaster: triangle " + std::to_string(i) + " references vertex " +
                                    std::to_string(index) + " but the mesh has " +
                                    std::to_string(positions.size()) + " vertices");
  if (tris.size() >= std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("MeshRayCaster: too many triangles");

  const size_t n = tris.size();
  std::vector<BuildItem> items(n);
  for (size_t i = 0; i < n; ++i) {
    for (uint32_t index : tris[i]) items[i].box.grow(positions[index]);
    items[i].centroid = 0.5 * (items[i].box.lo + items[i].box.hi);
  }
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<uint32_t>(i);

  nodes_.clear();
  nodes_.reserve(n == 0 ? 1 : 2 * n / std::max(1, options_.max_leaf_size) + 1);
  depth_ = 0;
  const int bins = options_.sah_bins;
  std::vector<Box> bin_boxes(bins), right_boxes(bins);
  std::vector<size_t> bin_counts(bins), right_counts(bins);

  // Iterative depth-first build: a node's first child directly follows it; the second child's index is
  // patched into the parent when the second child is created.
  struct Task {
    uint32_t begin, end;
    int64_t parent;  // node whose `offset` receives this node's index (-1: none)
    int depth;
  };
  std::vector<Task> tasks;
  tasks.push_back({0, static_cast<uint32_t>(n), -1, 1});
  while (!tasks.empty()) {
    const Task task = tasks.back();
    tasks.pop_back();
    const uint32_t node_index = static_cast<uint32_t>(nodes_.size());
    if (task.parent >= 0) nodes_[task.parent].offset = node_index;
    depth_ = std::max(depth_, task.depth);

    Box box, centroid_box;
    for (uint32_t i = task.begin; i < task.end; ++i) {
      box.grow(items[order[i]].box);
      centroid_box.grow(items[order[i]].centroid);
    }
    Node node{};
    for (int k = 0; k < 3; ++k) {
      node.bounds[0][k] = box.valid() ? box.lo[k] : 0.0;
      node.bounds[1][k] = box.valid() ? box.hi[k] : -1.0;  // empty mesh: a box no ray enters
    }
    const uint32_t count = task.end - task.begin;
    nodes_.push_back(node);
    auto makeLeaf = [&]() {
      nodes_[node_index].offset = task.begin;
      nodes_[node_index].count = count;
    };
    if (count <= static_cast<uint32_t>(options_.max_leaf_size)) {
      makeLeaf();
      continue;
    }

    if (task.depth >= kMedianSplitDepth) {
      // Very deep (pathological triangle distributions): object-median split on the widest centroid axis
      // keeps the remaining depth logarithmic and within the traversal stack.
      int axis = 0;
      const Vec3 extent = centroid_box.hi - centroid_box.lo;
      if (extent.y() > extent[axis]) axis = 1;
      if (extent.z() > extent[axis]) axis = 2;
      const uint32_t mid = task.begin + count / 2;
      std::nth_element(
          order.data() + task.begin, order.data() + mid, order.data() + task.end,
          [&](uint32_t a, uint32_t b) { return items[a].centroid[axis] < items[b].centroid[axis]; });
      nodes_[node_index].axis = static_cast<uint32_t>(axis);
      nodes_[node_index].count = 0;
      tasks.push_back({mid, task.end, node_index, task.depth + 1});
      tasks.push_back({task.begin, mid, -1, task.depth + 1});
      continue;
    }

    // Binned SAH over the centroid bounds of every axis.
    int best_axis = -1;
    int best_split = -1;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int axis = 0; axis < 3; ++axis) {
      const double lo = centroid_box.lo[axis], extent = centroid_box.hi[axis] - lo;
      if (!(extent > 0.0)) continue;
      const double scale = bins / extent;
      std::fill(bin_boxes.begin(), bin_boxes.end(), Box());
      std::fill(bin_counts.begin(), bin_counts.end(), 0);
      for (uint32_t i = task.begin; i < task.end; ++i) {
        const BuildItem& item = items[order[i]];
        const int b = std::min(bins - 1, static_cast<int>((item.centroid[axis] - lo) * scale));
        bin_boxes[b].grow(item.box);
        ++bin_counts[b];
      }
      Box right;
      size_t right_count = 0;
      for (int b = bins - 1; b > 0; --b) {
        right.grow(bin_boxes[b]);
        right_count += bin_counts[b];
        right_boxes[b] = right;
        right_counts[b] = right_count;
      }
      Box left;
      size_t left_count = 0;
      for (int b = 0; b < bins - 1; ++b) {  // split between bin b and b + 1
        left.grow(bin_boxes[b]);
        left_count += bin_counts[b];
        if (left_count == 0 || right_counts[b + 1] == 0) continue;
        const double cost =
            left.halfArea() * left_count + right_boxes[b + 1].halfArea() * right_counts[b + 1];
        if (cost < best_cost) {
          best_cost = cost;
          best_axis = axis;
          best_split = b;
        }
      }
    }

    uint32_t mid;
    if (best_axis >= 0) {
      const double leaf_cost = kIntersectionCost * count;
      const double split_cost =
          kTraversalCost + kIntersectionCost * best_cost / std::max(box.halfArea(), 1e-300);
      if (split_cost >= leaf_cost && count <= 4 * static_cast<uint32_t>(options_.max_leaf_size)) {
        makeLeaf();
        continue;
      }
      const double lo = centroid_box.lo[best_axis];
      const double scale = bins / (centroid_box.hi[best_axis] - lo);
      auto* split_point = std::partition(order.data() + task.begin, order.data() + task.end, [&](uint32_t t) {
        return std::min(bins - 1, static_cast<int>((items[t].centroid[best_axis] - lo) * scale)) <=
               best_split;
      });
      mid = static_cast<uint32_t>(split_point - order.data());
      nodes_[node_index].axis = static_cast<uint32_t>(best_axis);
    } else {
      // All centroids coincide: split the range in half (keeps the depth logarithmic).
      mid = task.begin + count / 2;
      nodes_[node_index].axis = 0;
    }
    if (mid == task.begin || mid == task.end) mid = task.begin + count / 2;
    nodes_[node_index].count = 0;
    // Second child first on the stack so that the first child is built next (and lands at node_index + 1).
    tasks.push_back({mid, task.end, node_index, task.depth + 1});
    tasks.push_back({task.begin, mid, -1, task.depth + 1});
  }
  // Pad the boxes like the barycentric tolerance pads the triangles, so that rays grazing a box face (e.g.
  // along a mesh edge lying in it) are not culled by rounding before the tolerant triangle test.
  if (n > 0) {
    double extent = 0.0;
    for (int k = 0; k < 3; ++k) extent = std::max(extent, nodes_[0].bounds[1][k] - nodes_[0].bounds[0][k]);
    const double pad = 4.0 * kBarycentricTolerance * extent + 1e-300;
    for (Node& node : nodes_)
      for (int k = 0; k < 3; ++k) {
        node.bounds[0][k] -= pad;
        node.bounds[1][k] += pad;
      }
  }
  if (depth_ > kMaxStackDepth)
    throw std::runtime_error("MeshRayCaster: BVH depth " + std::to_string(depth_) +
                             " exceeds the traversal stack");

  triangles_.resize(n);
  triangle_ids_ = order;
  for (size_t i = 0; i < n; ++i) {
    const Triangle& tri = tris[order[i]];
    const Vec3& p0 = positions[tri[0]];
    triangles_[i] = {p0, positions[tri[1]] - p0, positions[tri[2]] - p0};
  }
}

bool MeshRayCaster::intersectTriangle(const Vec3& origin, const Vec3& direction, const Vec3& p0,
                                      const Vec3& p1, const Vec3& p2, double t_min, double t_max, double* t,
                                      double* u, double* v) {
  const Vec3 e1 = p1 - p0, e2 = p2 - p0;
  const Vec3 pvec = direction.cross(e2);
  const double det = e1.dot(pvec);
  if (det == 0.0 || !std::isfinite(det)) return false;
  const double inv_det = 1.0 / det;
  const Vec3 tvec = origin - p0;
  const double uu = tvec.dot(pvec) * inv_det;
  if (uu < -kBarycentricTolerance || uu > 1.0 + kBarycentricTolerance) return false;
  const Vec3 qvec = tvec.cross(e1);
  const double vv = direction.dot(qvec) * inv_det;
  if (vv < -kBarycentricTolerance || uu + vv > 1.0 + kBarycentricTolerance) return false;
  const double tt = e2.dot(qvec) * inv_det;
  if (!(tt >= t_min && tt <= t_max)) return false;
  *t = tt;
  *u = uu;
  *v = vv;
  return true;
}

template <bool kAnyHit>
bool MeshRayCaster::traverse(const Ray& ray, RayHit* hit) const {
  if (triangles_.empty()) return false;
  const RaySlab slab(ray);
  double best_t = ray.t_max;
  uint32_t best_leaf_index = RayHit::kNoHit;
  double best_u = 0.0, best_v = 0.0;
  const Vec3& o = ray.origin;
  const Vec3& d = ray.direction;

  auto enter = [&](const Node& node, double* t_enter) {
    const double ax = node.bounds[slab.near[0]][0] * slab.inv[0] - slab.origin_scaled[0];
    const double bx = node.bounds[1 - slab.near[0]][0] * slab.inv[0] - slab.origin_scaled[0];
    const double ay = node.bounds[slab.near[1]][1] * slab.inv[1] - slab.origin_scaled[1];
    const double by = node.bounds[1 - slab.near[1]][1] * slab.inv[1] - slab.origin_scaled[1];
    const double az = node.bounds[slab.near[2]][2] * slab.inv[2] - slab.origin_scaled[2];
    const double bz = node.bounds[1 - slab.near[2]][2] * slab.inv[2] - slab.origin_scaled[2];
    const double t0 = std::max(std::max(ax, ay), std::max(az, ray.t_min));
    const double t1 = std::min(std::min(bx, by), std::min(bz, best_t));
    *t_enter = t0;
    return t0 <= t1;
  };

  struct Entry {
    uint32_t node;
    double t;
  };
  Entry stack[kMaxStackDepth + 1];
  int top = 0;
  double t_root;
  if (!enter(nodes_[0], &t_root)) return false;
  uint32_t current = 0;
  while (true) {
    const Node& node = nodes_[current];
    if (node.count > 0) {
      const uint32_t end = node.offset + node.count;
      for (uint32_t i = node.offset; i < end; ++i) {
        const TriangleData& tri = triangles_[i];
        // Moller-Trumbore on the precomputed edges.
        const Vec3 pvec = d.cross(tri.e2);
        const double det = tri.e1.dot(pvec);
        if (det == 0.0) continue;
        const double inv_det = 1.0 / det;
        const Vec3 tvec = o - tri.p0;
        const double u = tvec.dot(pvec) * inv_det;
        if (u < -kBarycentricTolerance || u > 1.0 + kBarycentricTolerance) continue;
        const Vec3 qvec = tvec.cross(tri.e1);
        const double v = d.dot(qvec) * inv_det;
        if (v < -kBarycentricTolerance || u + v > 1.0 + kBarycentricTolerance) continue;
        const double t = tri.e2.dot(qvec) * inv_det;
        if (!(t >= ray.t_min && t <= best_t)) continue;
        if (kAnyHit) return true;
        best_t = t;
        best_leaf_index = i;
        best_u = u;
        best_v = v;
      }
    } else {
      const uint32_t first = current + 1, second = node.offset;
      double t_first, t_second;
      const bool hit_first = enter(nodes_[first], &t_first);
      const bool hit_second = enter(nodes_[second], &t_second);
      if (hit_first && hit_second) {
        if (t_second < t_first) {
          stack[top++] = {first, t_first};
          current = second;
        } else {
          stack[top++] = {second, t_second};
          current = first;
        }
        continue;
      }
      if (hit_first) {
        current = first;
        continue;
      }
      if (hit_second) {
        current = second;
        continue;
      }
    }
    // Pop the next node that may still hold a closer hit.
    bool found = false;
    while (top > 0) {
      const Entry entry = stack[--top];
      if (entry.t <= best_t) {
        current = entry.node;
        found = true;
        break;
      }
    }
    if (!found) break;
  }
  if (best_leaf_index == RayHit::kNoHit) return false;
  const TriangleData& tri = triangles_[best_leaf_index];
  hit->t = best_t;
  hit->triangle = triangle_ids_[best_leaf_index];
  hit->u = best_u;
  hit->v = best_v;
  const Vec3 n = tri.e1.cross(tri.e2);
  const double length = n.norm();
  hit->normal = length > 0.0 ? Vec3(n / length) : Vec3::Zero();
  return true;
}

bool MeshRayCaster::intersect(const Ray& ray, RayHit* hit) const {
  *hit = RayHit();
  return traverse<false>(ray, hit);
}

bool MeshRayCaster::occluded(const Ray& ray) const {
  return traverse<true>(ray, nullptr);
}

void MeshRayCaster::intersectBatch(const Ray* rays, size_t count, RayHit* hits) const {
  const int64_t n = static_cast<int64_t>(count);
#pragma omp parallel for schedule(dynamic, 256)
  for (int64_t i = 0; i < n; ++i) intersect(rays[i], &hits[i]);
}

void MeshRayCaster::intersectBatch(const std::vector<Ray>& rays, std::vector<RayHit>& hits) const {
  hits.resize(rays.size());
  intersectBatch(rays.data(), rays.size(), hits.data());
}

}  // namespace rc
