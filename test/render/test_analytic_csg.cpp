// The analytic CSG ray caster against hand-computed intersections.
#include <gtest/gtest.h>

#include <cmath>

#include "relaxed_connectivity/render/csg/analytic_csg.h"

namespace rc {
namespace {

constexpr double kTol = 1e-12;

void expectVec(const Vec3& a, const Vec3& b, double tol = 1e-12) {
  EXPECT_NEAR((a - b).norm(), 0.0, tol) << a.transpose() << " vs " << b.transpose();
}

TEST(AnalyticSolid, SphereIntervalAndNormals) {
  const IntervalList l =
      solidIntervals(AnalyticSolid::sphere(Vec3::Zero(), 1), 3, Vec3(0, 0, -5), Vec3::UnitZ());
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0].enter.t, 4, kTol);
  EXPECT_NEAR(l[0].leave.t, 6, kTol);
  EXPECT_EQ(l[0].enter.patch, 3);
  expectVec(l[0].enter.normal, -Vec3::UnitZ());
  expectVec(l[0].leave.normal, Vec3::UnitZ());
  EXPECT_TRUE(
      solidIntervals(AnalyticSolid::sphere(Vec3::Zero(), 1), 0, Vec3(0, 1.01, -5), Vec3::UnitZ()).empty());
}

TEST(AnalyticSolid, EllipsoidOffAxisRay) {
  const AnalyticSolid e = AnalyticSolid::ellipsoid(Vec3::Zero(), Vec3(2, 1, 1));
  IntervalList l = solidIntervals(e, 0, Vec3(-5, 0, 0), Vec3::UnitX());
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0].enter.t, 3, kTol);
  EXPECT_NEAR(l[0].leave.t, 7, kTol);
  // x = 1: (1/2)^2 + y^2 = 1 -> y = -sqrt(3)/2 on entry; gradient (x/4, y, 0).
  l = solidIntervals(e, 0, Vec3(1, -5, 0), Vec3::UnitY());
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0].enter.t, 5 - std::sqrt(0.75), kTol);
  expectVec(l[0].enter.normal, Vec3(0.25, -std::sqrt(0.75), 0).normalized());
  // Rotated by 90 degrees about z: the long axis lies along y.
  const AnalyticSolid r = AnalyticSolid::ellipsoid(Vec3(0, 0, 1), Vec3(2, 1, 1),
                                                   Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()).matrix());
  l = solidIntervals(r, 0, Vec3(0, -5, 1), Vec3::UnitY());
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0].enter.t, 3, kTol);
  EXPECT_TRUE(r.contains(Vec3(0, 1.9, 1)));
  EXPECT_FALSE(r.contains(Vec3(1.9, 0, 1)));
}

TEST(AnalyticSolid, HalfSpaceAndParallelRays) {
  const AnalyticSolid h = AnalyticSolid::halfSpace(Vec3(0, 0, 1), Vec3(0, 0, 2));
  IntervalList l = solidIntervals(h, 7, Vec3(0, 0, 5), -Vec3::UnitZ());
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0].enter.t, 4, kTol);
  EXPECT_TRUE(std::isinf(l[0].leave.t));
  expectVec(l[0].enter.normal, Vec3::UnitZ());
  l = solidIntervals(h, 7, Vec3(0, 0, -5), Vec3::UnitZ());  // starts inside, leaves at z = 1
  ASSERT_EQ(l.size(), 1u);
  EXPECT_TRUE(std::isinf(l[0].enter.t) && l[0].enter.t < 0);
  EXPECT_NEAR(l[0].leave.t, 6, kTol);
  EXPECT_EQ(solidIntervals(h, 7, Vec3(0, 0, 0), Vec3::UnitX()).size(), 1u);  // parallel, inside
  EXPECT_TRUE(solidIntervals(h, 7, Vec3(0, 0, 2), Vec3::UnitX()).empty());   // parallel, outside
}

