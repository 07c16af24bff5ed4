// The object representation of thesis 5.3: originals in a static kd-tree, child lists, enabled flags.
#include "relaxed_connectivity/paint/paint_surface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>
#include <vector>

#include "relaxed_connectivity/core/kd_tree.h"

#include "paint_test_surfaces.h"

namespace rc {
namespace {

TEST(PaintSurface, ChildrenReplaceTheirClosestOriginalAndOriginalsStay) {
  PaintSurface s(paint_test::planeCloud(0.01, 0.001));
  const size_t n = s.originalCount();
  ASSERT_EQ(n, 21u * 21u);
  EXPECT_EQ(s.activeCount(), n);
  // Four children near the original at (0.002, -0.003, 0).
  const uint32_t father = s.closestOriginal(Vec3(0.002, -0.003, 0));
  EXPECT_NEAR((s.originals().positions[father] - Vec3(0.002, -0.003, 0)).norm(), 0.0, 1e-15);
  for (int k = 0; k < 4; ++k) {
    ChildSurfel c;
    c.position = Vec3(0.002 + 0.0002 * (k % 2), -0.003 + 0.0002 * (k / 2), 0);
    c.normal = Vec3::UnitZ();
    c.radius = 0.0002;
    c.paint.wet.rgb = Vec3(1, 0, 0);
    c.paint.wet_volume = 1.0;
    EXPECT_EQ(s.addChild(c), father);
  }
  EXPECT_FALSE(s.enabled(father));
  EXPECT_EQ(s.children(father).size(), 4u);
  EXPECT_EQ(s.childCount(), 4u);
  EXPECT_EQ(s.activeCount(), n - 1 + 4);
  // Collision still sees every original, the replaced one included.
  Neighbor nn[3];
  ASSERT_EQ(s.nearestOriginals(Vec3(0.002, -0.003, 0.0001), 3, nn), 3u);
  EXPECT_EQ(nn[0].index, father);
  const SurfelCloud active = s.activeCloud();
  EXPECT_EQ(active.size(), n + 3);
  const Attribute* fathers = active.attributes.find("father");
  ASSERT_NE(fathers, nullptr);
  size_t red = 0;
  for (size_t i = 0; i < active.size(); ++i)
    if (active.colors[i][0] == 255 && active.colors[i][1] == 0) {
      ++red;
      EXPECT_EQ(uint32_t(fathers->get(i)), father);
    }
  EXPECT_EQ(red, 4u);
  // Downsampling (5.5.2) drops the children and re-enables the father.
  s.clearChildren(father);
  EXPECT_TRUE(s.enabled(father));
  EXPECT_EQ(s.childCount(), 0u);
  EXPECT_EQ(s.activeCount(), n);
}

TEST(PaintSurface, ExplicitFatherAndEnableFlagsCount) {
  PaintSurface s(paint_test::planeCloud(0.002, 0.001));
  ChildSurfel c;
  c.position = Vec3(0.0014, 0, 0);
  c.normal = Vec3::UnitZ();
  s.addChild(0, c);  // a child may be filed under any father the paint model chooses
  EXPECT_EQ(s.children(0).size(), 1u);
  s.setEnabled(0, false);  // idempotent
  EXPECT_EQ(s.activeCount(), s.originalCount() - 1 + 1);
  s.setEnabled(3, false);
  EXPECT_EQ(s.activeCount(), s.originalCount() - 2 + 1);
  s.setEnabled(3, true);
  EXPECT_EQ(s.activeCount(), s.originalCount());
}

TEST(PaintSurface, AChildListKeepsNoMoreThanTwiceItsChildrensRoom) {
  // Resampling adds and removes children at the same originals all session long (issue 20's soak).
  PaintSurface s(paint_test::planeCloud(0.002, 0.001));
  ChildSurfel c;
  c.normal = Vec3::UnitZ();
  for (int i = 0; i < 64; ++i) s.addChild(0, c);
  EXPECT_GE(s.children(0).capacity(), 64u);
  for (int i = 0; i < 60; ++i) s.removeChild(0, s.children(0).size() - 1);
  EXPECT_EQ(s.children(0).size(), 4u);
  EXPECT_LE(s.children(0).capacity(), 2u * 4u + 4u);
  EXPECT_EQ(s.childCount(), 4u);
}

/// A sphere and a flat plane (a zero-thickness bounding box) to query, each with its surface and a kd-tree
/// over the same points as the reference.
struct QueriedSurface {
  SurfelCloud cloud;
  PaintSurface surface;
  KdTree tree;
  explicit QueriedSurface(SurfelCloud c) : cloud(std::move(c)), surface(cloud), tree(cloud.positions) {}
};

std::vector<std::unique_ptr<QueriedSurface>> queriedSurfaces() {
  std::vector<std::unique_ptr<QueriedSurface>> out;
  out.push_back(std::make_unique<QueriedSurface>(paint_test::sphereCloud(Vec3::Zero(), 0.05, 20000)));
  out.push_back(std::make_unique<QueriedSurface>(paint_test::planeCloud(0.02, 0.0005)));
  return out;
}

/// Deterministic uniform numbers in [0, 1).
struct Uniform {
  uint32_t state;
  double operator()() { return (state = state * 1664525u + 1013904223u) / 4294967296.0; }
};

TEST(PaintSurface, NearestOriginalsFromTheGridEqualTheKdTree) {
  // Queries on, near, deep below, far above and outside the bounding box of a sphere and of a flat plane
  // (a zero-thickness box): the grid answers near the surface, the kd-tree elsewhere; both must agree.
  for (const auto& queried : queriedSurfaces()) {
    const auto& [cloud, surface, tree] = *queried;
    Uniform uniform{12345};
    for (int q = 0; q < 3000; ++q) {
      const Vec3& on = cloud.positions[size_t(uniform() * cloud.size())];
      const double offset = std::pow(10.0, -6 + 5 * uniform()) * (uniform() < 0.5 ? -1 : 1);  // 1 um - 10 cm
      const Vec3 x =
          on + offset * cloud.normals[0].cwiseAbs().maxCoeff() * Vec3(uniform(), uniform(), 1).normalized();
      for (const size_t k : {size_t(1), size_t(10), size_t(40)}) {
        Neighbor grid[64], exact[64];
        ASSERT_EQ(surface.nearestOriginals(x, k, grid), tree.knn(x, k, exact));
        for (size_t i = 0; i < k; ++i) {
          ASSERT_EQ(grid[i].sq_dist, exact[i].sq_dist) << "query " << q << " k " << k << " rank " << i;
          // Equal distances may come in another order; the surfel must lie at that distance.
          EXPECT_EQ((cloud.positions[grid[i].index] - x).squaredNorm(), grid[i].sq_dist);
        }
      }
    }
  }
}

TEST(PaintSurface, ClearanceLowerBoundNeverExceedsTheDistance) {
  for (const auto& queried : queriedSurfaces()) {
    const auto& [cloud, surface, tree] = *queried;
    Uniform uniform{99};
    int positive = 0, far = 0;
    for (int q = 0; q < 5000; ++q) {
      const Vec3 x = 0.12 * Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5);
      Neighbor nearest;
      tree.knn(x, 1, &nearest);
      const double bound = surface.clearanceLowerBound(x);
      ASSERT_LE(bound, std::sqrt(nearest.sq_dist)) << "query " << q;
      // Not vacuous far from the surface (the Chebyshev cell distance gives about d / sqrt(3) - w
      // diagonally).
      const double distance = std::sqrt(nearest.sq_dist);
      if (distance > 0.02) ++far, positive += bound > 0.25 * distance;
    }
    std::printf("%d of %d queries with 2 cm clearance or more get a bound above a quarter of the distance\n",
                positive, far);
    EXPECT_GT(positive, far / 2);
  }
}

TEST(PaintSurface, RejectsCloudsItCannotCollideWith) {
  EXPECT_THROW(PaintSurface{SurfelCloud()}, std::invalid_argument);
  SurfelCloud no_normals = paint_test::planeCloud(0.002, 0.001);
  no_normals.normals.clear();
  EXPECT_THROW(PaintSurface{no_normals}, std::invalid_argument);
  SurfelCloud nan = paint_test::planeCloud(0.002, 0.001);
  nan.positions[3].x() = std::nan("");
  try {
    PaintSurface s(nan);
    FAIL() << "accepted a NaN position";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("surfel 3"), std::string::npos) << e.what();
  }
}

