// A convex polyhedral finite element (thesis 9.1.1): nodes, planar faces as outward (counter-clockwise seen
// from outside) polygons and the triangulation of those faces on which the mean value coordinates are
// defined.
#pragma once

#include <array>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// A closed convex polyhedron with its own copy of the node positions (optionally tagged with global node
/// ids). The constructor validates the element and throws std::invalid_argument naming the problem: index out
/// of range, degenerate or non-planar face, open or inconsistently oriented surface (every edge must be
/// shared by exactly two faces with opposite orientation), unused node, inverted (non-positive volume),
/// non-convex (a node outside a face plane) and, for given triangulations, triangles that do not tile their
/// face. Tolerances are relative to the bounding-box diagonal ("scale").
class ConvexPolyhedron {
 public:
  using Face = std::vector<int>;        // local node indices, counter-clockwise seen from outside
  using Triangle = std::array<int, 3>;  // local node indices, counter-clockwise seen from outside
  static constexpr double kDefaultRelativeTolerance = 1e-10;

  /// Faces are fan-triangulated from the apex that maximises the smallest fan triangle (no zero-area
  /// triangles for faces with collinear nodes unless unavoidable). global_node_ids: empty (0..n-1) or one id
  /// per node.
  ConvexPolyhedron(std::vector<Vec3> nodes, std::vector<Face> faces,
                   double relative_tolerance = kDefaultRelativeTolerance,
                   std::vector<int> global_node_ids = {});
  /// Same with a given triangulation per face (face_triangles[f] tiles faces[f]); neighbouring elements must
  /// triangulate shared faces identically for C0 continuity of the shape functions.
  ConvexPolyhedron(std::vector<Vec3> nodes, std::vector<Face> faces,
                   std::vector<std::vector<Triangle>> face_triangles,
                   double relative_tolerance = kDefaultRelativeTolerance,
                   std::vector<int> global_node_ids = {});

  /// Nodes a, b, c, d with positive orientation: det(b - a, c - a, d - a) > 0 (else: inverted, throws).
  static ConvexPolyhedron tetrahedron(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
  /// VTK/Abaqus ordering: 0-3 bottom face counter-clockwise seen from the top, 4-7 the top face above 0-3.
  static ConvexPolyhedron hexahedron(const std::array<Vec3, 8>& corners,
                                     double relative_tolerance = kDefaultRelativeTolerance);
  /// Convex hull of points (brute force, O(n^4); n <= 64 as a guard). Nodes are the points on the hull
  /// boundary: corners and points on hull edges; points inside the hull or strictly inside a hull face are
  /// dropped. globalNodeIds() gives the input index of each node. Coplanar hull facets are merged into one
  /// polygon face. Throws for fewer than 4 non-coplanar points, coincident points or n > 64.
  static ConvexPolyhedron convexHull(const std::vector<Vec3>& points,
                                     double relative_tolerance = kDefaultRelativeTolerance);

  /// This element with other global node ids (one per node) and relative tolerance, its built data copied
  /// without validating again (the geometry is unchanged; e.g. an element a cut left whole). Throws
  /// std::invalid_argument for a wrong id count or a tolerance outside [0, 1e-2).
  ConvexPolyhedron relabelled(std::vector<int> global_node_ids, double relative_tolerance) const;

  int numNodes() const { return static_cast<int>(nodes_.size()); }
  int numFaces() const { return static_cast<int>(faces_.size()); }
  int numTriangles() const { return static_cast<int>(triangles_.size()); }
  const std::vector<Vec3>& nodes() const { return nodes_; }
  const Vec3& node(int i) const { return nodes_[i]; }
  const std::vector<int>& globalNodeIds() const { return global_node_ids_; }
  const std::vector<Face>& faces() const { return faces_; }
  /// Triangulation of all faces; triangleFace()[t] is the face of triangle t.
  const std::vector<Triangle>& triangles() const { return triangles_; }
  const std::vector<int>& triangleFace() const { return triangle_face_; }
  /// Unit outward normal n_f and offset o_f of face f: points y on the face satisfy n_f . y = o_f.
  const Vec3& faceNormal(int f) const { return face_normals_[f]; }
  double faceOffset(int f) const { return face_offsets_[f]; }
  Vec3 faceCentroid(int f) const;  // area centroid of the face polygon

  double volume() const { return volume_; }
  const Vec3& centroid() const { return centroid_; }  // volume centroid
  double scale() const { return scale_; }             // bounding-box diagonal
  double tolerance() const { return tolerance_; }     // absolute: relative_tolerance * scale
  bool isTetrahedron() const { return nodes_.size() == 4 && faces_.size() == 4; }

  /// max_f (n_f . x - o_f): negative inside, 0 on the boundary, positive outside (distance to the farthest
  /// violated face plane).
  double maxFacePlaneDistance(const Vec3& x) const;
  bool contains(const Vec3& x) const { return maxFacePlaneDistance(x) <= tolerance_; }

 private:
  void validateAndBuild(std::vector<std::vector<Triangle>> face_triangles, bool given_triangulation);

  std::vector<Vec3> nodes_;
  std::vector<int> global_node_ids_;
  std::vector<Face> faces_;
  std::vector<Triangle> triangles_;
  std::vector<int> triangle_face_;
  std::vector<Vec3> face_normals_;
  std::vector<double> face_offsets_;
  double relative_tolerance_ = kDefaultRelativeTolerance;
  double scale_ = 0.0, tolerance_ = 0.0, volume_ = 0.0;
  Vec3 centroid_ = Vec3::Zero();
};

}  // namespace rc
