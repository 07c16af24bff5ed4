// The simulated brush of thesis 5.4: skeleton dynamics, collision of the spring end points with the painted
// object (5.4.1), the skinned brush surface, and splitting (5.4.3). Advanced once per main-loop event with
// the device pose; hands the contact parameters of its handle points to the haptic force loop (5.4.2).
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "relaxed_connectivity/paint/brush_skin.h"
#include "relaxed_connectivity/paint/brush_split.h"
#include "relaxed_connectivity/paint/force_shading.h"

namespace rc {

/// Contact of one handle point: what the force loop needs to evaluate K_p d N - eta d v_t.
struct HandlePointContact {
  int index = 0;                 ///< handle point of the preset
  double depth = 0;              ///< d (5.2) [m] > 0
  Vec3 normal = Vec3::UnitZ();   ///< N (5.3), unit
  Vec3 position = Vec3::Zero();  ///< where d was evaluated (world)
};

struct BrushOptions {
  /// Exact collision passes (kd-tree query + force shading, (5.2)-(5.5)) over the active masses per event;
  /// the last one is at the end of the event. Each costs one query per active mass near the surface.
  int collision_passes = 1;
  /// Between exact passes, every substep also projects each active mass onto the tangent plane of its last
  /// exact contact (one dot product), so bristles slide on the surface instead of sinking into it until the
  /// next pass. Used within `proxy_reach` (a fraction of the bristle length) of that contact, measured along
  /// the plane.
  bool plane_proxy = true;
  double proxy_reach = 0.25;

  /// Throws std::invalid_argument naming the bad option.
  void validate() const;
};

struct BrushEventStats {
  int substeps = 0;
  int queries = 0;     ///< kd-tree queries (handle points: one for all while the handle is clear)
  int projected = 0;   ///< active-mass projections (5.5)
  double deepest = 0;  ///< deepest active mass before its projection [m]
};

class Brush {
 public:
  explicit Brush(const BrushPreset& preset, BrushOptions options = {});

  const BrushPreset& preset() const { return preset_; }
  const BrushSkeleton& skeleton() const { return skeleton_; }
  /// The skin deformed to the current skeleton; skinned on first access after an event (an event whose skin
  /// nobody reads costs no skinning).
  const BrushSkin& skin() const;
  BrushSkin& skin();

  /// Places the brush at rest at `world_T_brush`.
  void reset(const Eigen::Isometry3d& world_T_brush);
  /// One main-loop event: the device moved from the last pose to `world_T_brush` over dt seconds. Steps the
  /// skeleton in preset time steps (the handle follows the interpolated pose), projects colliding active
  /// masses onto the surface (5.5) in `collision_passes` passes, evaluates the handle contacts at the new
  /// pose, splits (5.4.3) and skins. `surface` may be null (free space); another surface than the last
  /// event's starts the query caches afresh. Throws BrushInstability.
  BrushEventStats advance(double dt, const Eigen::Isometry3d& world_T_brush, const PaintSurface* surface);

  /// Handle points inside the object after the last event.
  const std::vector<HandlePointContact>& handleContacts() const { return handle_contacts_; }
  /// Contacts of the active masses (index = active mass) from the last collision pass.
  const std::vector<SurfaceContact>& activeContacts() const { return active_contacts_; }
  /// The split state of the last event (tips hold active-mass indices).
  const BrushSplit& split() const { return split_; }

 private:
  /// What the last exact query of a node proved: outside with no original surfel within `clearance` of
  /// `from` (so it stays outside while it moves less than clearance - margin), and the tangent plane there.
  struct NodeCache {
    bool outside = false;
    Vec3 from = Vec3::Zero();
    double clearance = 0;
    uint32_t closest = 0;  ///< the closest original at the last query (bounds the next search)
    bool has_plane = false;
    Vec3 plane_point = Vec3::Zero(), plane_normal = Vec3::UnitZ();
  };
  /// Force shading at node's position, or none when its cache proves it outside.
  SurfaceContact contactOf(int node, const PaintSurface& surface, BrushEventStats* stats);
  /// Whether the cache proves x outside without a query (updating it from the distance transform).
  bool provenOutside(NodeCache& cache, const Vec3& x, const PaintSurface& surface) const;
  /// Whether x, clear of the surface at its last query, is still outside by its closest surfel (one query).
  bool outsideByClosestSurfel(NodeCache& cache, const Vec3& x, const PaintSurface& surface,
                              BrushEventStats* stats) const;
  void collideActives(const PaintSurface& surface, BrushEventStats* stats);
  void collideWithPlanes();
  void setContactPlanes();
  void collideHandles(const PaintSurface& surface, BrushEventStats* stats);

  BrushPreset preset_;
  BrushOptions options_;
  BrushSkeleton skeleton_;
  mutable BrushSkin skin_;
  mutable bool skin_stale_ = false;
  std::vector<HandlePointContact> handle_contacts_;
  std::vector<SurfaceContact> active_contacts_;
  BrushSplit split_;
  std::vector<NodeCache> cache_;
  std::vector<BrushSkeleton::ContactPlane> contact_planes_;
  // The handle is rigid: one query at the centre of its points proves them all outside while the centre
  // stays within clearance - handle_radius_ of where that query was made.
  NodeCache handle_cache_;
  uint64_t cached_surface_ = 0;        // PaintSurface::id() the caches were built on (0: none)
  Vec3 handle_centre_ = Vec3::Zero();  // brush frame
  double handle_radius_ = 0;
  std::array<Neighbor, 64> neighbours_;  // of the last query (contactOf)
  size_t neighbour_count_ = 0;
};

}  // namespace rc
