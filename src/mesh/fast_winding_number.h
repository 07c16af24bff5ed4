#pragma once
// Fast generalised winding numbers of triangle meshes (Barill et al. 2018), for inside tests of scans.

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

/// Generalised winding number of a triangle mesh (meshWindingNumber of sph_lattice.h) accelerated by a
/// bounding-volume hierarchy with the first-order far field of Barill et al. 2018 ("Fast winding numbers"):
/// a cluster of triangles seen from farther than kFarFactor times its radius contributes the solid angle of
/// its area-weighted normal sum N at its area-weighted centre P, (P - p) . N / |P - p|^3; nearer clusters
/// are split down to leaves of exact solid angles (van Oosterom & Strackee). Open meshes with small holes
/// (scans) still give ~1 inside.
class FastWindingNumber {
 public:
  /// Keeps a reference to `mesh`, which must outlive this object.
  explicit FastWindingNumber(const TriangleMesh& mesh);

  /// The winding number at p: ~1 inside, ~0 outside.
  double operator()(const Vec3& p) const;

 private:
  static constexpr size_t kLeafSize = 8;
  static constexpr double kFarFactor = 2.5;
  struct Node {
    Vec3 center = Vec3::Zero(), normal = Vec3::Zero();
    double radius = 0.0;
    uint32_t begin = 0, end = 0, left = 0, right = 0;  ///< left == 0: a leaf
  };

  /// The node of triangles order_[begin, end) and its subtree (median split on the longest axis).
  uint32_t build(size_t begin, size_t end);

  const TriangleMesh& mesh_;
  std::vector<uint32_t> order_;
  std::vector<Vec3> centroids_, normals_;
  std::vector<Node> nodes_;
};

}  // namespace rc
