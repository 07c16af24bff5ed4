// Linear elastic element stiffness of a convex polyhedral element (thesis 9.1.2-9.1.3): integration samples
// and weights (9.17)-(9.19), mean value basis gradients at the samples with an exact boundary-integral
// correction (patch test), isotropic constitutive matrix, K_e = sum_q w_q B_q^T C B_q (9.15).
#pragma once

#include <Eigen/Core>

#include <vector>

#include "relaxed_connectivity/fem/convex_polyhedron.h"

namespace rc {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using NodeGradients = Eigen::Matrix<double, Eigen::Dynamic, 3>;  // row i = grad phi_i^T
using StrainDisplacement = Eigen::Matrix<double, 6, Eigen::Dynamic>;

/// Isotropic elasticity matrix C for the Voigt strain (xx, yy, zz, 2xy, 2yz, 2zx) of (9.14). Throws for
/// E <= 0 or nu outside (-1, 0.5).
Matrix6d isotropicElasticity(double youngs_modulus, double poisson_ratio);

/// B (6 x 3n) of (9.14) from basis gradients; dofs ordered (u_x, u_y, u_z) per node.
StrainDisplacement strainDisplacement(const NodeGradients& gradients);

struct ElementQuadratureOptions {
  /// Vertex samples p_i = a x_i + (1 - a) c and face (triangle) samples p_f = b c_f + (1 - b) c (9.1.3).
  double vertex_sample_blend = 0.8;
  double face_sample_blend = 0.9;
  /// Add (G_i^exact - G_i^sampled) / V to every sampled gradient of node i, where G_i^exact =
  /// int_dV phi_i n = sum_{T contains i} (A_T / 3) n_T (phi_i is linear on boundary triangles). Makes the
  /// integrated gradients exact, which the patch test needs; linear precision holds pointwise either way.
  bool exact_gradient_correction = true;
  /// Tetrahedra: one sample at the centroid with the constant linear shape gradients (classic linear FEM).
  bool tetrahedron_shortcut = true;
};

/// Samples of one element: positions, weights w_q (sum = V), basis gradients per sample and the node volume
/// fractions mu_i (9.17) used for lumped masses (9.21).
struct ElementQuadrature {
  std::vector<Vec3> points;
  std::vector<double> weights;
  std::vector<NodeGradients> gradients;
  Eigen::VectorXd node_volume_fractions;  // mu_i, sum = 1
  double volume = 0.0;
};

/// Samples one vertex sample per node with weight mu_i V / 2 and one sample per boundary triangle with weight
/// nu_f V / 2 ((9.17)-(9.19)); tetrahedra use the shortcut unless disabled.
ElementQuadrature elementQuadrature(const ConvexPolyhedron& element,
                                    const ElementQuadratureOptions& options = ElementQuadratureOptions());

/// Exact integrals int_V grad phi_i = sum over boundary triangles containing i of (A_T / 3) n_T (rows).
NodeGradients exactIntegratedGradients(const ConvexPolyhedron& element);

/// K_e (3n x 3n) = sum_q w_q B_q^T C B_q.
Eigen::MatrixXd elementStiffness(const ElementQuadrature& quadrature, const Matrix6d& elasticity);

}  // namespace rc
