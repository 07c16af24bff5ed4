// Mesh generation, second step (thesis 6.1): Garland-Heckbert quadric simplification by edge collapses only
// (CGAL Surface_mesh_simplification with the plane-quadric policies), so the topology of the reconstruction
// is kept (CGAL refuses collapses that break the link condition), down to a triangle count or until the next
// collapse would move the surface by more than an error bound.
#pragma once

#include <cstddef>

#include "relaxed_connectivity/convert/stage_progress.h"
#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

struct SimplificationOptions {
  size_t target_triangles = 0;  ///< stop at this many triangles (0: no count bound)
  /// Stop before a collapse whose quadric error (the sum of squared distances of its new vertex to the planes
  /// of the original triangles around it) exceeds max_error^2, max_error as a fraction of the mesh's bounding
  /// box diagonal (0: no error bound). One of the two bounds is required.
  double max_error = 0;
};

struct SimplificationStats {
  size_t input_triangles = 0, triangles = 0;
  size_t collapses = 0;
};

/// The simplified mesh: positions only (the new vertices are placed by the quadrics; normals are the
/// area-weighted triangle normals). Throws std::invalid_argument for a mesh that is not an oriented
/// 2-manifold (possibly with boundary), for no bound, or for non-finite vertices; std::runtime_error without
/// CGAL.
/// `progress` (optional) is called every few thousand collapses with the fraction of the edges removed on
/// the way to the triangle count (or to none, for an error bound alone); returning false throws
/// ConversionCancelled.
TriangleMesh simplifyMesh(const TriangleMesh& mesh, const SimplificationOptions& options,
                          SimplificationStats* stats = nullptr, const StageProgress& progress = nullptr);

}  // namespace rc
