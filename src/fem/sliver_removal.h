// Element quality, sliver and needle detection and sliver removal by projection onto the sliver plane
// (thesis 9.2): the sliver's nodes are projected onto its least-squares plane, nodes that come too close are
// merged (needle avoidance), the edges in the plane are intersected, the plane is re-tessellated (overlay of
// the sliver's upper and lower faces) and every new face connects the two elements that were attached to
// the old faces it covers. The sliver element disappears; its neighbours keep their identity.
#pragma once

#include <utility>
#include <vector>

#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {

struct ElementQuality {
  double diameter = 0.0;            // largest node-node distance
  double thickness = 0.0;           // min over faces of the farthest node's distance to the face plane
  double relative_thickness = 0.0;  // thickness / diameter (0: planar)
  double relative_min_edge = 0.0;   // shortest edge / diameter
  double volume_ratio = 0.0;        // volume / diameter^3
};

/// Thickness, edges and volume of one element.
ElementQuality elementQuality(const ConvexPolyhedron& element);

/// Shewchuk's naming (9.2): almost planar elements are needles if they have a degenerated (short) edge and
/// slivers otherwise.
enum class ElementDefect { kNone, kSliver, kNeedle };

struct SliverRemovalOptions {
  /// Elements with relative_thickness below this are almost planar (sliver or needle).
  double sliver_relative_thickness = 0.05;
  /// Almost planar elements whose relative_min_edge is below this are needles.
  double needle_relative_edge = 0.1;
  /// Needle avoidance: nodes of the element closer than this (relative to its diameter) after projection onto
  /// the sliver plane are merged into one node.
  double merge_relative_distance = 0.1;
  /// Neighbours deformed by the projection may become slightly non-convex or get slightly non-planar faces
  /// (9.2 accepts this); the result's relative tolerance is raised to cover it, but a removal that would need
  /// more than this is rejected (the element is kept and counted in num_rejected).
  double max_relative_tolerance = 1e-3;
  /// Upper bound on removals (< 0: no bound).
  int max_removals = -1;
};

/// Per element defect of mesh. Throws std::invalid_argument for bad options.
std::vector<ElementDefect> classifyElements(const PolyhedralMesh& mesh,
                                            const SliverRemovalOptions& options = SliverRemovalOptions());

struct SliverRemovalResult {
  PolyhedralMesh mesh;
  /// Rest displacements at the nodes of mesh (empty if none were given): projected nodes keep theirs, merged
  /// nodes get the mean of the merged ones, an intersection node the mean of the linear interpolations along
  /// its two edges (the interpolant is linear on edges).
  std::vector<Vec3> displacements;
  std::vector<int> node_map;        // per input node: its node in mesh (merged nodes share one)
  std::vector<int> parent_element;  // per element of mesh: its element in the input mesh
  int num_slivers_removed = 0;
  int num_needles_removed = 0;
  int num_collapsed_elements = 0;        // neighbours that became flat by node merging and were dropped
  int num_new_nodes = 0;                 // edge intersection nodes in sliver planes
  int num_merged_nodes = 0;              // nodes merged into another node
  int num_rejected = 0;                  // bad elements whose removal was rejected (left in the mesh)
  double max_projection_distance = 0.0;  // largest node move onto a sliver plane
};

/// Repeatedly removes the thinnest sliver or needle (relative_thickness < sliver_relative_thickness) until
/// none is left that can be removed. displacements: empty or one per mesh node. Throws
/// std::invalid_argument for bad options or a wrong displacement count.
SliverRemovalResult removeSlivers(const PolyhedralMesh& mesh, const std::vector<Vec3>& displacements = {},
                                  const SliverRemovalOptions& options = SliverRemovalOptions());

/// Weights (node, weight) that give a derived node's value from earlier nodes' values.
using NodeStencil = std::vector<std::pair<int, double>>;

/// Automatic sliver removal after a cut (9.2 applied to the elements the cut created; 9.3.1: thin parts are
/// snapped to the existing geometry). Quality measure: ElementQuality::relative_thickness = thickness /
/// diameter (thickness: min over faces of the farthest node's distance to the face plane; diameter: largest
/// node distance). A cut element below `relative_thickness` is merged into its neighbours with its flat
/// neighbours. Sliver plane, first that applies: the mesh boundary (surface or crack faces) along the group
/// and parallel to it if that is one plane; the group's large faces on the side without neighbours; its
/// nodes from before the cut if coplanar; least squares. Merged nodes keep the position of a node on that
/// plane, else of a node from before the cut. So the boundary does not move and the volume is kept wherever
/// the boundary is planar. A thin element with no neighbour on either large side (a separated thin sheet)
/// cannot be merged and is kept (rejected), as is one whose neighbours would become invalid.
struct CutSliverOptions {
  bool enabled = true;  ///< off: cuts leave thin elements as they are (the behaviour without removal)
  /// 0.01: a 1e-3 h slice of a cube cell has 7e-4; 1e-2 h slices (7e-3) are merged too, 3e-2 h ones kept.
  double relative_thickness = 0.01;
  double merge_relative_distance = 0.1;  ///< SliverRemovalOptions::merge_relative_distance
  double max_relative_tolerance = 1e-3;  ///< SliverRemovalOptions::max_relative_tolerance
};

/// What the removal after one cut did.
struct CutSliverStats {
  int num_candidates = 0;    ///< elements the cut created (the only ones examined)
  int num_thin = 0;          ///< of these, below the threshold before the removal
  int num_removed = 0;       ///< elements merged away (thin cut elements and flat neighbours)
  int num_rejected = 0;      ///< thin elements kept (nothing to merge into, or invalid neighbours)
  int num_collapsed = 0;     ///< neighbours that became flat by node merging and were dropped
  int num_new_nodes = 0;     ///< edge intersections in sliver planes
  int num_merged_nodes = 0;  ///< nodes merged into another node
  double max_projection_distance = 0.0;
  double relative_tolerance = 0.0;  ///< the changed elements' tolerance (>= the input's)
};

/// Raw mesh arrays edited in place by removeCutSlivers.
struct EditableMesh {
  std::vector<Vec3> nodes;
  std::vector<Vec3> displacements;                     ///< empty or one per node
  std::vector<PolyhedralMesh::ElementFaces> elements;  ///< closed outward polygon surfaces
  std::vector<std::vector<char>> crack_faces;          ///< empty or per element face (crack: 1)
};

/// What removeCutSlivers changed beyond the arrays.
struct CutSliverEdits {
  std::vector<int> kept_elements;     ///< per output element: its input element (removed ones are dropped)
  std::vector<int> node_replacement;  ///< per output node: the node that replaces it (itself if kept)
  std::vector<NodeStencil> new_node_stencils;  ///< per node appended (input nodes first), over earlier nodes
  int num_input_nodes = 0;
};

/// Merges the thin elements among `candidates` (element ids of mesh, the elements a cut created) into their
/// neighbours. Nodes below first_new_node existed before the cut. Cost: the candidates' neighbourhoods plus
/// one linear pass to find node neighbours. Elements are compacted; merged nodes stay in the array unused;
/// new nodes are appended. relative_tolerance: the mesh's (the result's tolerance is at least that).
CutSliverStats removeCutSlivers(EditableMesh& mesh, const std::vector<int>& candidates, int first_new_node,
                                double relative_tolerance, const CutSliverOptions& options,
                                CutSliverEdits* edits = nullptr);

}  // namespace rc
