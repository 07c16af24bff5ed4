#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/fem/fem_cut_polygon.h"

namespace rc {
namespace {

std::string messageOf(const std::vector<Vec3>& polygon) {
  try {
    femCutFromPolygon(polygon, 1e-6);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(FemCutPolygon, SquareGivesItsPlaneCentroidAndRegion) {
  // Counter-clockwise seen from +z, with a closing copy of the first point (dropped).
  const FemSceneCut cut = femCutFromPolygon({{0, 0, 1}, {2, 0, 1}, {2, 2, 1}, {0, 2, 1}, {0, 0, 1}}, 1e-6);
  EXPECT_NEAR((cut.point - Vec3(1, 1, 1)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((cut.normal - Vec3(0, 0, 1)).norm(), 0.0, 1e-15);
  ASSERT_EQ(cut.region.size(), 4u);
  EXPECT_NEAR((cut.region[2] - Vec3(2, 2, 1)).norm(), 0.0, 1e-15);
}

TEST(FemCutPolygon, SlightlyBentPolygonIsProjectedOntoItsPlane) {
  const FemSceneCut cut = femCutFromPolygon({{0, 0, 0}, {1, 0, 1e-8}, {1, 1, 0}, {0, 1, 1e-8}}, 1e-6);
  for (const Vec3& p : cut.region) EXPECT_NEAR(cut.normal.dot(p - cut.point), 0.0, 1e-15);
}

TEST(FemCutPolygon, BadPolygonsAreRefusedWithTheReason) {
  EXPECT_EQ(messageOf({{0, 0, 0}, {1, 0, 0}}),
            "cut polygon: needs at least 3 distinct points (got 2 points, 2 distinct)");
  EXPECT_EQ(messageOf({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}),
            "cut polygon: zero area (collinear or coincident points)");
  EXPECT_EQ(messageOf({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {NAN, 1, 0}}), "cut polygon: point 3 is not finite");
  EXPECT_EQ(messageOf({{0, 0, 0}, {2, 0, 0}, {1, 0.5, 0}, {2, 2, 0}, {0, 2, 0}}), "cut polygon: not convex");
  const std::string bent = messageOf({{0, 0, 0}, {1, 0, 0.1}, {1, 1, 0}, {0, 1, 0.1}});
  EXPECT_EQ(bent.rfind("cut polygon: not planar: point ", 0), 0u) << bent;
}

}  // namespace
}  // namespace rc
