// Sampling anisotropy of shell nodes (thesis 7.6: highly irregular sampling makes the material anisotropic):
// analytic values on regular grids, the warning on stretched sampling, and clear errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/shell/shell_nodes.h"
#include "shell_test_support.h"

namespace rc {
namespace {

// Rectangular grid of nx x ny points with spacings dx, dy in the plane z = 0, normal +z.
ShellNodes gridNodes(size_t nx, size_t ny, double dx, double dy, size_t neighbor_count = 8) {
  std::vector<Vec3> points, normals;
  for (size_t a = 0; a < nx; ++a) {
    for (size_t b = 0; b < ny; ++b) {
      points.emplace_back(a * dx, b * dy, 0.0);
      normals.push_back(Vec3::UnitZ());
    }
  }
  return shellNodesFromPoints(points, normals, neighbor_count);
}

// Node index of grid point (a, b) as gridNodes orders them.
size_t gridIndex(size_t a, size_t b, size_t ny) {
  return a * ny + b;
}

TEST(ShellSampling, SquareGridIsIsotropicWithoutWarning) {
  const size_t n = 30;
  const ShellNodes nodes = gridNodes(n, n, 0.1, 0.1);
  // Interior node: 4 axis neighbours at h, 4 diagonal ones at h sqrt 2: M = 3 / h^2 I, anisotropy 1.
  EXPECT_NEAR(nodes.sampling_anisotropy[gridIndex(n / 2, n / 2, n)], 1.0, 1e-9);
  // Straight edge: neighbours (+-1, 0), (0, 1), (+-1, 1), (0, 2), (+-2, 0) h: M = diag(3, 1.75) / h^2.
  EXPECT_NEAR(nodes.sampling_anisotropy[gridIndex(n / 2, 0, n)], std::sqrt(3.0 / 1.75), 1e-9);
  std::printf("square grid: median %.4f, worst %.4f, above %.3g: %.4f\n", nodes.sampling.median,
              nodes.sampling.worst, nodes.sampling.threshold, nodes.sampling.fraction_above);
  EXPECT_NEAR(nodes.sampling.median, 1.0, 1e-9);
  EXPECT_LT(nodes.sampling.worst, 3.0);  // corners
  EXPECT_EQ(nodes.sampling.fraction_above, 0.0);
  EXPECT_TRUE(nodes.sampling.warning.empty()) << nodes.sampling.warning;
}

TEST(ShellSampling, HexagonalGridIsIsotropic) {
  std::vector<Vec3> points, normals;
  const size_t n = 24;
  for (size_t a = 0; a < n; ++a) {
    for (size_t b = 0; b < n; ++b) {
      points.emplace_back(a + 0.5 * (b % 2), b * std::sqrt(3.0) / 2.0, 0.0);
      normals.push_back(Vec3::UnitZ());
    }
  }
  const ShellNodes nodes = shellNodesFromPoints(points, normals, 6);
  EXPECT_NEAR(nodes.sampling_anisotropy[(n / 2) * n + n / 2], 1.0, 1e-9);  // 6 neighbours at 60 degrees
  EXPECT_NEAR(nodes.sampling.median, 1.0, 1e-9);
  EXPECT_TRUE(nodes.sampling.warning.empty()) << nodes.sampling.warning;
}

TEST(ShellSampling, ClusteredJitteredSheetHasNoWarning) {
  ShellNodeOptions options;
  options.spacing = 0.08;
  const ShellNodes nodes = selectShellNodes(shell_test::sheetCloud(1.4, 150), options);
  std::printf("clustered sheet: %zu nodes, median %.3f, worst %.3f, above %.3g: %.4f\n", nodes.size(),
              nodes.sampling.median, nodes.sampling.worst, options.anisotropy_threshold,
              nodes.sampling.fraction_above);
  EXPECT_LT(nodes.sampling.median, 1.5);
  EXPECT_GE(nodes.sampling.median, 1.0);
  EXPECT_LE(nodes.sampling.fraction_above, options.irregular_fraction);
  EXPECT_TRUE(nodes.sampling.warning.empty()) << nodes.sampling.warning;
}

TEST(ShellSampling, StretchedGridTriggersTheWarningWithTheMeasuredValue) {
  // dx = 3.3 dy: the 8 nearest are (0, +-1), (0, +-2), (0, +-3) dy and (+-3.3, 0) dy, so
  // M = diag(2 / 3.3^2, 2 (1 + 1/4 + 1/9)) / dy^2 and the anisotropy is sqrt(2.7222 * 3.3^2 / 2) = 3.85.
  const size_t nx = 12, ny = 40;
  const ShellNodes nodes = gridNodes(nx, ny, 0.33, 0.1);
  const double analytic = std::sqrt((1.0 + 0.25 + 1.0 / 9.0) * 3.3 * 3.3);
  EXPECT_NEAR(nodes.sampling_anisotropy[gridIndex(nx / 2, ny / 2, ny)], analytic, 1e-6);
  EXPECT_NEAR(nodes.sampling.median, analytic, 1e-6);
  EXPECT_GT(nodes.sampling.fraction_above, 0.5);
  std::printf("stretched grid: %s\n", nodes.sampling.warning.c_str());
  ASSERT_FALSE(nodes.sampling.warning.empty());
  EXPECT_NE(nodes.sampling.warning.find("highly irregular sampling"), std::string::npos);
  char median[32];
  std::snprintf(median, sizeof median, "median %.3g", analytic);
  EXPECT_NE(nodes.sampling.warning.find(median), std::string::npos) << nodes.sampling.warning;
  // A higher threshold accepts it.
  const ShellSamplingStats relaxed = summarizeShellSampling(nodes, 5.0, 0.02);
  EXPECT_TRUE(relaxed.warning.empty()) << relaxed.warning;
  EXPECT_NEAR(relaxed.median, analytic, 1e-6);
}

TEST(ShellSampling, OneToTenStretchLeavesCollinearNeighboursAndFailsNamingTheAnisotropy) {
  // dx = 10 dy: the 8 nearest neighbours all lie on the node's own grid line: no fan, infinite anisotropy.
  try {
    gridNodes(8, 40, 1.0, 0.1);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("sampling anisotropy inf"), std::string::npos) << what;
    EXPECT_NE(what.find("too irregular"), std::string::npos) << what;
  }
  // With dx = 10.5 dy, 22 neighbours reach the next grid lines: 20 on the own line (+-1 .. +-10 dy) and
  // (+-10.5, 0) dy, so the anisotropy is sqrt(10.5^2 sum_{j<=10} 1/j^2) = 13.07 and the warning reports it.
  const size_t nx = 8, ny = 40;
  const ShellNodes nodes = gridNodes(nx, ny, 1.05, 0.1, 22);
  double sum = 0.0;
  for (int j = 1; j <= 10; ++j) sum += 1.0 / (j * j);
  const double analytic = 10.5 * std::sqrt(sum);
  std::printf("1:10.5 grid, 22 neighbours: %s\n", nodes.sampling.warning.c_str());
  EXPECT_NEAR(nodes.sampling_anisotropy[gridIndex(nx / 2, ny / 2, ny)], analytic, 1e-6);
  EXPECT_GT(nodes.sampling.median, 10.0);
  ASSERT_FALSE(nodes.sampling.warning.empty());
  char median[32];
  std::snprintf(median, sizeof median, "median %.3g", nodes.sampling.median);
  EXPECT_NE(nodes.sampling.warning.find(median), std::string::npos) << nodes.sampling.warning;
}

TEST(ShellSampling, BadThresholdsAreRejected) {
  ShellNodeOptions options;
  options.spacing = 0.1;
  options.anisotropy_threshold = 0.5;
  EXPECT_THROW(selectShellNodes(shell_test::sheetCloud(1.0, 40), options), std::invalid_argument);
  options.anisotropy_threshold = 3.0;
  options.irregular_fraction = 1.5;
  EXPECT_THROW(selectShellNodes(shell_test::sheetCloud(1.0, 40), options), std::invalid_argument);
}

}  // namespace
}  // namespace rc
