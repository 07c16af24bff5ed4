// Undo and redo per stroke: after N strokes, N undos restore the painted surface bitwise, N redos bring the
// painted state back bitwise; background work outside strokes stays out of the journal; the journal keeps
// within its memory bound.
#include "relaxed_connectivity/paint/paint_journal.h"

#include <gtest/gtest.h>

#include "../sanitizer_support.h"
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
#include <malloc.h>
#define RC_HAVE_MALLINFO2 1
#endif

#include "paint_test_surfaces.h"
#include "relaxed_connectivity/paint/paint_dryer.h"
#include "relaxed_connectivity/paint/paint_transfer.h"

namespace rc {
namespace {

constexpr double kEvent = 1.0 / 30;

Eigen::Isometry3d stylusAt(const Vec3& ferrule) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() =
      Eigen::Quaterniond::FromTwoVectors(Vec3(0, 0, -1), Vec3(-0.5, 0, -std::sqrt(0.75))).toRotationMatrix();
  t.translation() = ferrule;
  return t;
}

/// Everything about the surface that undo must restore, as bytes of the active cloud.
std::vector<std::vector<uint8_t>> stateOf(const PaintSurface& surface) {
  const SurfelCloud c = surface.activeCloud();
  std::vector<std::vector<uint8_t>> out;
  const auto bytes = [&](const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    out.emplace_back(b, b + n);
  };
  bytes(c.positions.data(), c.size() * sizeof(Vec3));
  bytes(c.normals.data(), c.size() * sizeof(Vec3));
  bytes(c.radii.data(), c.radii.size() * sizeof(double));
  for (const auto& column : c.attributes.columns()) out.push_back(column.bytes);
  std::vector<uint8_t> enabled;
  for (size_t i = 0; i < surface.originalCount(); ++i) enabled.push_back(surface.enabled(i));
  out.push_back(enabled);
  return out;
}

struct Painter {
  PaintSurface surface{paint_test::planeCloud(0.03, 0.001)};
  Brush brush{BrushPreset()};
  PaintType paint;

  /// A 12-event stroke from (x0, y) along +x; its own stroke in the journal.
  void stroke(PaintJournal& journal, double x0, double y) {
    const double l = brush.preset().bristle_length;
    brush.reset(stylusAt(Vec3(x0, y, l)));
    journal.beginStroke();
    for (int e = 1; e <= 12; ++e) {
      const double lower = std::min(1.0, e / 4.0) * 0.004;
      brush.advance(kEvent, stylusAt(Vec3(x0 + 0.001 * e, y, l - lower)), &surface);
      const PaintJournal::Recording recording(journal);
      transferPaint(brush, surface, paint, kEvent);
    }
    journal.endStroke();
  }
};

TEST(PaintJournal, UndoAfterNStrokesRestoresTheSurfaceBitwiseAndRedoRepaintsIt) {
  Painter p;
  for (size_t i = 0; i < p.surface.originalCount(); ++i) {  // wet paint of varying colour on the object
    p.surface.originalPaint(i).wet_volume = 0.3;
    p.surface.originalPaint(i).wet.rgb = Vec3(0.1, double(i % 7) / 7, 0.9);
  }
  PaintJournal journal(p.surface);
  std::vector<std::vector<std::vector<uint8_t>>> states{stateOf(p.surface)};
  const double ys[] = {-0.01, 0.0, 0.004, 0.012};  // the second and third strokes overlap
  for (double y : ys) {
    p.stroke(journal, -0.008, y);
    states.push_back(stateOf(p.surface));
    EXPECT_NE(states.back(), states[states.size() - 2]);
  }
  ASSERT_EQ(journal.undoCount(), 4u);
  EXPECT_GT(journal.bytes(), 0u);
  for (int k = 3; k >= 0; --k) {
    ASSERT_TRUE(journal.undo());
    EXPECT_EQ(stateOf(p.surface), states[size_t(k)]) << "after undoing stroke " << k;
  }
  EXPECT_FALSE(journal.undo());
  EXPECT_EQ(p.surface.childCount(), 0u);
  for (size_t k = 1; k <= 4; ++k) {
    ASSERT_TRUE(journal.redo());
    EXPECT_EQ(stateOf(p.surface), states[k]) << "after redoing stroke " << k;
  }
  EXPECT_FALSE(journal.redo());
  // A new stroke after an undo forgets the redo.
  ASSERT_TRUE(journal.undo());
  p.stroke(journal, 0.0, -0.02);
  EXPECT_EQ(journal.redoCount(), 0u);
  EXPECT_EQ(journal.undoCount(), 4u);
}

TEST(PaintJournal, BackgroundWorkOutsideRecordingIsNotJournalled) {
  Painter p;
  p.paint.drying_rate = 0.5;
  PaintJournal journal(p.surface);
  p.stroke(journal, -0.008, 0.0);
  const size_t bytes = journal.bytes();
  PaintDryer dryer(p.paint.drying_rate, p.paint.drying);
  journal.beginStroke();
  dryer.run(p.surface, 10.0, p.surface.originalCount());  // no Recording: not journalled
  EXPECT_FALSE(journal.endStroke());
  EXPECT_EQ(journal.bytes(), bytes);
  EXPECT_EQ(journal.undoCount(), 1u);
}

TEST(PaintJournal, KeepsWithinItsMemoryBoundByForgettingTheOldestStrokes) {
  Painter p;
  PaintJournal unbounded(p.surface);
  p.stroke(unbounded, -0.008, -0.01);
  const size_t one_stroke = unbounded.bytes();
  ASSERT_GT(one_stroke, 0u);
  // (one journal per surface: the bounded one observes a second painter)
  Painter q;
  PaintJournal bounded(q.surface, size_t(2.5 * double(one_stroke)));
  for (double y : {-0.01, 0.0, 0.01, 0.02}) q.stroke(bounded, -0.008, y);
  EXPECT_LE(bounded.bytes(), bounded.maxBytes());
  EXPECT_GE(bounded.undoCount(), 1u);
  EXPECT_LT(bounded.undoCount(), 4u);
  EXPECT_THROW(PaintJournal(q.surface), std::logic_error);  // already observed
}

TEST(PaintJournal, ReportsTheHeapItHolds) {
#if defined(RC_SANITIZER_ALLOCATOR)
  GTEST_SKIP() << "glibc's heap statistics do not see the sanitizer's allocator";
#endif
  // bytes() is what the session's ~journal_bytes bounds and paint_stats reports (the soak subtracts it from
  // the node's memory): it must count the heap the journal holds, allocator headers and array room included.
#ifndef RC_HAVE_MALLINFO2
  GTEST_SKIP() << "needs glibc's mallinfo2 (glibc >= 2.33)";
#else
  Painter p;
  PaintJournal journal(p.surface);
  for (double y : {-0.01, 0.0, 0.01, 0.02}) p.stroke(journal, -0.008, y);
  const size_t reported = journal.bytes();
  ASSERT_GT(reported, 100000u);
  const size_t in_use_before = mallinfo2().uordblks + mallinfo2().hblkhd;
  journal.clear();  // frees exactly what the journal holds
  const size_t in_use_after = mallinfo2().uordblks + mallinfo2().hblkhd;
  ASSERT_GT(in_use_before, in_use_after);
  const double held = double(in_use_before - in_use_after);
  EXPECT_NEAR(double(reported) / held, 1.0, 0.1) << "reported " << reported << " bytes, held " << held;
#endif
}

}  // namespace
}  // namespace rc
