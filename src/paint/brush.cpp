#include "relaxed_connectivity/paint/brush.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

namespace {
constexpr int kProjectionIterations = 4;  // projections (5.5) per collision of an active mass
constexpr double kNearSurfaceRadii =
    4;  // farther than this (in surfel radii) only the closest surfel is read
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
  // The handle's bounding sphere (centred on the bounding box of its points).
  const std::vector<Vec3> handles = skeleton_.handleOffsets();
  Vec3 lo = handles.front(), hi = handles.front();
  for (const Vec3& h : handles) lo = lo.cwiseMin(h), hi = hi.cwiseMax(h);
  handle_centre_ = 0.5 * (lo + hi);
  for (const Vec3& h : handles) handle_radius_ = std::max(handle_radius_, (h - handle_centre_).norm());
}

void Brush::reset(const Eigen::Isometry3d& world_T_brush) {
  skeleton_.reset(world_T_brush);
  handle_contacts_.clear();
  active_contacts_.assign(skeleton_.activeCount(), SurfaceContact());
  split_ = BrushSplit();
  cache_.assign(skeleton_.nodeCount(), NodeCache());
  handle_cache_ = NodeCache();
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
  if (surface && surface->id() != cached_surface_) {  // what the caches proved was about another object
    cache_.assign(skeleton_.nodeCount(), NodeCache());
    handle_cache_ = NodeCache();
    cached_surface_ = surface->id();
  }
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
    if (surface && preset_.integrator == BrushIntegrator::kImplicitEuler) setContactPlanes();
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

bool Brush::provenOutside(NodeCache& cache, const Vec3& x, const PaintSurface& surface) const {
  if (!cache.outside) return false;
  const double margin = 2 * surface.typicalRadius();
  // Conservative advancement: no surfel within reach of where it was proven outside.
  if ((x - cache.from).norm() < cache.clearance - margin) return true;
  // No surfel within the distance-transform bound of x either, and the segment from where it was proven
  // outside keeps 2 radii from every surfel ((C + bound - L) / 2 at its worst point): x is on the same side.
  const double bound = surface.clearanceLowerBound(x);
  if (bound > margin && (x - cache.from).norm() < cache.clearance + bound - 2 * margin) {
    cache.from = x;
    cache.clearance = bound;
    return true;
  }
  return false;
}

bool Brush::outsideByClosestSurfel(NodeCache& cache, const Vec3& x, const PaintSurface& surface,
                                   BrushEventStats* stats) const {
  // Outside by the closest surfel (3.9) and clear of the surface: the closest surfel alone proves it (a cheap
  // query) and its tangent plane is the proxy. A node that was near at its last query skips this.
  const double near = kNearSurfaceRadii * surface.typicalRadius();
  if (!cache.outside || cache.clearance <= near) return false;
  const Neighbor closest = surface.closestOriginal(x, cache.closest);
  ++stats->queries;
  const Vec3& p = surface.originals().positions[closest.index];
  const Vec3& n = surface.originals().normals[closest.index];
  const double distance = std::sqrt(closest.sq_dist);
  cache.closest = closest.index;
  if ((x - p).dot(n) < 0 || distance <= near) return false;
  cache.from = x;
  cache.clearance = distance;
  cache.has_plane = true;
  cache.plane_point = p;
  cache.plane_normal = n;
  return true;
}

SurfaceContact Brush::contactOf(int node, const PaintSurface& surface, BrushEventStats* stats) {
  NodeCache& cache = cache_[node];
  const Vec3& x = skeleton_.positions()[node];
  if (provenOutside(cache, x, surface) || outsideByClosestSurfel(cache, x, surface, stats))
    return SurfaceContact();
  // Near or below the surface: force shading over the n nearest (5.2)-(5.4). Below its last tangent plane
  // (a long step pushed it in) the neighbours are looked up at its projection onto that plane: the same n
  // surfels on a plane, near the surface (cheap) instead of deep inside. Only a plane within reach: a plane
  // left from far away would bring the neighbours of another place.
  const SurfelCloud& originals = surface.originals();
  Vec3 query = x;
  if (options_.plane_proxy && cache.has_plane) {
    const double below = cache.plane_normal.dot(cache.plane_point - x);
    const Vec3 projected = x + below * cache.plane_normal;
    if (below > 0 && (projected - cache.plane_point).norm() <= options_.proxy_reach * preset_.bristle_length)
      query = projected;
  }
  std::array<Neighbor, 64>& found = neighbours_;
  const size_t count = neighbour_count_ =
      surface.nearestOriginals(query, size_t(preset_.collision_neighbors), found.data());
  ++stats->queries;
  if (query != x) {  // distances from x for the weights (5.4), nearest first
    for (size_t i = 0; i < count; ++i)
      found[i].sq_dist = (originals.positions[found[i].index] - x).squaredNorm();
    std::sort(found.begin(), found.begin() + count,
              [](const Neighbor& a, const Neighbor& b) { return a.sq_dist < b.sq_dist; });
  }
  const SurfaceContact c = forceShade(originals, x, found.data(), count);
  cache.outside = !c.inside;
  cache.from = x;
  if (count > 0) cache.closest = found[0].index;
  // Clearance from x is proven only by a query at x (one at its projection may miss nearer surfels).
  cache.clearance = count > 0 && query == x ? std::sqrt(found[0].sq_dist) : 0.0;
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

void Brush::setContactPlanes() {
  // The masses touching at the last exact pass stay on their tangent planes through the implicit step.
  std::vector<BrushSkeleton::ContactPlane>& planes = contact_planes_;
  planes.assign(skeleton_.activeCount(), BrushSkeleton::ContactPlane());
  for (int a = 0; a < skeleton_.activeCount(); ++a) {
    const NodeCache& cache = cache_[skeleton_.handleCount() + a];
    if (active_contacts_[a].inside && cache.has_plane)
      planes[a] = {true, cache.plane_point, cache.plane_normal};
  }
  skeleton_.setContactPlanes(planes);
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
  const Vec3 centre = skeleton_.handlePose() * handle_centre_;
  const double margin = handle_radius_ + 2 * surface.typicalRadius();
  NodeCache& cache = handle_cache_;
  if (!cache.outside || (centre - cache.from).norm() >= cache.clearance - margin) {
    const Neighbor closest = surface.closestOriginal(centre, cache.closest);
    cache.closest = closest.index;
    ++stats->queries;
    const SurfelCloud& originals = surface.originals();
    // Outside by the closest surfel (3.9); inside, the per-point test below decides.
    cache.outside = (centre - originals.positions[closest.index]).dot(originals.normals[closest.index]) >= 0;
    cache.from = centre;
    cache.clearance = std::sqrt(closest.sq_dist);
  }
  if (cache.outside && (centre - cache.from).norm() < cache.clearance - margin) return;
  for (int i = 0; i < skeleton_.handleCount(); ++i) {
    const SurfaceContact c = contactOf(i, surface, stats);
    if (c.inside) handle_contacts_.push_back({i, c.depth, c.normal, skeleton_.positions()[i]});
  }
}

}  // namespace rc
