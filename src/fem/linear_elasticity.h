// Linear elasticity on a polyhedral mesh (thesis 9.1.2-9.1.4): element stiffness matrices, the assembled
// global stiffness K (9.16), lumped masses (9.21), static solves K U = F with prescribed nodal displacements
// and per-sample stresses.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <vector>

#include "fem/element_stiffness.h"
#include "fem/polyhedral_mesh.h"

namespace rc {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// All three displacement components of a node prescribed (Dirichlet).
struct DisplacementConstraint {
  int node;
  Vec3 displacement;
};

/// Global dofs are (u_x, u_y, u_z) per mesh node: dof 3 i + k.
class LinearElasticModel {
 public:
  /// Throws std::invalid_argument for bad material parameters (isotropicElasticity) or density <= 0.
  LinearElasticModel(PolyhedralMesh mesh, double youngs_modulus, double poisson_ratio, double density = 1.0,
                     const ElementQuadratureOptions& quadrature_options = ElementQuadratureOptions());

  const PolyhedralMesh& mesh() const { return mesh_; }
  int numDofs() const { return 3 * mesh_.numNodes(); }
  const Matrix6d& elasticity() const { return elasticity_; }
  const ElementQuadrature& quadrature(int e) const { return quadratures_[e]; }
  /// K_e in the element's local node order (ConvexPolyhedron::globalNodeIds()).
  const Eigen::MatrixXd& elementStiffness(int e) const { return element_stiffness_[e]; }
  const Eigen::SparseMatrix<double>& stiffness() const { return stiffness_; }
  /// m_i = sum_e mu_i^e V_e rho (9.21).
  const Eigen::VectorXd& lumpedMasses() const { return lumped_masses_; }

  /// Solves K U = F for the free dofs with the constrained nodes held at their displacements (sparse LDLT).
  /// Returns the full displacement vector. Throws std::invalid_argument for a wrong force size, a bad or
  /// repeated node, and std::runtime_error if K restricted to the free dofs is singular (rigid motions not
  /// removed by the constraints).
  Eigen::VectorXd solveStatic(const Eigen::VectorXd& forces,
                              const std::vector<DisplacementConstraint>& constraints) const;

  /// Stress (Voigt: xx, yy, zz, xy, yz, zx) at each integration sample of element e.
  std::vector<Vector6d> elementStresses(int e, const Eigen::VectorXd& displacements) const;

  /// Consistent nodal loads of a constant traction on boundary triangles (global node ids): A_T / 3 per
  /// vertex, exact because the shape functions are linear on boundary triangles.
  Eigen::VectorXd tractionLoads(const std::vector<PolyhedralMesh::Triangle>& triangles,
                                const Vec3& traction) const;

 private:
  PolyhedralMesh mesh_;
  Matrix6d elasticity_;
  std::vector<ElementQuadrature> quadratures_;
  std::vector<Eigen::MatrixXd> element_stiffness_;
  Eigen::SparseMatrix<double> stiffness_;
  Eigen::VectorXd lumped_masses_;
};

}  // namespace rc
