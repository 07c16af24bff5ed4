// Fibers (thesis 7.2.1, appendix B): spline, arc length, tangent angle calibration and gradients.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "relaxed_connectivity/shell/shell_fibers.h"
#include "shell_test_support.h"

namespace rc {
namespace {

TEST(ShellFibers, SplineInterpolatesWithNaturalEnds) {
  const Vec3 x1(0, 0, 0), x(1, 0.3, 0.1), x2(2.2, -0.1, 0.4);
  const FiberSpline s = fiberSpline(x1, x, x2);
  EXPECT_LT((s.a1 - x1).norm(), 1e-15);
  EXPECT_LT((s.a1 + s.b1 + s.c1 + s.d1 - x).norm(), 1e-14);
  EXPECT_LT((s.a2 - x).norm(), 1e-15);
  EXPECT_LT((s.a2 + s.b2 + s.c2 + s.d2 - x2).norm(), 1e-14);
  EXPECT_LT((s.b1 + 3.0 * s.d1 - s.b2).norm(), 1e-14);  // C1 at x
  EXPECT_LT((6.0 * s.d1 - 2.0 * s.c2).norm(), 1e-14);   // C2 at x
  EXPECT_LT(s.c1.norm(), 1e-15);                        // f'' = 0 at x1
  EXPECT_LT((2.0 * s.c2 + 6.0 * s.d2).norm(), 1e-14);   // f'' = 0 at x2
  EXPECT_NEAR(fiberArcLength(x1, 0.5 * (x1 + x2), x2), (x2 - x1).norm(), 1e-14);
}

// Three points on a circle of radius r, half-angle phi: the raw spline angle (B.9) reads 3/4 of the true
// turning angle 2 phi (small-phi limit); theta / (3/4 l) is the curvature 1/r.
TEST(ShellFibers, RawTangentAngleIsThreeQuartersOfTheTurningAngle) {
  const double r = 2.0;
  double previous_error = INFINITY;
  for (double phi : {0.2, 0.1, 0.05}) {
    const Vec3 x1(r * std::sin(-phi), 0, r * (1 - std::cos(phi))), x(0, 0, 0),
        x2(r * std::sin(phi), 0, x1.z());
    const double raw = fiberTangentAngle(x1, x, x2);
    const double signed_angle = fiberNormalAngle(x1, x, x2, -Vec3::UnitZ());
    const double kappa = signed_angle / (0.75 * fiberArcLength(x1, x, x2));
    std::printf("phi %.3f: raw / turning %.5f, curvature * r %.5f\n", phi, raw / (2 * phi), kappa * r);
    EXPECT_NEAR(signed_angle, raw, 1e-12);
    EXPECT_NEAR(raw / (2 * phi), 0.75, 0.01);
    const double error = std::abs(kappa * r - 1.0);
    EXPECT_LT(error, 0.01);
    EXPECT_LT(error, previous_error);
    previous_error = error;
  }
  // Bending towards the normal gives a negative angle (7.10).
  EXPECT_LT(fiberNormalAngle(Vec3(-1, 0, 0.1), Vec3::Zero(), Vec3(1, 0, 0.1), Vec3::UnitZ()), 0.0);
}

TEST(ShellFibers, LengthAndAngleGradientsMatchCentralDifferences) {
  const Vec3 pts[3] = {Vec3(-1.0, 0.1, 0.2), Vec3(0.05, 0.0, -0.1), Vec3(0.9, -0.2, 0.3)};
  const Vec3 normal = Vec3(0.1, -0.2, 1.0).normalized();
  std::array<Vec3, 3> gl, gt;
  Vec3 gn;
  fiberArcLength(pts[0], pts[1], pts[2], &gl);
  fiberNormalAngle(pts[0], pts[1], pts[2], normal, &gt, &gn);
  const double eps = 1e-6;
  for (int p = 0; p < 3; ++p) {
    for (int c = 0; c < 3; ++c) {
      Vec3 a[3] = {pts[0], pts[1], pts[2]}, b[3] = {pts[0], pts[1], pts[2]};
      a[p][c] += eps, b[p][c] -= eps;
      EXPECT_NEAR((fiberArcLength(a[0], a[1], a[2]) - fiberArcLength(b[0], b[1], b[2])) / (2 * eps), gl[p][c],
                  1e-8);
      EXPECT_NEAR((fiberNormalAngle(a[0], a[1], a[2], normal) - fiberNormalAngle(b[0], b[1], b[2], normal)) /
                      (2 * eps),
                  gt[p][c], 1e-8);
    }
  }
  for (int c = 0; c < 3; ++c) {
    Vec3 np = normal, nm = normal;
    np[c] += eps, nm[c] -= eps;
    EXPECT_NEAR(
        (fiberNormalAngle(pts[0], pts[1], pts[2], np) - fiberNormalAngle(pts[0], pts[1], pts[2], nm)) /
            (2 * eps),
        gn[c], 1e-8);
  }
}

TEST(ShellFibers, FibersAreDistinctWeightedAndIsotropic) {
  const ShellNodes nodes = shell_test::sphereNodes(0.2);
  const ShellFibers fibers = buildShellFibers(nodes);
  size_t min_count = 1000;
  double worst_moment2 = 0.0, worst_moment4 = 0.0, mean_moment2 = 0.0, mean_unweighted2 = 0.0;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const size_t count = fibers.node_offsets[i + 1] - fibers.node_offsets[i];
    min_count = std::min(min_count, count);
    const Vec3 n = nodes.rest_normals[i];
    const Vec3 u = n.cross(Vec3(0.3, 0.5, 0.8)).normalized(), v = n.cross(u);
    double wsum = 0.0, c2 = 0.0, s2 = 0.0, c4 = 0.0, s4 = 0.0, uc2 = 0.0, us2 = 0.0;
    for (size_t q = fibers.node_offsets[i]; q < fibers.node_offsets[i + 1]; ++q) {
      const Fiber& f = fibers.fibers[q];
      EXPECT_EQ(f.center, i);
      EXPECT_NE(f.end1, f.end2);
      EXPECT_GT(f.weight, 0.0);
      for (size_t r = q + 1; r < fibers.node_offsets[i + 1]; ++r) {
        const Fiber& g = fibers.fibers[r];
        EXPECT_FALSE((g.end1 == f.end1 && g.end2 == f.end2) || (g.end1 == f.end2 && g.end2 == f.end1));
      }
      const Vec3 d = nodes.rest_positions[f.end2] - nodes.rest_positions[f.end1];
      const double a = std::atan2(d.dot(v), d.dot(u));
      wsum += f.weight, c2 += f.weight * std::cos(2 * a), s2 += f.weight * std::sin(2 * a);
      c4 += f.weight * std::cos(4 * a), s4 += f.weight * std::sin(4 * a);
      uc2 += std::cos(2 * a) / count, us2 += std::sin(2 * a) / count;
    }
    EXPECT_NEAR(wsum, 1.0, 1e-12);
    worst_moment2 = std::max(worst_moment2, std::hypot(c2, s2));
    mean_moment2 += std::hypot(c2, s2) / nodes.size();
    mean_unweighted2 += std::hypot(uc2, us2) / nodes.size();
    worst_moment4 = std::max(worst_moment4, std::hypot(c4, s4));
  }
  std::printf(
      "%zu nodes, %zu fibers, min %zu per node, |2nd moment| mean %.4f (unweighted %.4f) worst %.3f, worst "
      "|4th moment| %.3f\n",
      nodes.size(), fibers.size(), min_count, mean_moment2, mean_unweighted2, worst_moment2, worst_moment4);
  EXPECT_GE(min_count, 3u);
  EXPECT_LT(mean_moment2, 0.05);
  EXPECT_LT(mean_moment2, 0.5 * mean_unweighted2);
  EXPECT_LT(worst_moment2, 0.3);  // where the weights are clamped at 0.2 of the mean
}

}  // namespace
}  // namespace rc
