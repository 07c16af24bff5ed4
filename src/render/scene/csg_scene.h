// CSG scenes of thesis 4.3-4.4 from YAML files (config/scenes/*.yaml): analytic patches sampled into surfels,
// a CSG expression over the patch names, texture discontinuities, cameras and rigid patch motion.
//
// Schema (all lengths in metres, angles in degrees, colours 0-255 RGB):
//   name: cube_densities               # optional, default: the file name without extension
//   radius_scale: 1.5                  # optional, surfel radius / lattice covering radius (patch_sampling.h)
//   patches:                           # one entry per patch; patch id = index in this list
//     - name: px                       # [A-Za-z0-9_.]+, unique
//       shape: sphere                  # sphere | ellipsoid | half_space | box_faces
//       center: [0, 0, 0]              # sphere, ellipsoid, box_faces
//       radius: 1                      # sphere
//       semi_axes: [2, 0.5, 0.5]       # ellipsoid
//       half_extents: [1, 1, 1]        # box_faces
//       rotation: {axis: [0, 0, 1], angle: 30}   # ellipsoid, box_faces (optional)
//       point: [0.5, 0, 0]             # half_space: a point of the plane, the centre of the sampled square
//       normal: [1, 0, 0]              # half_space: outward normal (the solid is behind the plane)
//       size: 1                        # half_space: side of the sampled square ...
//       up: [0, 0, 1]                  #   ... whose edges follow `up` (optional)
//       disk_radius: 0.7               # half_space: instead of size/samples, one surfel of this radius
//       samples: 900                   # surfel count (per face for box_faces) ...
//       spacing: 0.02                  #   ... or mean spacing (one of the two, except with disk_radius)
//       color: [200, 200, 200]         # optional
//       motion:                        # optional rigid motion x(t) = pivot + R(axis, w t)(x - pivot) + v t
//         velocity: [0, 0, 0]          #   metres per second
//         angular_velocity: 90         #   degrees per second about `axis` through `pivot`
//         axis: [0, 0, 1]
//         pivot: [0, 0, 0]
//   csg: "ball - (left | right)"       # over patch names (render/csg_tree.h: ! & | - and parentheses)
//   texture_squares:                   # optional sharp texture squares on sphere patches (Fig. 4.6)
//     - name: square                   # name of the discontinuity patch (role 2 surfels)
//       patch: ball                    # a sphere patch
//       direction: [0, -1, 0]          # centre of the square, seen from the sphere centre
//       up: [0, 0, 1]                  # direction of one pair of edges
//       half_angle: 25                 # angular half width: the square is the sphere inside a square pyramid
//       color: [220, 30, 30]
//       spacing: 0.03                  # optional discontinuity surfel spacing (default: about the patch's)
//   cameras:
//     - name: front
//       projection: perspective        # perspective | orthographic
//       width: 640
//       height: 480
//       fov: 40                        # perspective: horizontal field of view
//       view_width: 3                  # orthographic: metres across the image
//       eye: [3, -4, 2]
//       target: [0, 0, 0]
//       up: [0, 0, 1]                  # optional
//       near: 0.01                     # optional
//       far: 1000                      # optional
//
// A texture square on patch P splits P into P (outside, P's colour) and P_<name> (inside, the square's
// colour; both keep the surfels within 0.9 radii of the border so either side covers it) and adds
// texture-discontinuity patches (role 2) on the four pyramid planes, normals out of the pyramid:
// <name>_a0..a3 and their copies <name>_b0..b3 (a patch occurs only once in a CSG tree). P is replaced in the
// CSG expression by
// "((P_<name> | !(a0 & a1 & a2 & a3)) & (P | (b0 & b1 & b2 & b3)))": a fragment of P_<name> survives only
// inside the pyramid, one of P only outside, and neither depends on the (ambiguous) test of one colour patch
// against the other. One patch per plane makes the square's corners exact intersections (Algorithm 4.3).
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_attributes.h"
#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/csg/analytic_csg.h"
#include "relaxed_connectivity/render/csg/csg_tree.h"
#include "relaxed_connectivity/render/splat/camera.h"

