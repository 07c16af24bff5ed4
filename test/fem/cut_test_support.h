// Shared by the cut tests: the Fig. 9.9 block and axis-aligned cut quads.
#pragma once

#include <vector>

#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {

/// The Fig. 9.9 block: [0, 3]^3 with 3 x 3 x 3 hexahedral cells (64 nodes, 27 elements).
inline PolyhedralMesh block() {
  return PolyhedralMesh::hexahedralGrid(Vec3(0, 0, 0), Vec3(3, 3, 3), 3, 3, 3);
}

/// Quad in the plane x = x0 covering y in [y0, y1], z in [z0, z1].
inline std::vector<Vec3> quadX(double x0, double y0, double y1, double z0, double z1) {
  return {Vec3(x0, y0, z0), Vec3(x0, y1, z0), Vec3(x0, y1, z1), Vec3(x0, y0, z1)};
}

}  // namespace rc
