#include "fem/horn_registration.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

Eigen::Matrix4d hornMatrix(const Eigen::Matrix3d& s) {
  // Horn (1987) eq. (4.x): N from the sums S_ab = sum w X'_a x'_b.
  const double sxx = s(0, 0), sxy = s(0, 1), sxz = s(0, 2);
  const double syx = s(1, 0), syy = s(1, 1), syz = s(1, 2);
  const double szx = s(2, 0), szy = s(2, 1), szz = s(2, 2);
  Eigen::Matrix4d n;
  n << sxx + syy + szz, syz - szy, szx - sxz, sxy - syx,  //
      syz - szy, sxx - syy - szz, sxy + syx, szx + sxz,   //
      szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy,  //
      sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz;
  return n;
}

HornRegistration hornRegistration(const Eigen::Ref<const Eigen::VectorXd>& rest,
                                  const Eigen::Ref<const Eigen::VectorXd>& current,
                                  const Eigen::Ref<const Eigen::VectorXd>& weights) {
  HornRegistration result;
  const Eigen::Index n = weights.size();
  double weight_sum = 0.0;
  for (Eigen::Index a = 0; a < n; ++a) {
    result.rest_centroid += weights[a] * rest.segment<3>(3 * a);
    result.current_centroid += weights[a] * current.segment<3>(3 * a);
    weight_sum += weights[a];
  }
  result.rest_centroid /= weight_sum;
  result.current_centroid /= weight_sum;
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (Eigen::Index a = 0; a < n; ++a)
    s.noalias() += weights[a] * (rest.segment<3>(3 * a) - result.rest_centroid) *
                   (current.segment<3>(3 * a) - result.current_centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eigen(hornMatrix(s));
  const Eigen::Vector4d& lambda = eigen.eigenvalues();  // ascending
  const double scale = lambda.cwiseAbs().maxCoeff();
  result.eigenvalue_gap = scale > 0.0 ? (lambda[3] - lambda[2]) / scale : 0.0;
  const Eigen::Vector4d q = eigen.eigenvectors().col(3);
  result.rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  return result;
}

HornRegistration hornRegistration(const std::vector<Vec3>& rest, const std::vector<Vec3>& current,
                                  const Eigen::VectorXd& weights) {
  const size_t n = rest.size();
  if (current.size() != n || static_cast<size_t>(weights.size()) != n || n == 0)
    throw std::invalid_argument("hornRegistration: rest has " + std::to_string(n) + " points, current " +
                                std::to_string(current.size()) + ", weights " +
                                std::to_string(weights.size()) + " (need equal, non-zero counts)");
  double weight_sum = 0.0;
  Eigen::VectorXd rest_flat(3 * n), current_flat(3 * n);
  for (size_t a = 0; a < n; ++a) {
    if (!(weights[a] >= 0.0) || !std::isfinite(weights[a]))
      throw std::invalid_argument("hornRegistration: weight " + std::to_string(a) +
                                  " is negative or not finite");
    if (!rest[a].allFinite() || !current[a].allFinite())
      throw std::invalid_argument("hornRegistration: point " + std::to_string(a) + " is not finite");
    weight_sum += weights[a];
    rest_flat.segment<3>(3 * a) = rest[a];
    current_flat.segment<3>(3 * a) = current[a];
  }
  if (!(weight_sum > 0.0)) throw std::invalid_argument("hornRegistration: all weights are zero");
  return hornRegistration(rest_flat, current_flat, weights);
}

}  // namespace rc
