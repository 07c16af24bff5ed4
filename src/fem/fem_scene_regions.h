// The boxes of an FEM scene on a body's mesh (keys held, loads, probes): which rest nodes a box holds, the
// consistent nodal forces of a traction on the boundary faces inside a box, and a held region's prescribed
// displacement over time.
#pragma once

#include <Eigen/Core>

#include "relaxed_connectivity/fem/fem_scene.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {

/// r in the closed box [lo, hi] grown by tolerance.
bool inFemBox(const Vec3& r, const Vec3& lo, const Vec3& hi, double tolerance);

/// Nodal forces (3 N) of the traction t (force per rest area) on the mesh's boundary triangles whose three
/// nodes lie in the box: area / 3 t per node of each triangle, which is consistent because the shape
/// functions are linear on the triangulated boundary (9.1.2). `area`: the loaded area (may be null).
Eigen::VectorXd femTractionForces(const PolyhedralMesh& mesh, const Vec3& lo, const Vec3& hi, const Vec3& t,
                                  double tolerance, double* area = nullptr);

}  // namespace rc
