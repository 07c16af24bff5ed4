#include "relaxed_connectivity/fem/element_stiffness.h"

#include <Eigen/Dense>

#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/fem/mean_value_coordinates.h"

namespace rc {

Matrix6d isotropicElasticity(double youngs_modulus, double poisson_ratio) {
  if (!(youngs_modulus > 0.0) || !std::isfinite(youngs_modulus))
    throw std::invalid_argument("isotropicElasticity: Young's modulus must be positive and finite, got " +
                                std::to_string(youngs_modulus));
  if (!(poisson_ratio > -1.0 && poisson_ratio < 0.5))
    throw std::invalid_argument("isotropicElasticity: Poisson ratio must be in (-1, 0.5), got " +
                                std::to_string(poisson_ratio));
  const double lambda =
      youngs_modulus * poisson_ratio / ((1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio));
  const double mu = youngs_modulus / (2.0 * (1.0 + poisson_ratio));
  Matrix6d c = Matrix6d::Zero();
  c.topLeftCorner<3, 3>().setConstant(lambda);
  for (int k = 0; k < 3; ++k) {
    c(k, k) += 2.0 * mu;
    c(k + 3, k + 3) = mu;
  }
  return c;
}

StrainDisplacement strainDisplacement(const NodeGradients& gradients) {
  const int n = static_cast<int>(gradients.rows());
  StrainDisplacement b = StrainDisplacement::Zero(6, 3 * n);
  for (int i = 0; i < n; ++i) {
    const double gx = gradients(i, 0), gy = gradients(i, 1), gz = gradients(i, 2);
    b(0, 3 * i) = gx;
    b(1, 3 * i + 1) = gy;
    b(2, 3 * i + 2) = gz;
    b(3, 3 * i) = gy;  // 2 eps_xy
    b(3, 3 * i + 1) = gx;
    b(4, 3 * i + 1) = gz;  // 2 eps_yz
    b(4, 3 * i + 2) = gy;
    b(5, 3 * i) = gz;  // 2 eps_zx
    b(5, 3 * i + 2) = gx;
  }
  return b;
}

NodeGradients exactIntegratedGradients(const ConvexPolyhedron& element) {
  NodeGradients g = NodeGradients::Zero(element.numNodes(), 3);
  for (const auto& t : element.triangles()) {
    const Vec3 area_normal =
        0.5 * (element.node(t[1]) - element.node(t[0])).cross(element.node(t[2]) - element.node(t[0]));
    for (int v : t) g.row(v) += area_normal.transpose() / 3.0;
  }
  return g;
}

ElementQuadrature elementQuadrature(const ConvexPolyhedron& element,
                                    const ElementQuadratureOptions& options) {
  if (!(options.vertex_sample_blend > 0.0 && options.vertex_sample_blend < 1.0) ||
      !(options.face_sample_blend > 0.0 && options.face_sample_blend < 1.0))
    throw std::invalid_argument("elementQuadrature: sample blends must be in (0, 1), got " +
                                std::to_string(options.vertex_sample_blend) + " and " +
                                std::to_string(options.face_sample_blend));
  const int n = element.numNodes();
  const double volume = element.volume();
  const Vec3& c = element.centroid();
  ElementQuadrature q;
  q.volume = volume;

  // Volumes of the pyramids (boundary triangle, centroid): (9.17), (9.18).
  std::vector<double> pyramid(element.numTriangles());
  q.node_volume_fractions = Eigen::VectorXd::Zero(n);
  for (int t = 0; t < element.numTriangles(); ++t) {
    const auto& tri = element.triangles()[t];
    const Vec3 a = element.node(tri[0]) - c, b = element.node(tri[1]) - c, d = element.node(tri[2]) - c;
    pyramid[t] = a.dot(b.cross(d)) / 6.0;
    for (int v : tri) q.node_volume_fractions[v] += pyramid[t] / (3.0 * volume);
  }

  if (options.tetrahedron_shortcut && element.isTetrahedron()) {
    Eigen::Matrix3d edges;
    for (int k = 0; k < 3; ++k) edges.col(k) = element.node(k + 1) - element.node(0);
    const Eigen::Matrix3d inverse = edges.inverse();  // rows: grad phi_1..3
    NodeGradients g(4, 3);
    g.row(0) = -inverse.colwise().sum();
    g.bottomRows<3>() = inverse;
    q.points.push_back(c);
    q.weights.push_back(volume);
    q.gradients.push_back(g);
    return q;
  }

  const MeanValueCoordinates mvc(element);
  const double min_weight = 1e-14 * volume;
  for (int i = 0; i < n; ++i) {
    const double w = 0.5 * q.node_volume_fractions[i] * volume;  // (9.19)
    if (w <= min_weight) continue;
    q.points.push_back(options.vertex_sample_blend * element.node(i) +
                       (1.0 - options.vertex_sample_blend) * c);
    q.weights.push_back(w);
  }
  for (int t = 0; t < element.numTriangles(); ++t) {
    const double w = 0.5 * pyramid[t];
    if (w <= min_weight) continue;
    const auto& tri = element.triangles()[t];
    const Vec3 center = (element.node(tri[0]) + element.node(tri[1]) + element.node(tri[2])) / 3.0;
    q.points.push_back(options.face_sample_blend * center + (1.0 - options.face_sample_blend) * c);
    q.weights.push_back(w);
  }
  // Normalise so that the weights sum to V exactly (dropped zero-weight samples, rounding).
  double weight_sum = 0.0;
  for (double w : q.weights) weight_sum += w;
  for (double& w : q.weights) w *= volume / weight_sum;

  Eigen::VectorXd lambda;
  NodeGradients sampled = NodeGradients::Zero(n, 3);
  q.gradients.resize(q.points.size());
  for (size_t s = 0; s < q.points.size(); ++s) {
    mvc.evaluate(q.points[s], lambda, q.gradients[s]);
    sampled += q.weights[s] * q.gradients[s];
  }
  if (options.exact_gradient_correction) {
    const NodeGradients correction = (exactIntegratedGradients(element) - sampled) / volume;
    for (NodeGradients& g : q.gradients) g += correction;
  }
  return q;
}

Eigen::MatrixXd elementStiffness(const ElementQuadrature& quadrature, const Matrix6d& elasticity) {
  if (quadrature.gradients.empty())
    throw std::invalid_argument("elementStiffness: the quadrature has no samples");
  const int dofs = 3 * static_cast<int>(quadrature.gradients.front().rows());
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(dofs, dofs);
  for (size_t s = 0; s < quadrature.gradients.size(); ++s) {
    const StrainDisplacement b = strainDisplacement(quadrature.gradients[s]);
    const Eigen::Matrix<double, 6, Eigen::Dynamic> cb = quadrature.weights[s] * (elasticity * b);
    k.noalias() += b.transpose() * cb;
  }
  return 0.5 * (k + k.transpose());  // exact symmetry
}

}  // namespace rc
