#include "relaxed_connectivity/sph/polar_decomposition.h"

#include <gtest/gtest.h>

#include <random>

#include <Eigen/Geometry>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"

namespace rc {
namespace {

using Mat3 = Eigen::Matrix3d;

/// The rotation of the reflection-safe SVD (8.24).
Mat3 svdRotation(const Mat3& a) {
  Mat3 u, v;
  Vec3 sigma;
  rotationSvd(a, 3, u, sigma, v);
  return u * v.transpose();
}

Mat3 randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

// Deformations R S with stretches in [0.5, 2] (and with one negative singular value: inverted): the
// iteration from the identity finds the SVD's rotation to 1e-10.
TEST(PolarDecomposition, MatchesTheSvdRotation) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> stretch(0.5, 2.0);
  double worst = 0.0, worst_inverted = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const bool inverted = trial % 4 == 3;
    const Mat3 v = randomRotation(rng);
    Vec3 s(stretch(rng), stretch(rng), stretch(rng));
    if (inverted) s.z() = -0.3 * s.z();
    const Mat3 a = randomRotation(rng) * v * s.asDiagonal() * v.transpose();
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    ASSERT_TRUE(extractRotation(a, q, 200)) << trial;
    const double error = (q.toRotationMatrix() - svdRotation(a)).norm();
    (inverted ? worst_inverted : worst) = std::max(inverted ? worst_inverted : worst, error);
  }
  std::printf("polar decomposition: worst |R - U V^T| %.2e (inverted: %.2e)\n", worst, worst_inverted);
  EXPECT_LT(worst, 1e-10);
  EXPECT_LT(worst_inverted, 1e-9);
}

// Warm-started from the previous rotation (a small change of the deformation, as between two steps) the
// iteration needs far fewer steps than from the identity.
TEST(PolarDecomposition, WarmStartConvergesInFewIterations) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> small(-0.01, 0.01);
  int cold_total = 0, warm_total = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Mat3 a0 = randomRotation(rng) * (Mat3::Identity() + 0.05 * Mat3::Random());
    Eigen::Quaterniond q0 = Eigen::Quaterniond::Identity();
    ASSERT_TRUE(extractRotation(a0, q0, 200));
    Mat3 delta;
    for (int k = 0; k < 9; ++k) delta(k / 3, k % 3) = small(rng);
    const Mat3 a1 = Eigen::AngleAxisd(0.01, Vec3(1, 2, 3).normalized()).toRotationMatrix() * a0 + delta;
    int cold = 0, warm = 0;
    for (int limit = 1;; ++limit) {  // iterations to convergence: the smallest limit that converges
      Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
      if (extractRotation(a1, q, limit)) break;
      cold = limit;
    }
    for (int limit = 1;; ++limit) {
      Eigen::Quaterniond q = q0;
      if (extractRotation(a1, q, limit)) break;
      warm = limit;
    }
    Eigen::Quaterniond q = q0;
    ASSERT_TRUE(extractRotation(a1, q));
    EXPECT_LT((q.toRotationMatrix() - svdRotation(a1)).norm(), 1e-10);
    cold_total += cold;
    warm_total += warm;
  }
  std::printf("iterations per decomposition: cold %.2f, warm %.2f\n", cold_total / 100.0, warm_total / 100.0);
  EXPECT_LT(warm_total, cold_total / 2);
}

TEST(PolarDecomposition, ReportsNonConvergence) {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  const Mat3 a = Eigen::AngleAxisd(2.5, Vec3(0, 1, 0)).toRotationMatrix() * Vec3(1.0, 0.2, 3.0).asDiagonal();
  EXPECT_FALSE(extractRotation(a, q, 1));
  EXPECT_TRUE(extractRotation(a, q, 200));
  Eigen::Quaterniond nan_q = Eigen::Quaterniond::Identity();
  Mat3 bad = Mat3::Identity();
  bad(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(extractRotation(bad, nan_q));
}

}  // namespace
}  // namespace rc
