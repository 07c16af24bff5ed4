// Background drying of the object (thesis 5.6.1): bounded visits, each surfel dried for exactly the time
// since its last visit, so any schedule of calls dries (5.12) as one step would; only drying a viewer sees is
// reported as a change (the deltas), and what is not reported still looks as the viewer last saw it.
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

TEST(PaintDryer, ReportsOnlyTheDryingAViewerSees) {
  // Red wet paint over a white base: thick (alpha = rho V_w = 20, opaque until it has thinned 20-fold) on
  // half the originals and a child, thin (alpha 0.5) on the others; a metallic drying function changes the
  // dry layer's colour and reflectivity.
  PaintSurface s(paint_test::planeCloud(0.005, 0.001));
  DryingFunction metallic;
  metallic.reflectivity_factor = 0.5;
  metallic.brighten = 0.1;
  auto wet = [](double alpha) {
    PaintState p;
    p.dry.rgb = Vec3::Ones();
    p.dry_volume = 1;
    p.wet.rgb = Vec3(0.9, 0.1, 0.1);
    p.wet.reflectivity = 0.8;
    p.optical_density = 10;
    p.wet_volume = alpha / 10;
    return p;
  };
  for (size_t i = 0; i < s.originalCount(); ++i) s.originalPaint(i) = wet(i % 2 ? 20.0 : 0.5);
  ChildSurfel c;
  c.position = s.originals().positions[8];
  c.normal = Vec3::UnitZ();
  c.paint = wet(20.0);
  s.addChild(8, c);
  s.takeChangedOriginals();
  const SurfelCloud seen_first = s.activeCloud();
  SurfelCloud viewer = seen_first;  // the viewer's copy: updated for reported originals only
  Attribute* reflectivity = viewer.attributes.find("reflectivity");
  PaintDryer dryer(0.5, metallic);
  size_t reported = 0, unseen_thick = 0;
  for (int second = 1; second <= 8; ++second) {  // thick paint stays opaque for ln(20) / 0.5 = 6 s
    dryer.run(s, double(second), s.originalCount());
    const std::vector<uint32_t> changed = s.takeChangedOriginals();
    reported += changed.size();
    const SurfelCloud now = s.activeCloud();
    std::vector<bool> is_changed(s.originalCount(), false);
    for (uint32_t o : changed) is_changed[o] = true;
    const Attribute* father = now.attributes.find("father");
    const Attribute* now_reflectivity = now.attributes.find("reflectivity");
    for (size_t k = 0; k < now.size(); ++k) {  // (the same surfels in the same order: no resampling here)
      const uint32_t o = uint32_t(father->get(k));
      if (is_changed[o]) {
        viewer.colors[k] = now.colors[k];
        reflectivity->set(k, now_reflectivity->get(k));
        continue;
      }
      EXPECT_EQ(viewer.colors[k], now.colors[k]) << "surfel " << k << " at " << second << " s";
      EXPECT_EQ(colourByte(reflectivity->get(k)), colourByte(now_reflectivity->get(k)))
          << "surfel " << k << " at " << second << " s";
      if (second < 6 && o % 2) ++unseen_thick;
    }
    if (second == 1)  // every thin original changed visibly, no thick one (nor the child's father 8)
      for (size_t o = 0; o < s.originalCount(); ++o) EXPECT_EQ(is_changed[o], o % 2 == 0) << o;
  }
  // The thick paint dried meanwhile (unseen), and its colour changed once it thinned.
  EXPECT_NEAR(s.originalPaint(1).wet_volume, 2.0 * std::exp(-0.5 * 8.0), 1e-12);
  EXPECT_EQ(unseen_thick, 5 * (s.originalCount() / 2));  // every thick original, every second to 5 s
  EXPECT_NE(seen_first.colors[1], s.activeCloud().colors[1]);
  EXPECT_LT(reported, 8 * s.originalCount());
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
