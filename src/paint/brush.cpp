#include "relaxed_connectivity/paint/brush.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

namespace {
constexpr int kProjectionIterations = 4;  // projections (5.5) per collision of an active mass
}  // namespace

void BrushOptions::validate() const {
  if (collision_passes < 1)
    throw std::invalid_argument("collision_passes must be >= 1 (got " + std::to_string(collision_passes) +
                                ")");
  if (!(proxy_reach > 0) || !std::isfinite(proxy_reach))
    throw std::invalid_argument("proxy_reach must be positive (got " + std::to_string(proxy_reach) + ")");
}

Brush::Brush(const BrushPreset& preset, BrushOptions options)
    : preset_(preset), options_(options), skeleton_(preset), skin_(preset, skeleton_) {
  options_.validate();
  active_contacts_.resize(skeleton_.activeCount());
  cache_.resize(skeleton_.nodeCount());
}

void Brush::reset(const Eigen::Isometry3d& world_T_brush) {
  skeleton_.reset(world_T_brush);
  handle_contacts_.clear();
  active_contacts_.assign(skeleton_.activeCount(), SurfaceContact());
  split_ = BrushSplit();
  cache_.assign(skeleton_.nodeCount(), NodeCache());
  skin_stale_ = true;
}

const BrushSkin& Brush::skin() const {
  if (skin_stale_) skin_.update(skeleton_), skin_stale_ = false;
  return skin_;
}

BrushSkin& Brush::skin() {
  static_cast<const Brush*>(this)->skin();
  return skin_;
}

BrushEventStats Brush::advance(double dt, const Eigen::Isometry3d& world_T_brush,
                               const PaintSurface* surface) {
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("Brush::advance: dt must be positive");
  BrushEventStats stats;
  const Eigen::Isometry3d start = skeleton_.handlePose();
  const Eigen::Quaterniond q0(start.linear()), q1(world_T_brush.linear());
  stats.substeps = std::max(1, int(std::ceil(dt / preset_.time_step - 1e-9)));
  const double h = dt / stats.substeps;
  const int every = std::max(1, int(std::ceil(double(stats.substeps) / options_.collision_passes)));
  if (surface && options_.plane_proxy)  // masses not queried since the reset get their tangent plane first
    for (int node = skeleton_.handleCount(); node < skeleton_.nodeCount(); ++node)
      if (!cache_[node].has_plane) contactOf(node, *surface, &stats);
  for (int s = 1; s <= stats.substeps; ++s) {
    const double t = double(s) / stats.substeps;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = q0.slerp(t, q1).toRotationMatrix();
    pose.translation() = (1 - t) * start.translation() + t * world_T_brush.translation();
    if (s == stats.substeps) pose = world_T_brush;
    skeleton_.step(h, pose);
    if (surface && (s % every == 0 || s == stats.substeps))
      collideActives(*surface, &stats);
    else if (surface && options_.plane_proxy)
      collideWithPlanes();
  }
  handle_contacts_.clear();
  if (surface) {
    collideHandles(*surface, &stats);
  } else {
    active_contacts_.assign(skeleton_.activeCount(), SurfaceContact());
  }
  std::vector<int> colliding;
  std::vector<Vec3> normals;
  for (int a = 0; a < skeleton_.activeCount(); ++a)
    if (active_contacts_[a].inside) colliding.push_back(a), normals.push_back(active_contacts_[a].normal);
  split_ = splitBrush(colliding, normals, preset_.split_angle_deg);
  skin_stale_ = true;
  return stats;
}

SurfaceContact Brush::contactOf(int node, const PaintSurface& surface, BrushEventStats* stats) {
  NodeCache& cache = cache_[node];
  const Vec3& x = skeleton_.positions()[node];
  // Conservative advancement: outside, and no surfel within reach of where it was proven outside.
  if (cache.outside && (x - cache.from).norm() < cache.clearance - 2 * surface.typicalRadius())
    return SurfaceContact();
  std::array<Neighbor, 64>& found = neighbours_;
  const size_t count = neighbour_count_ =
      surface.nearestOriginals(x, size_t(preset_.collision_neighbors), found.data());
  ++stats->queries;
  const SurfaceContact c = forceShade(surface.originals(), x, found.data(), count);
  cache.outside = !c.inside;
  cache.from = x;
  cache.clearance = count > 0 ? std::sqrt(found[0].sq_dist) : 0.0;
  cache.has_plane = count > 0;
  cache.plane_point = x + c.depth * c.normal;
  cache.plane_normal = c.normal;
  return c;
}

void Brush::collideActives(const PaintSurface& surface, BrushEventStats* stats) {
  for (int a = 0; a < skeleton_.activeCount(); ++a) {
    const int node = skeleton_.handleCount() + a;
    const Vec3 x = skeleton_.positions()[node];
    const SurfaceContact c = contactOf(node, surface, stats);
    if (c.inside) {
      stats->deepest = std::max(stats->deepest, c.depth);
      // (5.5); near an edge the blended normal leaves the mass inside after one projection (by up to 0.3 d at
      // a right angle), so it is repeated with the same neighbours while the mass is inside.
      Vec3 y = x + c.depth * c.normal;
      for (int k = 1; k < kProjectionIterations; ++k) {
        const SurfaceContact again = forceShade(surface.originals(), y, neighbours_.data(), neighbour_count_);
        if (!again.inside) break;
        y += again.depth * again.normal;
      }
      skeleton_.projectActive(node, y, c.normal);
      cache_[node].plane_point = y;
      ++stats->projected;
    }
    active_contacts_[a] = c;  // the pre-projection contact: which masses touch and the surface normal there
  }
}

void Brush::collideWithPlanes() {
  const double reach = options_.proxy_reach * preset_.bristle_length;
  for (int node = skeleton_.handleCount(); node < skeleton_.nodeCount(); ++node) {
    const NodeCache& cache = cache_[node];
    const Vec3& x = skeleton_.positions()[node];
    if (!cache.has_plane) continue;
    const double depth = cache.plane_normal.dot(cache.plane_point - x);
    if ((x - cache.plane_point + depth * cache.plane_normal).norm() > reach) continue;  // too far along it
    if (depth > 0) skeleton_.projectActive(node, x + depth * cache.plane_normal, cache.plane_normal);
  }
}

void Brush::collideHandles(const PaintSurface& surface, BrushEventStats* stats) {
  for (int i = 0; i < skeleton_.handleCount(); ++i) {
    const SurfaceContact c = contactOf(i, surface, stats);
    if (c.inside) handle_contacts_.push_back({i, c.depth, c.normal, skeleton_.positions()[i]});
  }
}

}  // namespace rc
