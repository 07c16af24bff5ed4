// Closing the holes of an open triangle surface (e.g. the scanned Stanford bunny, whose base has open
// boundary loops) so that it encloses a volume TetGen can mesh (thesis Fig. 9.10). Each boundary loop is
// filled by the minimum-weight triangulation of Liepa ("Filling holes in meshes", SGP 2003): dynamic
// programming over the loop minimising lexicographically (largest dihedral angle, total area), the dihedral
// angles taken against the surface triangles on the loop and the neighbouring fill triangles. No vertices
// are added (TetGen's quality refinement splits large fill triangles).
#pragma once

#include <vector>

#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

struct HoleFillingStats {
  int holes = 0;                      // boundary loops filled
  int boundary_edges = 0;             // edges used by one triangle before filling
  int added_triangles = 0;            // sum over holes of (loop length - 2)
  int largest_hole = 0;               // loop length
  double max_dihedral_degrees = 0.0;  // largest dihedral angle the fill creates
};

/// The surface with every boundary loop triangulated (consistently oriented with the surface). Throws
/// std::invalid_argument naming the problem for a face index out of range, an edge used twice in the same
/// direction (inconsistent orientation / non-manifold), a boundary vertex on more than one loop, or a loop
/// longer than max_hole_edges (the O(n^3) triangulation would be too slow).
TriangleMesh closeSurfaceHoles(const TriangleMesh& surface, HoleFillingStats* stats = nullptr,
                               int max_hole_edges = 2000);

/// Edges used by exactly one triangle (either direction).
int countBoundaryEdges(const TriangleMesh& surface);

}  // namespace rc
