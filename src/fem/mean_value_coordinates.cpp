#include "relaxed_connectivity/fem/mean_value_coordinates.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace rc {

MeanValueCoordinates::MeanValueCoordinates(const ConvexPolyhedron& element, Options options)
    : element_(element), options_(options) {
  if (!(options_.boundary_relative_tolerance >= 0.0) || !(options_.boundary_gradient_offset > 0.0))
    throw std::invalid_argument(
        "MeanValueCoordinates: boundary_relative_tolerance must be >= 0 and boundary_gradient_offset > 0");
  const double scale = element_.scale();
  for (const auto& t : element_.triangles()) {
    const Vec3& a = element_.node(t[0]);
    const double twice_area = (element_.node(t[1]) - a).cross(element_.node(t[2]) - a).norm();
    if (twice_area > 1e-14 * scale * scale) active_triangles_.push_back(t);  // zero area: no contribution
  }
  use_barycentric_ = options_.tetrahedron_shortcut && element_.isTetrahedron();
  Eigen::Matrix3d edges;
  for (int k = 0; k < 3; ++k) edges.col(k) = element_.node(k + 1) - element_.node(0);
  tet_inverse_ = element_.isTetrahedron() ? Eigen::Matrix3d(edges.inverse()) : Eigen::Matrix3d::Zero();
}

BoundaryContact MeanValueCoordinates::evaluate(const Vec3& x, Eigen::VectorXd& lambda,
                                               Eigen::Matrix<double, Eigen::Dynamic, 3>& gradients) const {
  const int n = numNodes();
  lambda.resize(n);
  gradients.resize(n, 3);
  std::vector<Vec3> g(n);
  const BoundaryContact contact = evaluate(x, lambda.data(), g.data());
  for (int i = 0; i < n; ++i) gradients.row(i) = g[i].transpose();
  return contact;
}

BoundaryContact MeanValueCoordinates::evaluate(const Vec3& x, double* lambda, Vec3* gradients) const {
  // Distance to the nearest face plane (positive inside).
  int nearest_face = -1;
  double nearest = INFINITY, outside = -INFINITY;
  for (int f = 0; f < element_.numFaces(); ++f) {
    const double h = element_.faceOffset(f) - element_.faceNormal(f).dot(x);
    if (std::abs(h) < nearest) {
      nearest = std::abs(h);
      nearest_face = f;
    }
    outside = std::max(outside, -h);
  }
  if (!(outside <= element_.tolerance())) {
    std::ostringstream s;
    s << "MeanValueCoordinates: point (" << x.x() << ", " << x.y() << ", " << x.z() << ") is " << outside
      << " outside the element (tolerance " << element_.tolerance() << ")";
    throw std::domain_error(s.str());
  }
  if (nearest <= options_.boundary_relative_tolerance * element_.scale())
    return evaluateBoundary(x, nearest_face, lambda, gradients);
  if (use_barycentric_) {
    const Vec3 b = tet_inverse_ * (x - element_.node(0));
    lambda[0] = 1.0 - b.sum();
    for (int k = 0; k < 3; ++k) lambda[k + 1] = b[k];
    if (gradients) {
      gradients[0] = -tet_inverse_.colwise().sum().transpose();
      for (int k = 0; k < 3; ++k) gradients[k + 1] = tet_inverse_.row(k).transpose();
    }
    return BoundaryContact::kInterior;
  }
  evaluateInterior(x, lambda, gradients);
  return BoundaryContact::kInterior;
}

