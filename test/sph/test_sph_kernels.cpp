#include "relaxed_connectivity/sph/sph_kernels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>

namespace rc {
namespace {

/// int over the support of f(|x|) in `dimension` dimensions, radial Simpson rule.
double radialIntegral(const std::function<double(double)>& f, double h, int dimension,
                      int intervals = 20000) {
  const double dr = h / intervals;
  double sum = 0.0;
  for (int k = 0; k <= intervals; ++k) {
    const double r = k * dr;
    const double shell = dimension == 3 ? 4.0 * M_PI * r * r : 2.0 * M_PI * r;
    const double w = (k == 0 || k == intervals) ? 1.0 : (k % 2 ? 4.0 : 2.0);
    sum += w * shell * f(r);
  }
  return sum * dr / 3.0;
}

class SphKernelsTest : public ::testing::TestWithParam<int> {};

TEST_P(SphKernelsTest, KernelsIntegrateToOne) {  // (8.1)
  const int dim = GetParam();
  for (double h : {0.05, 1.0, 3.0}) {
    const SphKernels k(dim, h);
    EXPECT_NEAR(radialIntegral([&](double r) { return k.poly6(r * r); }, h, dim), 1.0, 1e-10) << "h " << h;
    EXPECT_NEAR(radialIntegral([&](double r) { return k.spiky(r); }, h, dim), 1.0, 1e-10) << "h " << h;
  }
}

TEST_P(SphKernelsTest, LatticeSumOfPoly6IsOne) {
  const int dim = GetParam();
  const double h = 1.0, dx = 0.02;
  const SphKernels k(dim, h);
  const Vec3 offset(0.0037, -0.0071, dim == 3 ? 0.0013 : 0.0);  // off-lattice evaluation point
  const int n = static_cast<int>(h / dx) + 2;
  double sum = 0.0;
  for (int c = (dim == 3 ? -n : 0); c <= (dim == 3 ? n : 0); ++c)
    for (int b = -n; b <= n; ++b)
      for (int a = -n; a <= n; ++a) sum += k.poly6((Vec3(a * dx, b * dx, c * dx) - offset).squaredNorm());
  EXPECT_NEAR(sum * std::pow(dx, dim), 1.0, 1e-4);
}

TEST_P(SphKernelsTest, ViscosityLaplacianMakesTheSphLaplacianOfAQuadraticExact) {
  // (1 / (2 dim)) int L(r) r^2 dV = 1  <=>  sum_j L_ij (f_j - f_i) V_j = lap f = 2 dim for f = |x|^2.
  const int dim = GetParam();
  const double h = 0.7;
  const SphKernels k(dim, h);
  const double moment = radialIntegral([&](double r) { return k.viscosityLaplacian(r) * r * r; }, h, dim);
  EXPECT_NEAR(moment / (2.0 * dim), 1.0, 1e-10);
  EXPECT_GE(k.viscosityLaplacian(0.0), 0.0);
  EXPECT_GE(k.viscosityLaplacian(0.99 * h), 0.0);
}

TEST_P(SphKernelsTest, DerivativesMatchFiniteDifferences) {
  const int dim = GetParam();
  const double h = 0.8, eps = 1e-6;
  const SphKernels k(dim, h);
  for (double d = 0.01; d < h - 2 * eps; d += 0.037) {
    const double fd_poly6 = (k.poly6((d + eps) * (d + eps)) - k.poly6((d - eps) * (d - eps))) / (2 * eps);
    const double fd_spiky = (k.spiky(d + eps) - k.spiky(d - eps)) / (2 * eps);
    EXPECT_NEAR(k.poly6Derivative(d), fd_poly6, 1e-6 * (1 + std::abs(fd_poly6))) << d;
    EXPECT_NEAR(k.spikyDerivative(d), fd_spiky, 1e-6 * (1 + std::abs(fd_spiky))) << d;
    const double fd2_poly6 = (k.poly6Derivative(d + eps) - k.poly6Derivative(d - eps)) / (2 * eps);
    const double fd2_spiky = (k.spikyDerivative(d + eps) - k.spikyDerivative(d - eps)) / (2 * eps);
    EXPECT_NEAR(k.poly6SecondDerivative(d), fd2_poly6, 1e-5 * (1 + std::abs(fd2_poly6))) << d;
    EXPECT_NEAR(k.spikySecondDerivative(d), fd2_spiky, 1e-5 * (1 + std::abs(fd2_spiky))) << d;
  }
}

TEST_P(SphKernelsTest, GradientsAndLaplacianMatchFiniteDifferencesOfTheField) {
  const int dim = GetParam();
  const double h = 0.5, eps = 1e-5;
  const SphKernels k(dim, h);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uni(-0.35, 0.35);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 r(uni(rng), uni(rng), dim == 3 ? uni(rng) : 0.0);
    if (r.norm() >= h - 2 * eps || r.norm() < 0.01) continue;
    Vec3 fd_poly6 = Vec3::Zero(), fd_spiky = Vec3::Zero();
    double lap = 0.0;
    for (int a = 0; a < dim; ++a) {
      Vec3 e = Vec3::Zero();
      e[a] = eps;
      const double wp = k.poly6((r + e).squaredNorm()), wm = k.poly6((r - e).squaredNorm());
      fd_poly6[a] = (wp - wm) / (2 * eps);
      fd_spiky[a] = (k.spiky((r + e).norm()) - k.spiky((r - e).norm())) / (2 * eps);
      lap += (wp - 2 * k.poly6(r.squaredNorm()) + wm) / (eps * eps);
    }
    EXPECT_LT((k.poly6Gradient(r) - fd_poly6).norm(), 1e-6 * (1 + fd_poly6.norm()));
    EXPECT_LT((k.spikyGradient(r) - fd_spiky).norm(), 1e-6 * (1 + fd_spiky.norm()));
    EXPECT_NEAR(k.poly6Laplacian(r.squaredNorm()), lap, 1e-3 * (1 + std::abs(lap)));
  }
}

TEST_P(SphKernelsTest, SymmetricAndCompactlySupported) {
  const int dim = GetParam();
  const double h = 0.3;
  const SphKernels k(dim, h);
  const Vec3 r(0.1, -0.07, dim == 3 ? 0.05 : 0.0);
  EXPECT_EQ(k.poly6(r.squaredNorm()), k.poly6((-r).squaredNorm()));
  EXPECT_EQ(k.poly6Gradient(r), Vec3(-k.poly6Gradient(-r)));  // exactly antisymmetric
  EXPECT_EQ(k.spikyGradient(r), Vec3(-k.spikyGradient(-r)));
  EXPECT_GT(k.poly6(0.0), 0.0);
  EXPECT_GT(k.spiky(0.0), 0.0);
  for (double d : {h, h * (1 + 1e-12), 1.5 * h, 10.0 * h}) {
    EXPECT_EQ(k.poly6(d * d), 0.0);
    EXPECT_EQ(k.spiky(d), 0.0);
    EXPECT_EQ(k.poly6Derivative(d), 0.0);
    EXPECT_EQ(k.spikyDerivative(d), 0.0);
    EXPECT_EQ(k.viscosityLaplacian(d), 0.0);
    EXPECT_EQ(k.poly6Laplacian(d * d), 0.0);
    EXPECT_EQ(k.poly6Gradient(Vec3(d, 0, 0)), Vec3::Zero());
    EXPECT_EQ(k.spikyGradient(Vec3(0, d, 0)), Vec3::Zero());
  }
  // The kernels decrease outwards: grad W(r) is anti-parallel to r.
  EXPECT_LT(k.poly6Gradient(r).dot(r), 0.0);
  EXPECT_LT(k.spikyGradient(r).dot(r), 0.0);
  EXPECT_EQ(k.spikyGradient(Vec3::Zero()), Vec3::Zero());
}

INSTANTIATE_TEST_SUITE_P(Dimensions, SphKernelsTest, ::testing::Values(2, 3));

TEST(SphKernels, Normalisations2DAnd3D) {
  const double h = 0.2;
  EXPECT_DOUBLE_EQ(SphKernels(3, h).poly6(0.0), 315.0 / (64.0 * M_PI * h * h * h));  // (C.1)
  EXPECT_DOUBLE_EQ(SphKernels(2, h).poly6(0.0), 4.0 / (M_PI * h * h));               // (C.4)
  EXPECT_DOUBLE_EQ(SphKernels(3, h).spiky(0.0), 15.0 / (M_PI * h * h * h));          // (C.7)
  EXPECT_DOUBLE_EQ(SphKernels(2, h).spiky(0.0), 10.0 / (M_PI * h * h));  // (C.10) with 10, see header
}

TEST(SphKernels, RejectsBadInput) {
  EXPECT_THROW(SphKernels(1, 0.1), std::invalid_argument);
  EXPECT_THROW(SphKernels(4, 0.1), std::invalid_argument);
  EXPECT_THROW(SphKernels(3, 0.0), std::invalid_argument);
  EXPECT_THROW(SphKernels(3, -1.0), std::invalid_argument);
  EXPECT_THROW(SphKernels(2, std::nan("")), std::invalid_argument);
}

}  // namespace
}  // namespace rc
