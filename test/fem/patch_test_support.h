// The MacNeal-Harder style patch test shared by the FEM tests: boundary nodes prescribed by a linear field,
// interior nodes solved; a consistent discretisation reproduces the field and its constant stress exactly.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <vector>

#include "relaxed_connectivity/fem/linear_elasticity.h"

namespace rc {

/// Patch field u = 1e-3 (2x + y + z) / 2 and cyclic (constant strain), plus kPatchTranslation.
inline Eigen::Matrix3d patchGradient() {
  Eigen::Matrix3d a;
  a << 2, 1, 1, 1, 2, 1, 1, 1, 2;
  return 0.5e-3 * a;
}
inline const Vec3 kPatchTranslation(0.1e-3, -0.2e-3, 0.05e-3);

/// u = a x + b at every node, stacked (3 per node).
inline Eigen::VectorXd nodalField(const PolyhedralMesh& mesh, const Eigen::Matrix3d& a, const Vec3& b) {
  Eigen::VectorXd u(3 * mesh.numNodes());
  for (int i = 0; i < mesh.numNodes(); ++i) u.segment<3>(3 * i) = a * mesh.node(i) + b;
  return u;
}

struct PatchResult {
  double max_displacement_error;  ///< relative to max |u|
  double max_stress_error;        ///< relative to max |sigma|
};

inline PatchResult runPatchTest(const PolyhedralMesh& mesh, const ElementQuadratureOptions& options = {}) {
  const LinearElasticModel model(mesh, 1000.0, 0.3, 1.0, options);
  const Eigen::Matrix3d a = patchGradient();
  const Eigen::VectorXd exact = nodalField(mesh, a, kPatchTranslation);
  std::vector<DisplacementConstraint> constraints;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.isBoundaryNode()[i]) constraints.push_back({i, exact.segment<3>(3 * i)});
  const Eigen::VectorXd u = model.solveStatic(Eigen::VectorXd::Zero(model.numDofs()), constraints);
  PatchResult result;
  result.max_displacement_error = (u - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff();
  const Eigen::Matrix3d strain = 0.5 * (a + a.transpose());
  Vector6d voigt;
  voigt << strain(0, 0), strain(1, 1), strain(2, 2), 2 * strain(0, 1), 2 * strain(1, 2), 2 * strain(2, 0);
  const Vector6d sigma = model.elasticity() * voigt;
  result.max_stress_error = 0.0;
  for (int e = 0; e < mesh.numElements(); ++e)
    for (const Vector6d& s : model.elementStresses(e, u))
      result.max_stress_error = std::max(result.max_stress_error, (s - sigma).cwiseAbs().maxCoeff());
  result.max_stress_error /= sigma.cwiseAbs().maxCoeff();
  return result;
}

inline int countInteriorNodes(const PolyhedralMesh& mesh) {
  return static_cast<int>(std::count(mesh.isBoundaryNode().begin(), mesh.isBoundaryNode().end(), 0));
}

}  // namespace rc
