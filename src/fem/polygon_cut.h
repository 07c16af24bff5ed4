// Progressive cuts by convex polygons (thesis 9.3.2): a cut surface given as a sequence of convex polygons
// (consecutive ones may share an edge: non-planar cuts) is applied one polygon at a time. Elements crossed by
// the polygon are split by its plane (9.3.1), faces in the plane are split along the polygon edges into
// convex pieces, pieces inside the polygon become crack faces, and nodes are duplicated where the crack
// separates the material around them. Nodes on the crack front keep the material connected (partial cut);
// a crack face without a node that can open gets a node at its centroid (pocket).
#pragma once

#include <utility>
#include <vector>

#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/sliver_removal.h"

namespace rc {

class EdgeCrossingNodes;

struct PolygonCutOptions {
  /// Needle avoidance (9.2): nodes closer than this (relative to the initial mesh bounding-box diagonal) to
  /// a cutting plane or a polygon edge line count as lying on it (no new node next to them).
  double snap_relative_distance = 1e-6;
  /// Thin elements a polygon's split creates are merged into their neighbours after the polygon
  /// (removeCutSlivers; crack faces stay crack faces); off: they are kept.
  CutSliverOptions slivers;
};

/// What one polygon did.
struct PolygonCutStats {
  int num_split_elements = 0;    // elements split by the cutting plane
  int num_new_nodes = 0;         // plane/edge intersections and polygon-edge nodes in the cut plane
  int num_pocket_nodes = 0;      // centroid nodes of crack faces that could not open otherwise
  int num_duplicated_nodes = 0;  // node copies created to open the crack
  int num_new_crack_faces = 0;   // element faces that became crack faces
  CutSliverStats slivers;        // thin split elements merged after the polygon (merged nodes stay unused)
};

/// A polyhedral mesh with internal cracks. Elements are closed polygon surfaces over node ids (outward,
/// counter-clockwise); two elements are connected through a face when both use the same node set and
/// neither marks it as a crack face. Crack faces come in coincident pairs with opposite orientation (one per
/// side) and share at least one node pair only through duplicates; PolyhedralMesh holds a component with an
/// internal crack when its crack faces are listed (componentMesh does); validate() checks the mesh. Crack
/// faces of the input mesh (PolyhedralMesh::crackFaces) stay crack faces, so cuts continue across bodies
/// rebuilt from componentMesh.
class ProgressiveCutMesh {
 public:
  /// displacements: empty or one per node (rest displacements carried through the cuts). Throws
  /// std::invalid_argument for a wrong displacement count or a bad snap distance.
  explicit ProgressiveCutMesh(const PolyhedralMesh& mesh, std::vector<Vec3> displacements = {},
                              const PolygonCutOptions& options = PolygonCutOptions());

  /// Cuts by one convex polygon (>= 3 coplanar points, either orientation). Throws std::invalid_argument
  /// for a non-finite, non-planar or non-convex polygon and std::runtime_error if an element lies within
  /// the snap distance of the plane.
  PolygonCutStats cut(const std::vector<Vec3>& polygon);
  /// Cuts by a sequence of polygons (a blade sweep / tessellated non-planar cut surface).
  std::vector<PolygonCutStats> cutSurface(const std::vector<std::vector<Vec3>>& polygons);

  int numNodes() const { return static_cast<int>(nodes_.size()); }
  int numElements() const { return static_cast<int>(elements_.size()); }
  const std::vector<Vec3>& nodes() const { return nodes_; }
  /// Empty if none were given; new nodes get the interpolant u (linear on edges and on the face triangles
  /// of the mean value interpolant), duplicates copy their original.
  const std::vector<Vec3>& displacements() const { return displacements_; }
  /// Any other per-node field (e.g. velocities) carried the same way: values of the input mesh's nodes in,
  /// values of every node out. Throws std::invalid_argument for a wrong count.
  std::vector<Vec3> interpolateNodeValues(const std::vector<Vec3>& initial_values) const;
  int numInitialNodes() const { return num_initial_nodes_; }
  const PolyhedralMesh::ElementFaces& elementFaces(int e) const { return elements_[e]; }
  bool isCrackFace(int e, int f) const { return crack_[e][f] != 0; }
  int numCrackFaces() const;
  /// Per node: the node it was duplicated from (-1 for an original or cut node).
  const std::vector<int>& duplicateOf() const { return duplicate_of_; }
  int numDuplicatedNodes() const;
  double relativeTolerance() const { return relative_tolerance_; }

  /// Validates the mesh and throws std::logic_error naming the problem: invalid (non-convex, open, ...)
  /// element, a face used by more than two elements or twice with the same orientation, an unopened crack
  /// face pair (shared node set), a boundary (including crack faces) that is not closed, or element volumes
  /// that do not add up to the enclosed volume.
  void validate() const;
  /// Sum of element volumes.
  double volume() const;
  /// Connected components of elements (through shared non-crack faces); returns per element its component.
  /// Cached until the next cut (componentMesh calls it; not for concurrent calls).
  std::vector<int> elementComponents(int* num_components = nullptr) const;
  int numComponents() const;
  /// A validated PolyhedralMesh for component c (its nodes renumbered in order of first use; node_ids
  /// receives the mesh node of each) whose crack faces are listed (PolyhedralMesh::crackFaces), so a
  /// partially cut component is one mesh. input: null or the mesh this one was built from; its elements
  /// that the cuts left unchanged are taken over instead of built and validated again (PolyhedralMesh's
  /// prebuilt elements). Throws std::invalid_argument naming the problem otherwise, or for an input mesh
  /// with another element count.
  PolyhedralMesh componentMesh(int c, std::vector<int>* node_ids = nullptr,
                               const PolyhedralMesh* input = nullptr) const;
  /// Per element: the element of the input mesh it is unchanged from (same faces up to duplicated node
  /// ids), -1 for elements a cut created or changed.
  const std::vector<int>& unchangedInputElements() const { return input_element_; }

 private:
  struct CutState;
  struct CutElements;
  // Phases of cut().
  void selectCrossedElements(CutState& cut) const;
  void splitByPlane(CutState& cut);
  CutElements splitSelectedElements(CutState& cut, EdgeCrossingNodes& plane_crossing);
  void splitSharedFacesOfWholeElements(const CutState& cut, EdgeCrossingNodes& plane_crossing,
                                       CutElements& split) const;
  void splitFacesInPlane(CutState& cut);
  std::vector<std::pair<PolyhedralMesh::Face, char>> clipFaceByPolygon(CutState& cut,
                                                                       const PolyhedralMesh::Face& face);
  void insertEdgeNodes(CutState& cut);
  void removeSliversOfCut(CutState& cut);
  int addNode(const Vec3& x, NodeStencil stencil);
  void duplicateSeparatedNodes(PolygonCutStats& stats);
  int openClosedCracks();

  std::vector<Vec3> nodes_, displacements_;
  std::vector<PolyhedralMesh::ElementFaces> elements_;
  std::vector<std::vector<char>> crack_;  // per element face
  std::vector<int> duplicate_of_;
  std::vector<int> input_element_;  // per element, see unchangedInputElements()
  int num_input_elements_ = 0;
  std::vector<NodeStencil> stencils_;    // per node created after the input mesh's
  mutable std::vector<int> components_;  // elementComponents() of the current mesh; empty after a cut
  mutable int num_components_ = 0;
  int num_initial_nodes_ = 0;
  double snap_distance_ = 0.0, relative_tolerance_ = ConvexPolyhedron::kDefaultRelativeTolerance;
  CutSliverOptions slivers_;
};

}  // namespace rc