TEST(AnalyticSolid, BoxSlabs) {
  const AnalyticSolid b = AnalyticSolid::box(Vec3(1, 0, 0), Vec3(1, 2, 3));
  IntervalList l = solidIntervals(b, 0, Vec3(-5, 0.5, 0), Vec3::UnitX());
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0].enter.t, 5, kTol);
  EXPECT_NEAR(l[0].leave.t, 7, kTol);
  expectVec(l[0].enter.normal, -Vec3::UnitX());
  expectVec(l[0].leave.normal, Vec3::UnitX());
  // Diagonal ray entering through the y face: from (1, -5, 0) towards +y and +z.
  const Vec3 dir = Vec3(0, 1, 1).normalized();
  l = solidIntervals(b, 0, Vec3(1, -5, -1), dir);
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0].enter.t, 3 * std::sqrt(2.0), 1e-12);  // y = -2 at t / sqrt2 = 3, z = 2 there
  expectVec(l[0].enter.normal, -Vec3::UnitY());
  EXPECT_NEAR(l[0].leave.t, 4 * std::sqrt(2.0), 1e-12);  // z = 3 at t / sqrt2 = 4
  expectVec(l[0].leave.normal, Vec3::UnitZ());
  // Touching the edge (y = -2 and z = 3 at the same t) is no interval.
  EXPECT_TRUE(solidIntervals(b, 0, Vec3(1, -5, 0), dir).empty());
  EXPECT_TRUE(solidIntervals(b, 0, Vec3(-5, 2.5, 0), Vec3::UnitX()).empty());
  // Rotated 45 degrees about z: the x ray enters at the corner x = 1 - sqrt(2) (half extent 1 along a
  // diagonal).
  const AnalyticSolid rb =
      AnalyticSolid::box(Vec3::Zero(), Vec3(1, 1, 1), Eigen::AngleAxisd(M_PI / 4, Vec3::UnitZ()).matrix());
  l = solidIntervals(rb, 0, Vec3(-5, 0, 0), Vec3::UnitX());
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0].enter.t, 5 - std::sqrt(2.0), 1e-12);
}

TEST(IntervalBoolean, TwoOverlappingSpheres) {
  const Vec3 o(-5, 0, 0), d = Vec3::UnitX();
  const IntervalList a = solidIntervals(AnalyticSolid::sphere(Vec3::Zero(), 1), 0, o, d);   // [4, 6]
  const IntervalList b = solidIntervals(AnalyticSolid::sphere(Vec3(1, 0, 0), 1), 1, o, d);  // [5, 7]
  IntervalList u = intervalUnion(a, b);
  ASSERT_EQ(u.size(), 1u);
  EXPECT_NEAR(u[0].enter.t, 4, kTol);
  EXPECT_NEAR(u[0].leave.t, 7, kTol);
  EXPECT_EQ(u[0].enter.patch, 0);
  EXPECT_EQ(u[0].leave.patch, 1);
  IntervalList i = intervalIntersection(a, b);
  ASSERT_EQ(i.size(), 1u);
  EXPECT_NEAR(i[0].enter.t, 5, kTol);
  EXPECT_EQ(i[0].enter.patch, 1);
  expectVec(i[0].enter.normal, -Vec3::UnitX());
  EXPECT_EQ(i[0].leave.patch, 0);
  IntervalList ab = intervalDifference(a, b);
  ASSERT_EQ(ab.size(), 1u);
  EXPECT_NEAR(ab[0].leave.t, 5, kTol);
  EXPECT_EQ(ab[0].leave.patch, 1);
  expectVec(ab[0].leave.normal, Vec3::UnitX());  // B's inward normal: out of A - B
  IntervalList ba = intervalDifference(b, a);
  ASSERT_EQ(ba.size(), 1u);
  EXPECT_NEAR(ba[0].enter.t, 6, kTol);
  EXPECT_EQ(ba[0].enter.patch, 0);
  expectVec(ba[0].enter.normal, -Vec3::UnitX());
  IntervalList c = intervalComplement(a);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_TRUE(std::isinf(c[0].enter.t));
  EXPECT_NEAR(c[0].leave.t, 4, kTol);
  expectVec(c[0].leave.normal, Vec3::UnitX());
  EXPECT_NEAR(c[1].enter.t, 6, kTol);
  EXPECT_TRUE(std::isinf(c[1].leave.t));
  EXPECT_EQ(intervalComplement(IntervalList{}).size(), 1u);
  EXPECT_TRUE(intervalComplement(intervalComplement(IntervalList{})).empty());
}