void MeanValueCoordinates::weights(const Vec3& x, double* w, Vec3* grad_w) const {
  const int n = numNodes();
  std::fill(w, w + n, 0.0);
  if (grad_w) std::fill(grad_w, grad_w + n, Vec3::Zero());
  for (const auto& t : active_triangles_) {
    Vec3 d[3], c[3];
    double len[3];
    for (int k = 0; k < 3; ++k) {
      d[k] = element_.node(t[k]) - x;
      len[k] = d[k].norm();
    }
    for (int k = 0; k < 3; ++k) c[k] = d[(k + 1) % 3].cross(d[(k + 2) % 3]);
    const double det = d[0].dot(c[0]);  // 6 V_T
    // Edge k (opposite vertex k) joins a = k+1 and b = k+2: angle beta_k, unit normal n_k = c_k / |c_k|.
    Vec3 normal[3], mean = Vec3::Zero();
    double beta[3], inv_c[3];
    for (int k = 0; k < 3; ++k) {
      const double cn = c[k].norm();
      inv_c[k] = 1.0 / cn;
      normal[k] = c[k] * inv_c[k];
      beta[k] = std::atan2(cn, d[(k + 1) % 3].dot(d[(k + 2) % 3]));
      mean += beta[k] * normal[k];
    }
    const double inv_det = 1.0 / det;
    double mc[3];
    for (int j = 0; j < 3; ++j) {
      mc[j] = mean.dot(c[j]);
      w[t[j]] += mc[j] * inv_det;
    }
    if (!grad_w) continue;
    // grad beta_k = (n x u_a)/|d_a| + (u_b x n)/|d_b|; J_{n_k}^T v = g_k x (v - n (n . v)) / |c_k|, g_k = d_a
    // - d_b.
    Vec3 grad_beta[3], g[3];
    for (int k = 0; k < 3; ++k) {
      const int a = (k + 1) % 3, b = (k + 2) % 3;
      grad_beta[k] = normal[k].cross(d[a]) / (len[a] * len[a]) + d[b].cross(normal[k]) / (len[b] * len[b]);
      g[k] = d[a] - d[b];
    }
    const Vec3 grad_det = -(c[0] + c[1] + c[2]);
    for (int j = 0; j < 3; ++j) {
      // grad (m . c_j) = J_m^T c_j + (d_{j+1} - d_{j+2}) x m
      Vec3 grad_mc = (d[(j + 1) % 3] - d[(j + 2) % 3]).cross(mean);
      for (int k = 0; k < 3; ++k) {
        const double nc = normal[k].dot(c[j]);
        grad_mc += nc * grad_beta[k] + (beta[k] * inv_c[k]) * g[k].cross(c[j] - nc * normal[k]);
      }
      grad_w[t[j]] += (grad_mc - (mc[j] * inv_det) * grad_det) * inv_det;
    }
  }
}

void MeanValueCoordinates::evaluateInterior(const Vec3& x, double* lambda, Vec3* gradients) const {
  const int n = numNodes();
  weights(x, lambda, gradients);
  double sum = 0.0;
  Vec3 grad_sum = Vec3::Zero();
  for (int i = 0; i < n; ++i) sum += lambda[i];
  if (gradients)
    for (int i = 0; i < n; ++i) grad_sum += gradients[i];
  const double inv_sum = 1.0 / sum;
  for (int i = 0; i < n; ++i) {
    lambda[i] *= inv_sum;
    if (gradients) gradients[i] = (gradients[i] - lambda[i] * grad_sum) * inv_sum;  // (D.1)
  }
}

BoundaryContact MeanValueCoordinates::evaluateBoundary(const Vec3& x, int face, double* lambda,
                                                       Vec3* gradients) const {
  const int n = numNodes();
  const Vec3& normal = element_.faceNormal(face);
  const Vec3 p = x + (element_.faceOffset(face) - normal.dot(x)) * normal;  // projection onto the face plane
  // Barycentric coordinates of p in the face triangle that contains it best (largest smallest coordinate).
  double best_min = -INFINITY;
  Vec3 best_bary = Vec3::Zero();
  ConvexPolyhedron::Triangle best_triangle{0, 0, 0};
  for (int t = 0; t < element_.numTriangles(); ++t) {
    if (element_.triangleFace()[t] != face) continue;
    const auto& tri = element_.triangles()[t];
    const Vec3 &a = element_.node(tri[0]), &b = element_.node(tri[1]), &c = element_.node(tri[2]);
    const double area = normal.dot((b - a).cross(c - a));
    if (!(area > 0.0)) continue;
    const Vec3 bary(normal.dot((b - p).cross(c - p)) / area, normal.dot((c - p).cross(a - p)) / area, 0.0);
    const Vec3 full(bary[0], bary[1], 1.0 - bary[0] - bary[1]);
    if (full.minCoeff() > best_min) {
      best_min = full.minCoeff();
      best_bary = full;
      best_triangle = tri;
    }
  }
  std::fill(lambda, lambda + n, 0.0);
  // Coordinates below 1e-13 are snapped to 0 (edge or node contact); the rest renormalised.
  int nonzero = 0;
  double kept = 0.0;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(best_bary[k]) <= 1e-13) best_bary[k] = 0.0;
    if (best_bary[k] != 0.0) ++nonzero;
    kept += best_bary[k];
  }
  for (int k = 0; k < 3; ++k) lambda[best_triangle[k]] = best_bary[k] / kept;
  if (gradients) {
    // Inward limit along the ray to the centroid: Richardson extrapolation 2 g(h) - g(2 h).
    const Vec3 direction = (element_.centroid() - x).normalized();
    const double h = options_.boundary_gradient_offset * element_.scale();
    std::vector<double> values(n);
    std::vector<Vec3> far(n);
    evaluate(x + h * direction, values.data(), gradients);
    evaluate(x + 2.0 * h * direction, values.data(), far.data());
    for (int i = 0; i < n; ++i) gradients[i] = 2.0 * gradients[i] - far[i];
  }
  return nonzero == 3   ? BoundaryContact::kFace
         : nonzero == 2 ? BoundaryContact::kEdge
                        : BoundaryContact::kVertex;
}

}  // namespace rc
