// Background drying of the object (thesis 5.6.1): bounded visits, each surfel dried for exactly the time
// since its last visit, so any schedule of calls dries (5.12) as one step would.
#include "relaxed_connectivity/paint/paint_dryer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "paint_test_surfaces.h"
#include "relaxed_connectivity/paint/paint_transfer.h"

namespace rc {
namespace {

PaintSurface wetPlane() {
  PaintSurface s(paint_test::planeCloud(0.005, 0.001));  // 121 originals
  for (size_t i = 0; i < s.originalCount(); ++i) s.originalPaint(i).wet_volume = 1.0 + 0.01 * double(i);
  ChildSurfel c;
  c.position = s.originals().positions[7];
  c.normal = Vec3::UnitZ();
  c.paint.wet_volume = 2.0;
  s.addChild(7, c);
  return s;
}

TEST(PaintDryer, AnyScheduleOfBoundedCallsDriesAsTheExponential) {
  const double kappa = 0.3;
  PaintSurface once = wetPlane(), bounded = wetPlane();
  PaintDryer a(kappa, DryingFunction()), b(kappa, DryingFunction());
  a.run(once, 2.0, once.originalCount());  // everything at t = 2 s
  // Bounded: 13 originals per call, calls at irregular times, ending with a full round at t = 2 s.
  double t = 0;
  for (int call = 0; call < 20; ++call) b.run(bounded, t += 0.037 * (1 + call % 3), 13);  // to 1.48 s
  const size_t n = bounded.originalCount();
  for (size_t k = 0; k < n; k += 13) b.run(bounded, 2.0, 13);
  for (size_t i = 0; i < n; ++i) {
    const double expected = (1.0 + 0.01 * double(i)) * std::exp(-kappa * 2.0);
    EXPECT_NEAR(once.originalPaint(i).wet_volume, expected, 1e-12);
    EXPECT_NEAR(bounded.originalPaint(i).wet_volume, expected, 1e-12) << i;
  }
  EXPECT_NEAR(bounded.children(7)[0].paint.wet_volume, 2.0 * std::exp(-kappa * 2.0), 1e-12);
  // Wet + dry conserved (the base layer was 1.0 per original).
  EXPECT_NEAR(bounded.originalPaint(3).wet_volume + bounded.originalPaint(3).dry_volume, 1.03 + 1.0, 1e-12);
}

TEST(PaintDryer, TimeMustNotGoBack) {
  PaintSurface s = wetPlane();
  PaintDryer d(0.3, DryingFunction(), 1.0);
  d.run(s, 2.0, 5);
  EXPECT_THROW(d.run(s, 1.0, 200), std::invalid_argument);  // visits surfel 0 again, last seen at 2 s
  EXPECT_THROW(PaintDryer(-1, DryingFunction()), std::invalid_argument);
}

}  // namespace
}  // namespace rc
