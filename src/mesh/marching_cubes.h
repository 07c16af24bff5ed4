// Marching cubes (Lorensen & Cline 1987, thesis [133]) on a scalar field sampled on a uniform grid: the
// iso-surface as a shared-vertex triangle mesh (the SPH fluid surface, 8.2.7; any implicit surface).
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

/// Scalar values on the nodes of a uniform grid, x fastest: node (i, j, k) is at origin + cell_size (i, j,
/// k).
struct ScalarGrid {
  Vec3 origin = Vec3::Zero();
  double cell_size = 1.0;
  std::array<size_t, 3> dims{{0, 0, 0}};
  std::vector<double> values;

  size_t size() const { return dims[0] * dims[1] * dims[2]; }
  size_t index(size_t i, size_t j, size_t k) const { return i + dims[0] * (j + dims[1] * k); }
  double at(size_t i, size_t j, size_t k) const { return values[index(i, j, k)]; }
  Vec3 node(size_t i, size_t j, size_t k) const {
    return origin + cell_size * Vec3(double(i), double(j), double(k));
  }
};

/// Marching cubes on the iso-surface grid = iso_value; a node is
/// inside where value >= iso_value. The 256-case table is generated here (not copied): on each cube face
/// the crossings are joined so that the inside corners are cut off (on an ambiguous face they stay
/// separated), a rule both cubes sharing the face agree on; the resulting loops are triangulated with
/// diagonals only between vertices on no common face. The mesh is therefore watertight and manifold (every
/// edge in exactly two triangles, oppositely oriented) wherever the iso-surface does not reach the grid
/// boundary. Vertices are shared: one per crossed grid edge, placed by linear interpolation. Triangles
/// are counter-clockwise seen from outside (normals point towards smaller values); vertex normals are
/// -grad(value) (central differences) interpolated along the edge, normalised. Deterministic for any
/// thread count. Throws std::invalid_argument for a non-finite iso_value or a grid whose values do not
/// match its dims.
void marchingCubes(const ScalarGrid& grid, double iso_value, bool compute_normals, int num_threads,
                   TriangleMesh* mesh);

}  // namespace rc