TEST(PaintSurface, ReportsEachChangedOriginalOnceAndItsActiveSurfelsForADelta) {
  PaintSurface s(paint_test::planeCloud(0.005, 0.001));
  EXPECT_TRUE(s.takeChangedOriginals().empty());
  ChildSurfel c;
  c.position = s.originals().positions[7];
  c.normal = Vec3::UnitZ();
  c.radius = 5e-4;
  s.addChild(7, c);
  s.addChild(7, c);
  s.originalPaint(3).wet_volume = 0.5;
  s.keepAsChild(9);
  EXPECT_EQ(s.takeChangedOriginals(), (std::vector<uint32_t>{7, 3, 9}));
  EXPECT_TRUE(s.takeChangedOriginals().empty());
  // The delta's surfels: original 3 itself, two children of 7, 9 as its own child.
  const SurfelCloud delta = s.activeCloudOf({7, 3, 9});
  ASSERT_EQ(delta.size(), 4u);
  const Attribute* father = delta.attributes.find("father");
  ASSERT_NE(father, nullptr);
  EXPECT_EQ(father->get(0), 7);
  EXPECT_EQ(father->get(2), 3);
  EXPECT_EQ(father->get(3), 9);
  EXPECT_EQ(delta.positions[3], s.originals().positions[9]);
  EXPECT_EQ(delta.attributes.find("paint_wet_volume")->get(2), 0.5);
  // restoreOriginal (undo, load) reports too.
  s.restoreOriginal(7, true, s.originalPaint(7), {});
  EXPECT_EQ(s.takeChangedOriginals(), (std::vector<uint32_t>{7}));
  EXPECT_THROW(s.activeCloudOf({100000}), std::out_of_range);
  // reset (the paint model's clear): the object as constructed, every original reported.
  s.addChild(4, c);
  s.reset();
  EXPECT_EQ(s.childCount(), 0u);
  EXPECT_EQ(s.activeCount(), s.originalCount());
  EXPECT_EQ(s.originalPaint(3).wet_volume, 0.0);
  EXPECT_EQ(s.takeChangedOriginals().size(), s.originalCount());
}

}  // namespace
}  // namespace rc