namespace rc {

/// Rigid motion x(t) = pivot + R(axis, angular_velocity t)(x - pivot) + velocity t.
struct PatchMotion {
  Vec3 velocity = Vec3::Zero();
  double angular_velocity = 0;  ///< radians per second
  Vec3 axis = Vec3::UnitZ();
  Vec3 pivot = Vec3::Zero();
  bool moves() const { return angular_velocity != 0 || velocity != Vec3::Zero(); }
  Eigen::Isometry3d at(double t) const;
};

/// A sharp texture square on a sphere patch: the sphere inside the pyramid with apex `center` around
/// `direction` whose four planes make the angle half_angle with it.
struct TextureSquare {
  std::string name;
  int sphere_patch = -1;       ///< the outside part (original patch)
  int inside_patch = -1;       ///< P_<name>
  int border_patch = -1;       ///< first of the four role-2 side patches <name>_a0..a3
  int border_copy_patch = -1;  ///< first of their copies <name>_b0..b3
  Vec3 center = Vec3::Zero(), direction = Vec3::UnitZ(), up = Vec3::UnitX();
  double half_angle = 0;  ///< radians
  Rgba color = {255, 0, 0, 255};
  /// True if x (anywhere) is inside the pyramid, i.e. on the square when x is on the sphere.
  bool contains(const Vec3& x) const;
};

struct CsgScenePatch {
  std::string name;
  SurfelRole role = SurfelRole::kSurface;
  bool has_solid = false;  ///< false for texture-discontinuity patches (no analytic solid)
  AnalyticSolid solid;     ///< at t = 0
  PatchMotion motion;
  Rgba color = {200, 200, 200, 255};
  size_t first_surfel = 0, surfel_count = 0;  ///< the patch's surfels are contiguous
};

struct CsgSceneCamera {
  std::string name;
  Camera camera;
};

struct CsgScene {
  std::string name;  ///< from the file (or the file stem)
  std::string path;
  SurfelCloud surfels;  ///< t = 0; normals, radii (+ axes), colours, int32 "patch_id" and "surfel_role"
  std::vector<CsgScenePatch> patches;  ///< index = patch id
  std::string csg_expression;          ///< after texture-square rewriting
  std::string geometry_expression;     ///< as written in the file (texture squares not expanded)
  std::vector<TextureSquare> texture_squares;
  std::vector<CsgSceneCamera> cameras;

  std::map<std::string, int> patchIds() const;
  /// The parsed CSG expression (names -> patch ids).
  CsgTree csgTree() const;
  bool isDynamic() const;
  /// Surfels at time t (moved patches transformed rigidly).
  SurfelCloud atTime(double t) const;
  /// Same as atTime(), writing into `out` (reuses its storage; `out` must be a copy of `surfels`).
  void moveTo(double t, SurfelCloud* out) const;
  /// Analytic solids at time t, index = patch id (texture-discontinuity patches get an empty solid).
  std::vector<AnalyticSolid> solidsAt(double t) const;
  /// Analytic reference of the scene at time t. Throws std::invalid_argument if the CSG uses a patch without
  /// analytic solid (texture squares: use analyticGeometryCaster()).
  AnalyticCsgCaster analyticCaster(double t = 0) const;
  /// The geometry without texture squares: each texture square's parts replaced by the plain sphere patch.
  AnalyticCsgCaster analyticGeometryCaster(double t = 0) const;
};

/// Loads a scene file. Throws std::runtime_error "<path>:<line>:<column>: <problem>" for bad input.
CsgScene loadCsgScene(const std::string& path);
/// Same from YAML text (`source_name` is used in error messages and as the default scene name).
CsgScene parseCsgScene(const std::string& yaml_text, const std::string& source_name);

}  // namespace rc
