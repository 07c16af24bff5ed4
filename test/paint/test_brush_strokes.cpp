// The shipped strokes (config/paint/strokes/) painted with the shipped brushes on the objects they were made
// for: replays are bitwise identical, no active mass ends inside the object, the brush splits on the edge of
// the block and never on the board.
#include <gtest/gtest.h>

#include <cstring>

#include "paint_test_surfaces.h"
#include "relaxed_connectivity/paint/brush.h"
#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/stroke_file.h"

namespace rc {
namespace {

std::string configPath(const std::string& relative) {
  return std::string(RC_SOURCE_DIR) + "/config/paint/" + relative;
}

struct Replay {
  std::vector<Vec3> trajectory;  // every node after every event, then the skin at the end
  int split_events = 0;
  double deepest_end = 0;  // deepest active mass at the end of an event, below the analytic surface [m]
};

/// Plays `stroke` at 60 events per second with `brush` on `object`; `depth_below` gives how far a point lies
/// inside the analytic object.
template <class DepthBelow>
Replay replay(const std::string& brush, const std::string& stroke, const PaintSurface& object,
              DepthBelow depth_below) {
  const StrokeSampler sampler(readStrokeFile(configPath("strokes/" + stroke)));
  Brush b(readBrushPreset(configPath("brushes/" + brush)));
  auto pose = [&](double t) { return sampler.at(t).pose(); };
  Replay r;
  const double dt = 1.0 / 60;
  b.reset(pose(sampler.startTime()));
  for (double t = sampler.startTime() + dt; t <= sampler.startTime() + sampler.duration() + 1e-9; t += dt) {
    b.advance(dt, pose(t), &object);
    const BrushSkeleton& s = b.skeleton();
    r.trajectory.insert(r.trajectory.end(), s.positions().begin(), s.positions().end());
    for (int a = 0; a < s.activeCount(); ++a)
      r.deepest_end = std::max(r.deepest_end, depth_below(s.positions()[s.handleCount() + a]));
    r.split_events += b.split().split;
  }
  r.trajectory.insert(r.trajectory.end(), b.skin().positions().begin(), b.skin().positions().end());
  return r;
}

void expectBitwiseEqual(const Replay& a, const Replay& b) {
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  EXPECT_EQ(std::memcmp(a.trajectory.data(), b.trajectory.data(), a.trajectory.size() * sizeof(Vec3)), 0);
}

TEST(BrushStrokes, BoardStrokesReplayIdenticallyWithoutSplittingOrSinking) {
  const PaintSurface board(paint_test::planeCloud(0.08, 0.001));
  const auto below = [](const Vec3& x) { return -x.z(); };
  for (const char* brush : {"round.yaml", "flat.yaml"})
    for (const char* stroke : {"straight.csv", "spiral.csv"}) {
      const Replay a = replay(brush, stroke, board, below);
      expectBitwiseEqual(a, replay(brush, stroke, board, below));
      EXPECT_EQ(a.split_events, 0) << brush << " " << stroke;
      EXPECT_LT(a.deepest_end, 1e-12) << brush << " " << stroke;
    }
}

TEST(BrushStrokes, TheFlatBrushSplitsOnTheEdgeOfTheBlock) {
  const PaintSurface block(paint_test::edgeCloud(0.1, 0.001));
  // Inside the block: x < 0 and z < 0; the depth is the distance to the nearer face.
  const auto below = [](const Vec3& x) { return x.x() < 0 && x.z() < 0 ? std::min(-x.x(), -x.z()) : 0.0; };
  const Replay flat = replay("flat.yaml", "edge.csv", block, below);
  expectBitwiseEqual(flat, replay("flat.yaml", "edge.csv", block, below));
  EXPECT_GT(flat.split_events, 0);
  EXPECT_LT(flat.deepest_end,
            2e-4);  // force shading rounds the edge over about one neighbourhood (10 surfels)
  const Replay round = replay("round.yaml", "edge.csv", block, below);
  EXPECT_LT(round.deepest_end, 2e-4);
}

}  // namespace
}  // namespace rc
