// The object representation of thesis 5.3: originals in a static kd-tree, child lists, enabled flags.
#include "relaxed_connectivity/paint/paint_surface.h"

#include <gtest/gtest.h>

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
    c.colour = Vec3(1, 0, 0);
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

}  // namespace
}  // namespace rc
