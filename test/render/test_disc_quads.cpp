// Surfels as oriented disc quads for rviz (render/display/disc_quads.h): corners in the tangent plane at the
// radius, colours from the cloud or a scalar field through viridis, bad surfels skipped, bad options refused.
#include "relaxed_connectivity/render/display/disc_quads.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rc {
namespace {

SurfelCloud threeSurfels() {
  SurfelCloud c;
  c.positions = {Vec3(0, 0, 0), Vec3(1, 2, 3), Vec3(-1, 0, 0.5)};
  c.normals = {Vec3(0, 0, 2), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  c.radii = {0.1, 0.2, 0.3};
  c.colors = {{255, 0, 0, 255}, {0, 255, 0, 255}, {0, 0, 255, 255}};
  return c;
}

Vec3 positionOf(const DiscVertex& v) {
  return Vec3(v.position[0], v.position[1], v.position[2]);
}

TEST(DiscQuads, CornersLieInTheTangentPlaneAroundTheDisc) {
  const SurfelCloud c = threeSurfels();
  std::vector<DiscVertex> v;
  const DiscQuadStats s = buildDiscQuads(c, DiscQuadOptions(), &v);
  ASSERT_EQ(s.discs, 3u);
  ASSERT_EQ(v.size(), 12u);
  for (size_t i = 0; i < 3; ++i) {
    const Vec3 n = c.normals[i].normalized();
    for (int k = 0; k < 4; ++k) {
      const DiscVertex& corner = v[4 * i + k];
      const Vec3 d = positionOf(corner) - c.positions[i];
      EXPECT_NEAR(d.dot(n), 0.0, 1e-6);                          // in the tangent plane
      EXPECT_NEAR(d.norm(), std::sqrt(2.0) * c.radii[i], 1e-6);  // the disc is the quad's incircle
      EXPECT_NEAR(Vec3(corner.normal[0], corner.normal[1], corner.normal[2]).dot(n), 1.0, 1e-6);
      EXPECT_EQ(std::abs(corner.uv[0]), 1.0f);
      EXPECT_EQ(std::abs(corner.uv[1]), 1.0f);
    }
    // Opposite corners through the centre; the edge midpoints at the radius.
    EXPECT_NEAR(((positionOf(v[4 * i]) + positionOf(v[4 * i + 2])) / 2 - c.positions[i]).norm(), 0, 1e-6);
    EXPECT_NEAR(((positionOf(v[4 * i]) + positionOf(v[4 * i + 1])) / 2 - c.positions[i]).norm(), c.radii[i],
                1e-6);
    EXPECT_EQ(v[4 * i].colour[i], 255);  // red, green, blue
  }
  DiscQuadOptions twice;
  twice.radius_scale = 2;
  buildDiscQuads(c, twice, &v);
  EXPECT_NEAR((positionOf(v[0]) - c.positions[0]).norm(), 2 * std::sqrt(2.0) * 0.1, 1e-6);
}

TEST(DiscQuads, ScalarFieldsThroughViridis) {
  SurfelCloud c = threeSurfels();
  c.attributes.add("wet", ScalarType::kFloat32, 1, 3);
  for (size_t i = 0; i < 3; ++i) c.attributes.find("wet")->set(i, double(i * i));
  const std::vector<std::string> fields = discColourFields(c);
  for (const char* f : {"rgb", "radius", "x", "y", "z", "wet"})
    EXPECT_NE(std::find(fields.begin(), fields.end(), f), fields.end()) << f;
  DiscQuadOptions o;
  o.colour_field = "wet";
  std::vector<DiscVertex> v;
  const DiscQuadStats s = buildDiscQuads(c, o, &v);
  EXPECT_EQ(s.min_value, 0.0);
  EXPECT_EQ(s.max_value, 4.0);
  uint8_t low[3], high[3], quarter[3];
  viridisColour(0, low);
  viridisColour(1, high);
  viridisColour(0.25, quarter);
  EXPECT_EQ(low[0], 68);  // matplotlib's viridis ends
  EXPECT_EQ(high[1], 231);
  EXPECT_EQ(quarter[2], 139);
  for (int ch = 0; ch < 3; ++ch) {
    EXPECT_EQ(v[0].colour[ch], low[ch]);
    EXPECT_EQ(v[4].colour[ch], quarter[ch]);  // 1 of 0..4
    EXPECT_EQ(v[8].colour[ch], high[ch]);
  }
  o.colour_field = "z";
  o.auto_range = false;
  o.min_value = 0;
  o.max_value = 1;  // z = 3 clamps to the top
  buildDiscQuads(c, o, &v);
  EXPECT_EQ(v[4].colour[1], high[1]);
}

TEST(DiscQuads, BadSurfelsAreSkippedAndBadOptionsRefused) {
  SurfelCloud c = threeSurfels();
  c.positions[1].x() = std::nan("");
  c.normals[2] = Vec3::Zero();
  std::vector<DiscVertex> v;
  const DiscQuadStats s = buildDiscQuads(c, DiscQuadOptions(), &v);
  EXPECT_EQ(s.discs, 1u);
  EXPECT_EQ(s.skipped, 2u);
  EXPECT_EQ(v.size(), 4u);
  DiscQuadOptions o;
  o.colour_field = "no_such_field";
  EXPECT_THROW(buildDiscQuads(c, o, &v), std::invalid_argument);
  SurfelCloud bare;
  bare.positions = {Vec3::Zero()};
  EXPECT_THROW(buildDiscQuads(bare, DiscQuadOptions(), &v), std::invalid_argument);
  // No radii: the default radius.
  SurfelCloud no_radii = threeSurfels();
  no_radii.radii.clear();
  DiscQuadOptions d;
  d.default_radius = 0.05;
  buildDiscQuads(no_radii, d, &v);
  EXPECT_NEAR((positionOf(v[0]) - no_radii.positions[0]).norm(), std::sqrt(2.0) * 0.05, 1e-6);
}

TEST(DiscQuads, EllipticalSurfelsUseTheirAxes) {
  SurfelCloud c;
  c.positions = {Vec3(0, 0, 1)};
  c.normals = {Vec3::UnitZ()};
  c.axes1 = {Vec3(0.3, 0, 0)};
  c.axes2 = {Vec3(0, 0.1, 0)};
  std::vector<DiscVertex> v;
  buildDiscQuads(c, DiscQuadOptions(), &v);
  ASSERT_EQ(v.size(), 4u);
  EXPECT_NEAR(v[1].position[0] - v[0].position[0], 0.6f, 1e-6);  // along axis 1
  EXPECT_NEAR(v[2].position[1] - v[1].position[1], 0.2f, 1e-6);  // along axis 2
}

}  // namespace
}  // namespace rc