TEST(AnalyticCsgCaster, SphereMinusTwoSpheresTunnel) {
  // A - (B | C): B and C bite into A from -x and +x; a ray along x passes A only between them.
  const std::map<std::string, int> names = {{"A", 0}, {"B", 1}, {"C", 2}};
  AnalyticCsgCaster caster({AnalyticSolid::sphere(Vec3::Zero(), 2), AnalyticSolid::sphere(Vec3(-2, 0, 0), 1),
                            AnalyticSolid::sphere(Vec3(2, 0, 0), 1)},
                           CsgTree::parse("A - (B | C)", names));
  const IntervalList l = caster.intervals(Vec3(-5, 0, 0), Vec3::UnitX());
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0].enter.t, 4, kTol);  // x = -1, B's surface
  EXPECT_EQ(l[0].enter.patch, 1);
  EXPECT_NEAR(l[0].leave.t, 6, kTol);  // x = 1, C's surface
  EXPECT_EQ(l[0].leave.patch, 2);
  // Off axis, above the bites: y = 1.9 misses B and C, so A's own surface is first.
  const AnalyticHit hit = caster.cast(Vec3(-5, 1.9, 0), Vec3::UnitX());
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.patch, 0);
  EXPECT_NEAR(hit.t, 5 - std::sqrt(4 - 1.9 * 1.9), kTol);
  EXPECT_TRUE(caster.contains(Vec3(0, 0, 0)));
  EXPECT_FALSE(caster.contains(Vec3(-1.5, 0, 0)));
  // The normalised tree (A & (!B & !C)) gives the same intervals.
  AnalyticCsgCaster normalized(
      {AnalyticSolid::sphere(Vec3::Zero(), 2), AnalyticSolid::sphere(Vec3(-2, 0, 0), 1),
       AnalyticSolid::sphere(Vec3(2, 0, 0), 1)},
      CsgTree::parse("A - (B | C)", names).normalized());
  const IntervalList m = normalized.intervals(Vec3(-5, 0, 0), Vec3::UnitX());
  ASSERT_EQ(m.size(), 1u);
  EXPECT_NEAR(m[0].enter.t, 4, kTol);
  EXPECT_EQ(m[0].enter.patch, 1);
  expectVec(m[0].enter.normal, -Vec3::UnitX());
}

TEST(AnalyticCsgCaster, CubeOfSixHalfSpaces) {
  std::vector<AnalyticSolid> faces;
  for (int k = 0; k < 3; ++k)
    for (int s : {1, -1})
      faces.push_back(AnalyticSolid::halfSpace(0.5 * s * Vec3::Unit(k), s * Vec3::Unit(k)));
  AnalyticCsgCaster cube(faces, CsgTree::parse("0 & 1 & 2 & 3 & 4 & 5"));
  AnalyticHit hit = cube.cast(Vec3(0.2, 0.1, 5), -Vec3::UnitZ());
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.t, 4.5, kTol);
  EXPECT_EQ(hit.patch, 4);  // +z face
  expectVec(hit.normal, Vec3::UnitZ());
  // A ray along the diagonal hits the corner region through the face it crosses first.
  hit = cube.cast(Vec3(5, 0.1, 0.2), -Vec3::UnitX());
  EXPECT_EQ(hit.patch, 0);
  EXPECT_FALSE(cube.cast(Vec3(0.6, 0, 5), -Vec3::UnitZ()).hit);
  EXPECT_THROW(AnalyticCsgCaster(faces, CsgTree::parse("0 & 6")), std::invalid_argument);
}

TEST(CastImage, OrthographicSphereDepthAndArea) {
  AnalyticCsgCaster sphere({AnalyticSolid::sphere(Vec3::Zero(), 1)}, CsgTree::leaf(0));
  Camera camera = Camera::orthographic(101, 101, 4.0);  // 25.25 px per metre
  camera.lookAt(Vec3(0, -10, 0), Vec3::Zero());
  const AnalyticImages image = castImage(sphere, camera);
  const size_t centre = 50 * 101 + 50;
  EXPECT_NEAR(image.depth[centre], 9.0, 1e-6);
  EXPECT_EQ(image.patch_id[centre], 0);
  EXPECT_NEAR(image.normal[centre].y(), -1.0, 1e-6);
  size_t covered = 0;
  for (int32_t p : image.patch_id) covered += p == 0;
  const double scale = 101 / 4.0;
  EXPECT_NEAR(double(covered), M_PI * scale * scale, 0.02 * M_PI * scale * scale);
  // Perspective: the centre ray hits at z = 9 as well; near_clip beyond the sphere front shows its back.
  Camera persp = Camera::perspective(64, 48, 0.5);
  persp.lookAt(Vec3(0, -10, 0), Vec3::Zero());
  persp.cx = 32;
  persp.cy = 24;
  const AnalyticImages p = castImage(sphere, persp);
  EXPECT_NEAR(p.depth[24 * 64 + 32], 9.0, 1e-5);
  persp.near_clip = 9.5;
  EXPECT_NEAR(castImage(sphere, persp).depth[24 * 64 + 32], 11.0, 1e-5);
}

}  // namespace
}  // namespace rc
