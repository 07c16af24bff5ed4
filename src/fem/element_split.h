// Splitting polyhedral elements by a plane (thesis 9.3.1), shared by the plane cut, the progressive polygon
// cut (9.3.2) and the random-plane mesh builder. Nodes carry a side of the plane (-1, 0: on it, +1); every
// mesh edge the plane crosses gets one node, shared by all faces using the edge.
#pragma once

#include <functional>
#include <map>
#include <utility>
#include <vector>

#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {

/// The sorted node ids of a face: the same key for both orientations of a shared face.
std::vector<int> sortedFaceKey(const PolyhedralMesh::Face& face);

/// Which sides of the plane an element has nodes strictly on.
struct ElementSides {
  bool positive = false, negative = false;
  bool crossed() const { return positive && negative; }
};
ElementSides elementSides(const PolyhedralMesh::ElementFaces& faces, const std::vector<int>& side);

/// One node per edge (a, b) crossed by the plane, created on first request.
class EdgeCrossingNodes {
 public:
  /// add_node(a, b, t) with a < b creates the node at (1 - t) x_a + t x_b and returns its id; t comes from
  /// the signed plane distances (one per node, held by the caller, which add_node extends).
  using AddNode = std::function<int(int a, int b, double t)>;
  EdgeCrossingNodes(const std::vector<double>& distance, AddNode add_node);
  /// The node on edge (a, b), created if new.
  int operator()(int a, int b);
  /// The node on edge (a, b), -1 if none was created.
  int find(int a, int b) const;
  int size() const { return static_cast<int>(nodes_.size()); }

 private:
  const std::vector<double>& distance_;
  AddNode add_node_;
  std::map<std::pair<int, int>, int> nodes_;
};

/// A face split by the plane: positive keeps the nodes with side >= 0, negative those with side <= 0, both
/// get the crossing node of every edge whose ends lie on opposite sides.
struct FaceSplit {
  PolyhedralMesh::Face positive, negative;
  bool has_positive = false, has_negative = false;  // some node strictly on that side
};

/// on_plane (optional) receives the face's nodes on the plane and its crossing nodes in face order.
FaceSplit splitFace(const PolyhedralMesh::Face& face, const std::vector<int>& side,
                    EdgeCrossingNodes& crossing, std::vector<int>* on_plane = nullptr);

/// An element split into its two convex parts.
struct ElementSplit {
  PolyhedralMesh::ElementFaces negative, positive;  // the parts' faces, each closed by the section last
  /// Per part face: the element face it came from (-1: the section).
  std::vector<int> negative_source, positive_source;
  std::vector<int> split_faces;  // element faces with nodes strictly on both sides
  PolyhedralMesh::Face section;  // counter-clockwise around the normal: outward for the negative part
  int face_in_plane = -1;        // a face with no node off the plane: the split stopped there (invalid)
};

/// order_section(nodes) returns the positions of the section nodes (on the plane or crossing nodes, first
/// seen first) counter-clockwise around the plane normal.
using SectionOrder = std::function<std::vector<int>(const std::vector<int>& section_nodes)>;

/// Splits the closed face list of one element with nodes strictly on both sides of the plane.
ElementSplit splitElement(const PolyhedralMesh::ElementFaces& faces, const std::vector<int>& side,
                          EdgeCrossingNodes& crossing, const SectionOrder& order_section);

/// The points where the element's face polygons meet the plane (nodes on it and edge intersections, once
/// per face using them), without creating nodes.
std::vector<Vec3> planeSectionPoints(const PolyhedralMesh::ElementFaces& faces, const std::vector<int>& side,
                                     const std::vector<double>& distance, const std::vector<Vec3>& nodes);

}  // namespace rc
