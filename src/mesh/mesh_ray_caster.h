// Closest-hit ray casting against a triangle mesh: a binned-SAH bounding volume hierarchy with flattened
// nodes and Moller-Trumbore triangle tests. Used by the simulated depth sensor for visibility (occlusion).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <vector>

#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

/// A ray origin + t * direction, t in [t_min, t_max]. The direction need not be unit length (t is then in
/// units of |direction|).
struct Ray {
  Vec3 origin = Vec3::Zero();
  Vec3 direction = Vec3::UnitZ();
  double t_min = 0.0;
  double t_max = std::numeric_limits<double>::infinity();
};

/// Closest intersection of a ray with the mesh. The hit point is
/// (1 - u - v) * p0 + u * p1 + v * p2 of triangle `triangle` = {i0, i1, i2}.
struct RayHit {
  static constexpr uint32_t kNoHit = std::numeric_limits<uint32_t>::max();
  double t = std::numeric_limits<double>::infinity();
  uint32_t triangle = kNoHit;  ///< index into TriangleMesh::triangles
  double u = 0.0, v = 0.0;     ///< barycentrics of vertices 1 and 2
  Vec3 normal = Vec3::Zero();  ///< unit geometric normal (p1 - p0) x (p2 - p0), not flipped towards the ray
  bool hit() const { return triangle != kNoHit; }
};

/// BVH over a triangle mesh. The caster references the caller's mesh (for vertex attributes used by callers,
/// see mesh()): the mesh must outlive the caster; geometry is copied at construction, so call rebuild() after
/// the mesh changes. All queries are const and thread-safe.
class MeshRayCaster {
 public:
  struct Options {
    int max_leaf_size = 4;  ///< triangles per leaf (at most)
    int sah_bins = 16;      ///< centroid bins per axis for the SAH split search
  };

  /// Throws std::invalid_argument if a triangle references a vertex that does not exist or a vertex position
  /// is not finite.
  explicit MeshRayCaster(const TriangleMesh& mesh);
  MeshRayCaster(const TriangleMesh& mesh, const Options& options);

  void rebuild();
  const TriangleMesh& mesh() const { return *mesh_; }
  size_t triangleCount() const { return triangle_ids_.size(); }
  size_t nodeCount() const { return nodes_.size(); }
  /// Longest root-to-leaf path (number of nodes).
  int depth() const { return depth_; }

  /// Closest hit with t in [ray.t_min, ray.t_max]; returns false (and leaves `hit` as a miss) if none.
  bool intersect(const Ray& ray, RayHit* hit) const;
  /// True if any triangle is hit with t in [ray.t_min, ray.t_max] (shadow/visibility query, stops early).
  bool occluded(const Ray& ray) const;
  /// Closest hits of `count` rays, multi-threaded (OpenMP). hits[i] belongs to rays[i].
  void intersectBatch(const Ray* rays, size_t count, RayHit* hits) const;
  void intersectBatch(const std::vector<Ray>& rays, std::vector<RayHit>& hits) const;

  /// Reference test of one triangle (Moller-Trumbore with a small barycentric tolerance so that rays through
  /// a shared edge or vertex hit at least one of the triangles). Returns true and sets t, u, v if the ray's
  /// line hits the triangle with t in [t_min, t_max].
  static bool intersectTriangle(const Vec3& origin, const Vec3& direction, const Vec3& p0, const Vec3& p1,
                                const Vec3& p2, double t_min, double t_max, double* t, double* u, double* v);

 private:
  struct Node {
    double bounds[2][3];  ///< bounds[0] = lower corner, bounds[1] = upper corner
    uint32_t offset;      ///< leaf: first triangle; inner: index of the second child (the first is this + 1)
    uint32_t count;       ///< leaf: number of triangles; inner: 0
    uint32_t axis;        ///< inner: split axis (the first child holds the smaller centroids)
    uint32_t pad;
  };
  struct TriangleData {  // p0, e1 = p1 - p0, e2 = p2 - p0 in BVH leaf order
    Vec3 p0, e1, e2;
  };
  template <bool kAnyHit>
  bool traverse(const Ray& ray, RayHit* hit) const;

  const TriangleMesh* mesh_;
  Options options_;
  std::vector<Node> nodes_;
  std::vector<TriangleData> triangles_;
  std::vector<uint32_t> triangle_ids_;  ///< leaf order -> index in mesh.triangles
  int depth_ = 0;
};

}  // namespace rc
