// The geometric error of a generated mesh against the surfels it approximates (thesis 6.1): distances both
// ways, surfel centres -> mesh (exact, CGAL's AABB tree of the triangles) and mesh -> surfels (at
// area-uniform samples of the mesh, the nearest of the surfel discs around), as the symmetric Hausdorff
// distance and the RMS, absolute and relative to the surfels' bounding box diagonal (the convention of Metro
// and MeshLab).
#pragma once

#include <cstddef>

#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

struct GeometricError {
  double diagonal = 0;                                    ///< of the surfels' bounding box [m]
  double hausdorff = 0, rms = 0;                          ///< symmetric, relative to the diagonal
  double points_to_mesh_max = 0, points_to_mesh_rms = 0;  ///< [m]
  double mesh_to_points_max = 0, mesh_to_points_rms = 0;  ///< [m], over the samples
  size_t samples = 0;                                     ///< mesh samples taken
};

/// `samples` area-uniform points on the mesh (deterministic); 0: as many as there are surfels. Throws
/// std::invalid_argument for an empty mesh or cloud, non-finite input; std::runtime_error without CGAL.
GeometricError geometricError(const TriangleMesh& mesh, const SurfelCloud& surfels, size_t samples = 0);

}  // namespace rc
