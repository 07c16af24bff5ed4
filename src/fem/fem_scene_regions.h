// The boxes of an FEM scene on a body's mesh (keys held, loads, probes): which rest nodes a box holds, the
// consistent nodal forces of a traction on the boundary faces inside a box, and a held region's prescribed
// displacement over time.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "relaxed_connectivity/fem/fem_scene.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {

/// r in the closed box [lo, hi] grown by tolerance.
bool inFemBox(const Vec3& r, const Vec3& lo, const Vec3& hi, double tolerance);
/// Whether a region selects the rest position r: in the box and, for a node set (points non-empty), within
/// tolerance of one of its points.
bool femSelects(const Vec3& lo, const Vec3& hi, const std::vector<Vec3>& points, const Vec3& r,
                double tolerance);
template <class Region>
bool femSelects(const Region& region, const Vec3& r, double tolerance) {
  return femSelects(region.lo, region.hi, region.points, r, tolerance);
}

/// Nodal forces (3 N) of the load's traction (load.force per rest area) on the mesh's boundary triangles
/// whose three nodes the load selects: area / 3 t per node of each triangle, which is consistent because the
/// shape functions are linear on the triangulated boundary (9.1.2). `area`: the loaded area (may be null).
Eigen::VectorXd femTractionForces(const PolyhedralMesh& mesh, const FemLoad& load, double tolerance,
                                  double* area = nullptr);

}  // namespace rc
