// Discontinuity surfels on a plain cloud (discontinuity_clipper.h, thesis 4.3): a pair of crack discs cuts
// the surfels of each side at the crack plane, inside the disc radius only; an opened crack renders as a
// clean gap.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "relaxed_connectivity/render/csg/discontinuity_clipper.h"
#include "relaxed_connectivity/render/splat/camera.h"
#include "relaxed_connectivity/render/splat/surfel_renderer.h"

using namespace rc;

namespace {

// Surfels on a grid in the plane z = 0 over [-1, 1]^2, spacing h, radius 3 h (overlapping splats), normal +z;
// those with x > 0 are shifted by `gap` in x.
SurfelCloud splitSheet(double h, double gap) {
  SurfelCloud c;
  for (double x = -1.0 + 0.5 * h; x < 1.0; x += h) {
    for (double y = -1.0 + 0.5 * h; y < 1.0; y += h) {
      c.positions.emplace_back(x + (x > 0.0 ? gap : 0.0), y, 0.0);
      c.normals.push_back(Vec3::UnitZ());
      c.radii.push_back(3.0 * h);
    }
  }
  return c;
}

// The crack pair at x = 0 (and x = gap for the right side): normals pointing away from their material.
SurfelCloud crackPair(double radius, double gap) {
  SurfelCloud d;
  d.positions = {Vec3(0.0, 0.0, 0.0), Vec3(gap, 0.0, 0.0)};
  d.normals = {Vec3::UnitX(), -Vec3::UnitX()};
  d.radii = {radius, radius};
  return d;
}

}  // namespace

TEST(DiscontinuityClipper, CutsEachSideAtItsDiscInsideTheRadius) {
  SurfelCloud s;
  s.positions = {Vec3(-0.05, 0.0, 0.0), Vec3(0.05, 0.0, 0.0), Vec3(-0.5, 0.0, 0.0), Vec3(-0.05, 0.9, 0.0)};
  s.normals.assign(4, Vec3::UnitZ());
  s.radii.assign(4, 0.08);
  const DiscontinuityClipper clip(s, crackPair(0.5, 0.0));
  EXPECT_TRUE(clip.needsClipping(0));
  EXPECT_TRUE(clip.needsClipping(1));
  EXPECT_FALSE(clip.needsClipping(2));  // does not reach the crack plane
  EXPECT_FALSE(clip.needsClipping(3));  // beyond the disc
  EXPECT_EQ(clip.clippedSurfels(), 2u);
  EXPECT_TRUE(clip.keepFragment(0, Vec3(-0.02, 0.0, 0.0)));
  EXPECT_FALSE(clip.keepFragment(0, Vec3(0.02, 0.0, 0.0)));  // across its own side's disc
  EXPECT_TRUE(clip.keepFragment(1, Vec3(0.02, 0.0, 0.0)));
  EXPECT_FALSE(clip.keepFragment(1, Vec3(-0.02, 0.0, 0.0)));
  EXPECT_TRUE(clip.keepFragment(0, Vec3(0.02, 0.6, 0.0)));  // the crack ends at the disc radius
  EXPECT_TRUE(clip.isVisible(0));
}

TEST(DiscontinuityClipper, AnOpenedCrackRendersAsACleanGap) {
  const double h = 0.02, gap = 0.1, radius = 0.5;
  const SurfelCloud sheet = splitSheet(h, gap);
  const DiscontinuityClipper clip(sheet, crackPair(radius, gap));
  Camera cam = Camera::orthographic(400, 400, 2.4);
  cam.lookAt(Vec3(0.05, 0.0, 5.0), Vec3(0.05, 0.0, 0.0), Vec3::UnitY());
  SplatConfig config;
  config.outputs = kOutputColor | kOutputWeight;
  SurfelRenderer renderer(config);
  RenderImages plain, clipped;
  RenderStats stats;
  renderer.render(sheet, cam, &plain);
  renderer.render(sheet, cam, &clipped, &clip, &stats);
  // Pixels whose centre lies in the gap (0, gap) x (-0.45, 0.45), away from its edges by a pixel.
  const double pixel = 2.4 / 400;
  size_t gap_pixels = 0, covered_plain = 0, covered_clipped = 0, outside_changed = 0;
  for (uint32_t v = 0; v < 400; ++v) {
    for (uint32_t u = 0; u < 400; ++u) {
      const double x = 0.05 + (u + 0.5 - 200.0) * pixel, y = (200.0 - v - 0.5) * pixel;
      const size_t p = size_t(v) * 400 + u;
      const bool in_gap = x > pixel && x < gap - pixel && std::abs(y) < radius - 0.05;
      if (in_gap) {
        ++gap_pixels;
        covered_plain += plain.weight[p] > 0.0f;
        covered_clipped += clipped.weight[p] > 0.0f;
      } else if (std::abs(y) > radius + 0.05 && (plain.weight[p] > 0.0f) != (clipped.weight[p] > 0.0f)) {
        ++outside_changed;
      }
    }
  }
  std::printf(
      "gap %zu pixels: covered %zu without the discs, %zu with; %zu fragments clipped on %zu surfels\n",
      gap_pixels, covered_plain, covered_clipped, stats.clipped_fragments, clip.clippedSurfels());
  ASSERT_GT(gap_pixels, 1000u);
  EXPECT_GT(covered_plain, gap_pixels / 10);  // the splats overlap into the gap
  EXPECT_EQ(covered_clipped, 0u);
  EXPECT_EQ(outside_changed, 0u);  // beyond the discs the sheet renders as before
  EXPECT_GT(stats.clipped_fragments, 0u);
}

TEST(DiscontinuityClipper, RejectsBadInput) {
  SurfelCloud s = splitSheet(0.2, 0.0);
  SurfelCloud no_radius = s;
  no_radius.radii.clear();
  EXPECT_THROW(DiscontinuityClipper(no_radius, crackPair(0.5, 0.0)), std::invalid_argument);
  SurfelCloud bad = crackPair(0.5, 0.0);
  bad.radii[1] = 0.0;
  EXPECT_THROW(DiscontinuityClipper(s, bad), std::invalid_argument);
  bad = crackPair(0.5, 0.0);
  bad.normals.clear();
  EXPECT_THROW(DiscontinuityClipper(s, bad), std::invalid_argument);
  const DiscontinuityClipper none(s, SurfelCloud());
  EXPECT_FALSE(none.needsClipping(0));
}
