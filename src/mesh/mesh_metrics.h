// Topological and integral measures of a triangle mesh (watertightness, enclosed volume, area), used to check
// the procedural models and meshes handed to the scanner.
#pragma once

#include <cstddef>

#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

/// Undirected edges grouped by how many triangles use them.
struct EdgeStatistics {
  size_t edges = 0;                 ///< distinct undirected edges
  size_t boundary_edges = 0;        ///< used by exactly one triangle
  size_t non_manifold_edges = 0;    ///< used by more than two triangles
  size_t misoriented_edges = 0;     ///< used by two triangles that traverse it in the same direction
  size_t degenerate_triangles = 0;  ///< triangles with a repeated vertex index
};

EdgeStatistics edgeStatistics(const TriangleMesh& mesh);
/// Every edge shared by exactly two consistently oriented triangles and no degenerate triangle.
bool isWatertight(const TriangleMesh& mesh);
/// Signed enclosed volume (divergence theorem); positive for a closed mesh with outward (counter-clockwise)
/// winding.
double signedVolume(const TriangleMesh& mesh);
double surfaceArea(const TriangleMesh& mesh);

}  // namespace rc
