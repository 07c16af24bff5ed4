#include "relaxed_connectivity/fem/horn_registration.h"

#include <Eigen/Cholesky>
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

namespace {

// Weighted centroids into result, cross-covariance S = sum_a w_a (X_a - C)(x_a - c)^T returned.
Eigen::Matrix3d crossCovariance(const Eigen::Ref<const Eigen::VectorXd>& rest,
                                const Eigen::Ref<const Eigen::VectorXd>& current,
                                const Eigen::Ref<const Eigen::VectorXd>& weights, HornRegistration& result) {
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
  return s;
}

void solveHornEigenproblem(const Eigen::Matrix3d& s, HornRegistration& result) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eigen(hornMatrix(s));
  const Eigen::Vector4d& lambda = eigen.eigenvalues();  // ascending
  const double scale = lambda.cwiseAbs().maxCoeff();
  result.eigenvalue_gap = scale > 0.0 ? (lambda[3] - lambda[2]) / scale : 0.0;
  const Eigen::Vector4d q = eigen.eigenvectors().col(3);
  result.rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

constexpr double kMinRelativeDeterminant = 1e-6;
constexpr double kNewtonStepTolerance = 1e-9;
constexpr int kMaxNewtonIterations = 8;

// Newton iterations for the rotation maximising tr(R^T a) from guess; false when they do not apply.
bool newtonRotation(const Eigen::Matrix3d& a, const Eigen::Matrix3d& guess, HornRegistration& result) {
  const double norm = a.norm();
  const double mean_singular = norm / std::sqrt(3.0);
  if (!(norm > 0.0) ||
      !(a.determinant() > kMinRelativeDeterminant * mean_singular * mean_singular * mean_singular))
    return false;
  Eigen::Quaterniond q(guess);
  q.normalize();
  Eigen::Matrix3d r = q.toRotationMatrix();
  for (int iteration = 0; iteration < kMaxNewtonIterations; ++iteration) {
    const Eigen::Matrix3d b = r.transpose() * a;
    const Vec3 g(b(2, 1) - b(1, 2), b(0, 2) - b(2, 0), b(1, 0) - b(0, 1));
    const Eigen::Matrix3d h = b.trace() * Eigen::Matrix3d::Identity() - 0.5 * (b + b.transpose());
    const Eigen::LLT<Eigen::Matrix3d> llt(h);
    if (llt.info() != Eigen::Success) return false;  // not near the maximum
    const Vec3 step = llt.solve(g);
    const double angle = step.norm();
    if (!std::isfinite(angle)) return false;
    if (angle > 0.0) {
      q = q * Eigen::Quaterniond(Eigen::AngleAxisd(angle, step / angle));
      q.normalize();
      r = q.toRotationMatrix();
    }
    if (angle <= kNewtonStepTolerance) {
      const Eigen::Matrix3d b_final = r.transpose() * a;
      const Eigen::Matrix3d symmetric = 0.5 * (b_final + b_final.transpose());
      const double trace = symmetric.trace();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
      eigen.computeDirect(symmetric, Eigen::EigenvaluesOnly);
      // The maximum (det A > 0): B = R^T A symmetric positive definite; other critical points are not.
      if (!(trace > 0.0) || !(eigen.eigenvalues()[0] > 0.0)) return false;
      result.rotation = r;
      result.eigenvalue_gap = 2.0 * (trace - eigen.eigenvalues()[2]) / trace;
      return true;
    }
  }
  return false;
}

}  // namespace

HornRegistration hornRegistration(const Eigen::Ref<const Eigen::VectorXd>& rest,
                                  const Eigen::Ref<const Eigen::VectorXd>& current,
                                  const Eigen::Ref<const Eigen::VectorXd>& weights) {
  HornRegistration result;
  solveHornEigenproblem(crossCovariance(rest, current, weights, result), result);
  return result;
}

HornRegistration warmStartedRegistration(const Eigen::Ref<const Eigen::VectorXd>& rest,
                                         const Eigen::Ref<const Eigen::VectorXd>& current,
                                         const Eigen::Ref<const Eigen::VectorXd>& weights,
                                         const Eigen::Matrix3d& guess, bool* used_eigen_solve) {
  HornRegistration result;
  const Eigen::Matrix3d s = crossCovariance(rest, current, weights, result);
  const bool newton = newtonRotation(s.transpose(), guess, result);
  if (!newton) solveHornEigenproblem(s, result);
  if (used_eigen_solve) *used_eigen_solve = !newton;
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
