// Force shading (thesis 5.4.1, (5.2)-(5.4)) and the inside test (3.9) against analytic surfaces.
#include "relaxed_connectivity/paint/force_shading.h"

#include <gtest/gtest.h>

#include "paint_test_surfaces.h"

namespace rc {
namespace {

TEST(ForceShading, PlaneGivesTheExactDepthAndNormal) {
  const PaintSurface s(paint_test::planeCloud(0.01, 0.001));
  for (const Vec3& x :
       {Vec3(0.0003, 0.0007, -0.0005), Vec3(-0.0041, 0.002, -0.002), Vec3(0.001, 0.001, -1e-7)}) {
    const SurfaceContact c = forceShade(s, x, 10);
    EXPECT_TRUE(c.inside);
    EXPECT_NEAR(c.depth, -x.z(), 1e-15);
    EXPECT_NEAR((c.normal - Vec3::UnitZ()).norm(), 0.0, 1e-15);
    EXPECT_NEAR(c.normal_length, 1.0, 1e-15);
  }
  const SurfaceContact above = forceShade(s, Vec3(0.0003, 0.0007, 0.0005), 10);
  EXPECT_FALSE(above.inside);
  EXPECT_NEAR(above.depth, -0.0005, 1e-15);
}

TEST(ForceShading, WeightsFollowEquation54) {
  // Three surfels at distances 1, 2, 4 from x: weights (4-1, 4-2, 0) / 5; depths N_i . (x_i - x).
  SurfelCloud c;
  c.positions = {Vec3(0, 0, -1), Vec3(0, 0, -2), Vec3(0, 0, 4)};
  c.normals = {Vec3(0, 0, 1), Vec3(0, 1, 0), Vec3(1, 0, 0)};
  const Neighbor n[3] = {{0, 1.0}, {1, 4.0}, {2, 16.0}};
  const SurfaceContact r = forceShade(c, Vec3::Zero(), n, 3);
  EXPECT_NEAR(r.depth, 0.6 * -1.0 + 0.4 * 0.0 + 0.0, 1e-15);
  EXPECT_NEAR((r.normal * r.normal_length - Vec3(0, 0.4, 0.6)).norm(), 0.0, 1e-15);
  // Equal distances: uniform weights (the sum of (5.4) vanishes).
  const Neighbor equal[2] = {{0, 1.0}, {1, 1.0}};
  const SurfaceContact u = forceShade(c, Vec3::Zero(), equal, 2);
  EXPECT_NEAR((u.normal * u.normal_length - Vec3(0, 0.5, 0.5)).norm(), 0.0, 1e-15);
}

TEST(ForceShading, SphereDepthAndNormalMatchTheAnalyticOnes) {
  const double r = 0.05;
  const PaintSurface s(paint_test::sphereCloud(Vec3::Zero(), r, 40000));  // spacing ~0.9 mm
  double worst_depth = 0, worst_angle = 0;
  for (int i = 0; i < 200; ++i) {
    const Vec3 dir = Vec3(std::sin(0.37 * i) * std::cos(1.3 * i), std::sin(0.37 * i) * std::sin(1.3 * i),
                          std::cos(0.37 * i))
                         .normalized();
    const double depth = 0.0002 + 0.00001 * (i % 50);
    const SurfaceContact c = forceShade(s, (r - depth) * dir, 10);
    EXPECT_TRUE(c.inside);
    worst_depth = std::max(worst_depth, std::abs(c.depth - depth));
    worst_angle = std::max(worst_angle, std::acos(std::min(1.0, c.normal.dot(dir))));
  }
  // The chord sag of a 0.9 mm sampling on a 50 mm sphere is 2e-6 m; the weighted plane adds about as much.
  EXPECT_LT(worst_depth, 1e-5);
  EXPECT_LT(worst_angle, 0.02);  // rad; the neighbourhood spans ~1.5 mm = 0.03 rad of the sphere
}

TEST(ForceShading, NormalTurnsSmoothlyAcrossAConvexEdge) {
  // Slide a point 0.2 mm inside the surface along the top face, around the edge and down the side face.
  const double h = 0.0005, delta = 0.0002;
  const PaintSurface s(paint_test::edgeCloud(0.01, h));
  std::vector<Vec3> path;
  for (double x = -10 * h; x < -delta; x += h / 40) path.push_back(Vec3(x, 0.00013, -delta));
  for (double z = -delta; z > -10 * h; z -= h / 40) path.push_back(Vec3(-delta, 0.00013, z));
  double largest_turn = 0, closest_turn = 0;
  Vec3 previous = forceShade(s, path[0], 10).normal;
  Vec3 previous_closest = s.originals().normals[s.closestOriginal(path[0])];
  for (const Vec3& x : path) {
    const SurfaceContact c = forceShade(s, x, 10);
    largest_turn = std::max(largest_turn, std::acos(std::min(1.0, c.normal.dot(previous))));
    const Vec3 closest = s.originals().normals[c.closest];
    closest_turn = std::max(closest_turn, std::acos(std::min(1.0, closest.dot(previous_closest))));
    previous = c.normal;
    previous_closest = closest;
  }
  EXPECT_NEAR(previous.dot(Vec3::UnitX()), 1.0, 1e-12);  // ends on the side face
  // 90 degrees spread over the path: with the closest surfel's normal it is one 90-degree jump; force shading
  // turns it by less than 3 degrees per step of h / 40.
  EXPECT_NEAR(closest_turn, M_PI / 2, 1e-12);
  EXPECT_LT(largest_turn, 3.0 * M_PI / 180);
  // At the bisector the shaded normal lies between the faces (not half-way: the edge line's surfels belong to
  // the top face, so more of the ten neighbours do).
  const SurfaceContact mid = forceShade(s, Vec3(-delta, 0.00013, -delta), 10);
  EXPECT_GT(mid.normal.x(), 0.25);
  EXPECT_GT(mid.normal.z(), 0.25);
  EXPECT_NEAR(mid.normal.y(), 0.0, 1e-12);
}

}  // namespace
}  // namespace rc
