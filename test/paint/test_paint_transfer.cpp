// One paint event after another (thesis 5.5): a brush pressed and dragged over a sampled plane leaves paint
// along its path on new child surfels; wet paint is conserved between brush and surface; replays are
// identical; nothing happens in the air.
#include "relaxed_connectivity/paint/paint_transfer.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "paint_test_surfaces.h"

namespace rc {
namespace {

constexpr double kEvent = 1.0 / 30;

Eigen::Isometry3d stylusAt(const Vec3& ferrule) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond::FromTwoVectors(Vec3(0, 0, -1), Vec3(-0.5, 0, -std::sqrt(0.75)))
                   .toRotationMatrix();  // leaning back 30 degrees against +x motion
  t.translation() = ferrule;
  return t;
}

PaintType symmetricPaint() {
  PaintType p;
  p.transfer_to_surface = 4.0;
  p.transfer_to_brush = 4.0;
  return p;
}

struct Session {
  PaintSurface surface{paint_test::planeCloud(0.03, 0.001)};  // 6 cm square, 1 mm sampling
  Brush brush{BrushPreset()};
  std::vector<PaintEventStats> events;

  /// Presses the brush 4 mm closer than its bristles are long over 10 events, then drags it 2 cm along +x.
  void stroke(const PaintType& paint, int drag_events = 30) {
    const double l = brush.preset().bristle_length;
    brush.reset(stylusAt(Vec3(-0.01, 0, l)));
    for (int e = 1; e <= 10 + drag_events; ++e) {
      const double lower = std::min(1.0, e / 10.0) * 0.004;
      const double x = -0.01 + 0.02 * std::max(0, e - 10) / double(drag_events);
      brush.advance(kEvent, stylusAt(Vec3(x, 0, l - lower)), &surface);
      events.push_back(transferPaint(brush, surface, paint, kEvent));
    }
  }
};

double brushWetVolume(const Brush& brush) {
  double sum = 0;
  for (const PaintState& p : brush.skin().paint) sum += p.wet_volume;
  return sum;
}

TEST(PaintTransfer, AStrokeLeavesPaintOnChildSurfelsAndConservesWetPaint) {
  Session s;
  const double before = brushWetVolume(s.brush) + surfaceWetVolume(s.surface);
  s.stroke(symmetricPaint());
  const double after = brushWetVolume(s.brush) + surfaceWetVolume(s.surface);
  EXPECT_NEAR(after, before, 1e-12 * before);
  // Paint moved to the surface, on children at the paint buffer's resolution along the path.
  size_t disabled = 0, painted = 0;
  double xmin = 1, xmax = -1;
  for (size_t i = 0; i < s.surface.originalCount(); ++i) {
    disabled += !s.surface.enabled(i);
    for (const ChildSurfel& c : s.surface.children(i))
      if (c.paint.wet_volume > 1e-3) {
        ++painted;
        xmin = std::min(xmin, c.position.x()), xmax = std::max(xmax, c.position.x());
        EXPECT_NEAR(c.position.z(), 0.0, 1e-9);
        EXPECT_GT(c.paint.wet.rgb.x(), c.paint.wet.rgb.z());  // the brush's red
      }
  }
  EXPECT_GT(disabled, 20u);
  EXPECT_GT(painted, 100u);
  EXPECT_GT(surfaceWetVolume(s.surface), 0.005 * before);  // measured 1.1 % of the load
  // The path runs along x for the 2 cm of the drag (the trailing tip 1-2 cm behind the ferrule).
  EXPECT_GT(xmax - xmin, 0.015);
  // The surface's wet paint is what the events moved there (nothing was on it before).
  double moved = 0;
  for (const PaintEventStats& e : s.events) moved += e.moved_to_surface - e.moved_to_brush;
  EXPECT_NEAR(surfaceWetVolume(s.surface), moved, 1e-9 * before);
}

TEST(PaintTransfer, ReplayingAStrokeGivesIdenticalSurfels) {
  Session a, b;
  a.stroke(symmetricPaint(), 12);
  b.stroke(symmetricPaint(), 12);
  ASSERT_EQ(a.surface.childCount(), b.surface.childCount());
  const SurfelCloud ca = a.surface.activeCloud(), cb = b.surface.activeCloud();
  ASSERT_EQ(ca.size(), cb.size());
  for (size_t i = 0; i < ca.size(); ++i) {
    ASSERT_EQ(ca.positions[i], cb.positions[i]) << i;
    ASSERT_EQ(ca.colors[i], cb.colors[i]) << i;
  }
  for (const auto& column : ca.attributes.columns())
    EXPECT_EQ(column.bytes, cb.attributes.find(column.name)->bytes);
}

TEST(PaintTransfer, ABrushInTheAirTransfersNothing) {
  Session s;
  s.brush.reset(stylusAt(Vec3(0, 0, 0.05)));
  s.brush.advance(kEvent, stylusAt(Vec3(0.001, 0, 0.05)), &s.surface);
  const PaintEventStats e = transferPaint(s.brush, s.surface, symmetricPaint(), kEvent);
  EXPECT_EQ(e.buffers, 0);
  EXPECT_EQ(s.surface.childCount(), 0u);
  PaintTransferOptions bad;
  bad.pixel_size = -1;
  EXPECT_THROW(transferPaint(s.brush, s.surface, symmetricPaint(), kEvent, bad), std::invalid_argument);
}

TEST(PaintTransfer, TheEraserTakesWetPaintAwayAndRestoresTheObjectsColour) {
  Session s;
  for (size_t i = 0; i < s.surface.originalCount(); ++i) {  // dried blue paint under a wet blue layer
    PaintState& p = s.surface.originalPaint(i);
    p.dry.rgb = Vec3(0.1, 0.1, 0.9);
    p.wet.rgb = Vec3(0.1, 0.1, 0.9);
    p.wet_volume = 0.2;
  }
  PaintType eraser;
  eraser.eraser = true;
  eraser.transfer_to_surface = 30.0;  // as config/paint/paints/eraser.yaml
  eraser.transfer_to_brush = 6.0;
  loadBrush(s.brush.skin(), eraser);
  EXPECT_EQ(brushWetVolume(s.brush), 0.0);  // the eraser carries no paint
  const double before = surfaceWetVolume(s.surface);
  s.stroke(eraser, 12);
  EXPECT_NEAR(brushWetVolume(s.brush) + surfaceWetVolume(s.surface), before, 1e-12 * before);
  EXPECT_GT(brushWetVolume(s.brush), 1.0);  // wet paint taken up (measured 2.3 of 0.2 per original)
  // Where it pressed, the dry colour moved towards the object's own (white, the plane has no colours).
  size_t restored = 0, children = 0;
  for (size_t i = 0; i < s.surface.originalCount(); ++i)
    for (const ChildSurfel& c : s.surface.children(i)) {
      ++children;
      EXPECT_LE(c.paint.dry.rgb.x(), 1.0 + 1e-12);
      restored += c.paint.dry.rgb.x() > 0.5;  // from 0.1 towards 1
    }
  EXPECT_GT(restored, 100u);
  EXPECT_LT(restored, children);  // the resampled border that was not pressed keeps its colour
}

TEST(PaintTransfer, ViscousPaintCarvesTheBristlePatternIntoNewSurfels) {
  PaintType oil = symmetricPaint();
  oil.imprint_depth = 2e-4;
  oil.imprint_spacing = 1.5e-3;
  Session s;
  s.stroke(oil, 20);
  size_t imprinted = 0;
  for (const PaintEventStats& e : s.events) imprinted += e.children_imprinted;
  EXPECT_GT(imprinted, 100u);
  // Along y (across the +x stroke, the tip stays on y = 0) the carved surfels lie on
  // depth (1 + cos(2 pi y / spacing)) / 2 with normals tilted by its slope; the others (resampled next to
  // the pressed pixels, heights averaged by the splatting) stay within that range.
  size_t raised = 0, on_pattern = 0;
  double zmax = 0;
  for (size_t i = 0; i < s.surface.originalCount(); ++i)
    for (const ChildSurfel& c : s.surface.children(i)) {
      const double z = c.position.z();
      EXPECT_GT(z, -0.1 * oil.imprint_depth);
      EXPECT_LT(z, 1.1 * oil.imprint_depth);
      if (!(z > 1e-9)) continue;
      ++raised;
      const double phase = 2 * M_PI * c.position.y() / oil.imprint_spacing;
      const double slope = -0.5 * oil.imprint_depth * 2 * M_PI / oil.imprint_spacing * std::sin(phase);
      if (std::abs(z - 0.5 * oil.imprint_depth * (1 + std::cos(phase))) < 1e-7) {
        ++on_pattern;
        zmax = std::max(zmax, z);
        EXPECT_NEAR(std::abs(c.normal.y()), std::abs(slope) / std::sqrt(1 + slope * slope), 1e-9);
        EXPECT_NEAR(c.normal.x(), 0.0, 1e-9);
      }
    }
  EXPECT_GT(on_pattern, 50u);     // measured 88 of 420 raised: the rest were resampled next to pressed pixels
  EXPECT_GT(raised, on_pattern);  // (their heights averaged from the carved ones around them)
  // Pixel centres at +-0.25, +-0.75, ... mm sample the 1.5 mm pattern at 3/4 depth and 0.
  EXPECT_NEAR(zmax, 0.75 * oil.imprint_depth, 1e-9);
  // Pressing without moving carves nothing.
  Session still;
  const double l = still.brush.preset().bristle_length;
  still.brush.reset(stylusAt(Vec3(0, 0, l)));
  size_t still_imprinted = 0;
  for (int e = 1; e <= 10; ++e) {
    still.brush.advance(kEvent, stylusAt(Vec3(0, 0, l - 0.0004 * e)), &still.surface);
    still_imprinted += transferPaint(still.brush, still.surface, oil, kEvent).children_imprinted;
  }
  EXPECT_GT(still.surface.childCount(), 0u);
  EXPECT_EQ(still_imprinted, 0u);
  // A pattern finer than two buffer pixels would alias: not carved, and said so.
  oil.imprint_spacing = 1.5 * still.brush.preset().surfel_spacing;
  Session fine;
  fine.stroke(oil, 20);
  size_t fine_imprinted = 0;
  for (const PaintEventStats& e : fine.events) {
    fine_imprinted += e.children_imprinted;
    EXPECT_TRUE(e.imprint_aliased);
  }
  EXPECT_EQ(fine_imprinted, 0u);
  EXPECT_FALSE(s.events.back().imprint_aliased);
}

TEST(PaintTransfer, ASurfelsTransferRateGovernsWhatLeavesIt) {
  // Wet blue on the whole board; in one run the half y > 0 holds its paint (tau = 0 on those surfels). A
  // clean brush that only picks up (tau brush -> surface = 0) is dragged along y = 0.
  struct Outcome {
    double picked, total_before, total_after;
  };
  const auto run = [](bool hold_upper) {
    Session s;
    for (size_t i = 0; i < s.surface.originalCount(); ++i) {
      PaintState& p = s.surface.originalPaint(i);
      p.wet.rgb = Vec3(0.1, 0.1, 0.9);
      p.wet_volume = 0.2;
      if (hold_upper && s.surface.originals().positions[i].y() > 0) p.transfer_rate = 0.0;
    }
    PaintType clean = symmetricPaint();
    clean.eraser = true;  // (loads no paint)
    loadBrush(s.brush.skin(), clean);
    clean.eraser = false;
    clean.transfer_to_surface = 0;
    Outcome o;
    o.total_before = surfaceWetVolume(s.surface);
    s.stroke(clean, 12);
    o.picked = brushWetVolume(s.brush);
    o.total_after = surfaceWetVolume(s.surface);
    for (size_t i = 0; i < s.surface.originalCount(); ++i)
      for (const ChildSurfel& c : s.surface.children(i))
        if (hold_upper && c.position.y() > 0.001) {
          EXPECT_EQ(c.paint.transfer_rate, 0.0);  // resampled, still holding
        }
    return o;
  };
  const Outcome held = run(true), free = run(false);
  EXPECT_NEAR(held.picked + held.total_after, held.total_before, 1e-12 * held.total_before);
  EXPECT_NEAR(free.picked + free.total_after, free.total_before, 1e-12 * free.total_before);
  // The brush takes paint only from the half that lets it go (measured 0.49 against 1.63 from the free
  // board: less than half, the pixels on the border mix both halves' rates).
  EXPECT_GT(held.picked, 0.15 * free.picked);
  EXPECT_LT(held.picked, 0.6 * free.picked);
}

}  // namespace
}  // namespace rc
