// Splitting polyhedral elements by a plane (thesis 9.3.1) and separating the mesh along the cut (node
// duplication as in 9.3.2, for a cut through the whole mesh).
#pragma once

#include <vector>

#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/sliver_removal.h"

namespace rc {

struct PlaneCutOptions {
  /// Needle avoidance (9.2): nodes closer than this (relative to the mesh bounding-box diagonal) to the plane
  /// count as lying on it; the cut passes through them instead of creating a new node next to them. The cut
  /// face is then non-planar by up to that distance, and the result's relative tolerance is raised to cover
  /// it (never lowered).
  double snap_relative_distance = 1e-6;
  /// Optional convex polygon in the plane (either orientation; empty: the whole plane). Only crossed
  /// elements whose section with the plane overlaps it are split; crossed neighbours left whole get the new
  /// nodes on their edges and faces shared with split elements split alike (T-junctions, 9.3.1).
  std::vector<Vec3> region;
  /// Thin elements the cut creates are merged into their neighbours (removeCutSlivers); off: they are kept.
  CutSliverOptions slivers;
};

/// The split mesh: every element with nodes strictly on both sides of the plane is replaced by its two
/// convex parts (negative side first); new nodes where the plane crosses element edges are shared by all
/// elements around that edge. Elements the plane only touches (node, edge, face) are kept.
struct PlaneCutResult {
  PolyhedralMesh mesh;
  /// Rest displacements at the nodes of mesh (empty if none were given). A new node at x = (1 - t) x_a +
  /// t x_b on edge (a, b) gets u = (1 - t) u_a + t u_b: the interpolant is linear on element edges.
  std::vector<Vec3> displacements;
  std::vector<int> parent_element;  // per element: its element in the input mesh
  std::vector<int> element_side;    // per element: -1 or +1 (side of the plane it lies on), 0: crossed, whole
  std::vector<int> node_side;       // per node: -1, +1 or 0 (on the plane after snapping)
  int num_split_elements = 0;
  int num_new_nodes = 0;      // edge intersection nodes
  int num_snapped_nodes = 0;  // existing nodes with 0 < |distance| <= snap distance, treated as on the plane
  /// Per node of mesh: weights over the input mesh's nodes that give its values (a crossing node: linear on
  /// its edge; a sliver-plane node: the mean along its two edges; kept nodes: themselves).
  std::vector<NodeStencil> node_stencils;
  /// Thin cut elements merged after the cut (PlaneCutOptions::slivers). Element and node counts above are
  /// the split's; the mesh has num_removed fewer elements and the merged nodes dropped.
  CutSliverStats slivers;
};

/// Splits every element of mesh crossed by the plane through plane_point with normal plane_normal (any
/// length). displacements: empty or one per mesh node. Throws std::invalid_argument for a non-finite point,
/// zero or non-finite normal, wrong displacement count, a negative snap distance or a bad region (fewer than
/// 3 points, off the plane, not convex), and
/// std::runtime_error if an element lies entirely within the snap distance of the plane.
PlaneCutResult cutMeshByPlane(const PolyhedralMesh& mesh, const std::vector<Vec3>& displacements,
                              const Vec3& plane_point, const Vec3& plane_normal,
                              const PlaneCutOptions& options = PlaneCutOptions());

/// A cut mesh separated along the plane: every node on the plane (node_side 0) used by elements of both
/// sides is duplicated and the positive-side elements use the copy, so no node is shared across the cut.
/// The combined rest mesh has coincident crack faces, which the PolyhedralMesh constructor rejects as
/// non-conforming, so it is returned as raw arrays plus one validated PolyhedralMesh per side.
struct SeparatedMesh {
  std::vector<Vec3> nodes;                             // split mesh nodes, then the duplicates
  std::vector<Vec3> displacements;                     // empty if the cut had none
  std::vector<PolyhedralMesh::ElementFaces> elements;  // same order as the cut mesh
  std::vector<int> duplicate_of;                       // per duplicate (node numNodes() + k): original
  std::vector<PolyhedralMesh> sides;                   // [0] negative, [1] positive
  std::vector<std::vector<int>> side_node_ids;         // per side: side node -> combined node id
  std::vector<std::vector<int>> side_element_ids;      // per side: side element -> combined element id
  int numDuplicatedNodes() const { return static_cast<int>(duplicate_of.size()); }
};

/// Throws std::invalid_argument if one side of the cut has no elements or an element was left whole across
/// the plane (region-restricted cut; partial cuts that end inside the material: ProgressiveCutMesh,
/// polygon_cut.h).
SeparatedMesh separateAlongPlane(const PlaneCutResult& cut);

/// Values at the nodes of cut.mesh from values at the nodes of `mesh` (the cut's input) through
/// PlaneCutResult::node_stencils (old nodes keep theirs, a new node on edge (a, b) gets the linear
/// interpolation, nodes of merged slivers theirs); without stencils, along the parent element's edges.
std::vector<Vec3> interpolateCutValues(const PolyhedralMesh& mesh, const PlaneCutResult& cut,
                                       const std::vector<Vec3>& values);

}  // namespace rc
