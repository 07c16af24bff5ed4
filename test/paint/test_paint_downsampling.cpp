// Downsampling (thesis 5.5.2): uniformly painted children merge back into their father (count and colour
// restored, wet paint conserved); detail stays; the work per call is bounded.
#include "relaxed_connectivity/paint/paint_downsampling.h"

#include <gtest/gtest.h>

#include "paint_test_surfaces.h"
#include "relaxed_connectivity/paint/paint_transfer.h"

namespace rc {
namespace {

/// Replaces originals [first, first + count) of a plane by four children each, painted `colour` (and, in
/// the children of every other original when `stripes`, alternately `colour` and blue).
PaintSurface paintedPlane(size_t first, size_t count, const Vec3& colour, bool stripes) {
  PaintSurface s(paint_test::planeCloud(0.01, 0.001));
  for (size_t i = first; i < first + count; ++i)
    for (int k = 0; k < 4; ++k) {
      ChildSurfel c;
      c.position = s.originals().positions[i] + 2.5e-4 * Vec3(k % 2 ? 1 : -1, k / 2 ? 1 : -1, 0);
      c.normal = Vec3(1e-3 * (k - 1.5), 0, 1).normalized();
      c.radius = 5e-4;
      c.paint.wet.rgb = stripes && i % 2 && k % 2 ? Vec3(0, 0, 1) : colour;
      c.paint.wet_volume = 0.25 + 0.01 * k;
      c.paint.optical_density = 4.0;  // opaque: the visible colour is the wet colour
      c.paint.dry.rgb = Vec3(1, 1, 1);
      c.paint.dry_volume = 1.0;
      s.addChild(uint32_t(i), c);
    }
  return s;
}

TEST(PaintDownsampling, AUniformlyPaintedRegionReturnsToTheOriginalSampling) {
  PaintSurface s = paintedPlane(100, 50, Vec3(0.8, 0.1, 0.1), false);
  const size_t original_active = s.originalCount();
  const double before = surfaceWetVolume(s);
  ASSERT_EQ(s.activeCount(), original_active - 50 + 200);
  PaintDownsampler downsampler;
  const DownsamplingStats stats = downsampler.run(s, 1000);
  EXPECT_EQ(stats.merged, 50u);
  EXPECT_EQ(stats.children_removed, 200u);
  EXPECT_EQ(s.activeCount(), original_active);  // the original surfel count
  EXPECT_EQ(s.childCount(), 0u);
  EXPECT_NEAR(surfaceWetVolume(s), before, 1e-12);
  for (size_t i = 100; i < 150; ++i) {
    EXPECT_TRUE(s.enabled(i));
    EXPECT_LT((visibleColour(s.originalPaint(i)).rgb - Vec3(0.8, 0.1, 0.1)).norm(), 1e-12) << i;
  }
}

TEST(PaintDownsampling, DetailStaysAndWorkIsBounded) {
  PaintSurface s = paintedPlane(100, 50, Vec3(0.8, 0.1, 0.1), true);
  PaintDownsampler downsampler;
  size_t merged = 0, calls = 0;
  for (DownsamplingStats st; (st = downsampler.run(s, 7)).visited > 0 && calls < 100; ++calls) {
    EXPECT_LE(st.visited, 7u);
    merged += st.merged;
    if (s.childCount() == 100) break;  // only the striped fathers are left
  }
  EXPECT_GT(calls, 3u);                 // the 50 fathers took several bounded calls
  EXPECT_EQ(merged, 25u);               // the uniform half merged
  EXPECT_EQ(s.childCount(), 25u * 4u);  // the striped half kept its children
  for (size_t i = 101; i < 150; i += 2) EXPECT_FALSE(s.enabled(i));
}

}  // namespace
}  // namespace rc
