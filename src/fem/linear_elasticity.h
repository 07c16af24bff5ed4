// Linear elasticity on a polyhedral mesh (thesis 9.1.2-9.1.4): element stiffness matrices, the assembled
// global stiffness K (9.16), lumped masses (9.21), static solves K U = F with prescribed nodal displacements
// and per-sample stresses. After a cut (9.3) only the elements the cut changed need new integration data:
// a model built with a donor (the model of the mesh before the cut) shares the samples, gradients and K_e
// of every element whose rest geometry (node positions, faces, triangulation) is bit-identical.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "relaxed_connectivity/fem/element_stiffness.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Prescribed displacement components of a node (Dirichlet): those with held[k] take displacement[k], the
/// others stay free (a roller or a symmetry plane holds only the normal component).
struct DisplacementConstraint {
  int node;
  Vec3 displacement;
  std::array<bool, 3> held = {true, true, true};
};

/// Integration data of one element: samples, basis gradients and K_e (immutable, shared between models).
struct ElementIntegration {
  ElementQuadrature quadrature;
  Eigen::MatrixXd stiffness;
};

/// Hash of what determines an element's integration data: node positions (bits, local order), faces,
/// triangles with their faces (the tolerance only gates validation and is left out).
std::uint64_t elementGeometryHash(const ConvexPolyhedron& element);
/// Bitwise equality of that data and of the derived volume, centroid, scale and face planes (equal
/// elements give bit-identical integration data).
bool sameElementGeometry(const ConvexPolyhedron& a, const ConvexPolyhedron& b);

/// Global dofs are (u_x, u_y, u_z) per mesh node: dof 3 i + k.
class LinearElasticModel {
 public:
  /// Throws std::invalid_argument for bad material parameters (isotropicElasticity) or density <= 0.
  LinearElasticModel(PolyhedralMesh mesh, double youngs_modulus, double poisson_ratio, double density = 1.0,
                     const ElementQuadratureOptions& quadrature_options = ElementQuadratureOptions());
  /// The same, reusing the integration data of donor elements with identical rest geometry
  /// (sameElementGeometry) when the donor has the same elasticity and quadrature options (else none are
  /// reused). donor may be null.
  LinearElasticModel(PolyhedralMesh mesh, double youngs_modulus, double poisson_ratio, double density,
                     const ElementQuadratureOptions& quadrature_options, const LinearElasticModel* donor);

  const PolyhedralMesh& mesh() const { return mesh_; }
  int numDofs() const { return 3 * mesh_.numNodes(); }
  const Matrix6d& elasticity() const { return elasticity_; }
  const ElementQuadratureOptions& quadratureOptions() const { return quadrature_options_; }
  const ElementQuadrature& quadrature(int e) const { return integration_[e]->quadrature; }
  /// K_e in the element's local node order (ConvexPolyhedron::globalNodeIds()).
  const Eigen::MatrixXd& elementStiffness(int e) const { return integration_[e]->stiffness; }
  /// Elements integrated by this model / taken from the donor.
  int numRecomputedElements() const { return num_recomputed_; }
  int numReusedElements() const { return mesh_.numElements() - num_recomputed_; }
  /// Compressed, full symmetric; every node pair sharing an element has a dense 3 x 3 block.
  const Eigen::SparseMatrix<double>& stiffness() const { return stiffness_; }
  /// Value index in stiffness() of entry (3 ids[a], 3 ids[b]) of element e (ids = globalNodeIds()), for
  /// local nodes a, b at blockValueIndices(e)[b * n + a]; entry (3 ids[a] + r, 3 ids[b] + c) is at that
  /// index + c * columnLength(ids[b]) + r.
  const int* blockValueIndices(int e) const { return block_index_.data() + block_offset_[e]; }
  /// Entries of each of the three stiffness() columns of a node.
  int columnLength(int node) const { return column_length_[node]; }
  /// m_i = sum_e mu_i^e V_e rho (9.21).
  const Eigen::VectorXd& lumpedMasses() const { return lumped_masses_; }

  /// Solves K U = F for the free dofs with the held components at their displacements (sparse LDLT).
  /// Returns the full displacement vector. Throws std::invalid_argument for a wrong force size, a bad node or
  /// a component held twice, and std::runtime_error if K restricted to the free dofs is singular (rigid
  /// motions not removed by the constraints).
  Eigen::VectorXd solveStatic(const Eigen::VectorXd& forces,
                              const std::vector<DisplacementConstraint>& constraints) const;
  /// The forces the constraints exert: K U - F (zero, up to round-off, at free dofs).
  Eigen::VectorXd reactions(const Eigen::VectorXd& displacements, const Eigen::VectorXd& forces) const;

  /// Stress (Voigt: xx, yy, zz, xy, yz, zx) at each integration sample of element e.
  std::vector<Vector6d> elementStresses(int e, const Eigen::VectorXd& displacements) const;

  /// Consistent nodal loads of a constant traction on boundary triangles (global node ids): A_T / 3 per
  /// vertex, exact because the shape functions are linear on boundary triangles.
  Eigen::VectorXd tractionLoads(const std::vector<PolyhedralMesh::Triangle>& triangles,
                                const Vec3& traction) const;

 private:
  PolyhedralMesh mesh_;
  Matrix6d elasticity_;
  void build(double density, const LinearElasticModel* donor);

  ElementQuadratureOptions quadrature_options_;
  std::vector<std::shared_ptr<const ElementIntegration>> integration_;
  int num_recomputed_ = 0;
  Eigen::SparseMatrix<double> stiffness_;
  std::vector<int> block_offset_, block_index_, column_length_;
  Eigen::VectorXd lumped_masses_;
};

}  // namespace rc
