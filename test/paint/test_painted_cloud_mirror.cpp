// The viewer's copy of the painted object (PaintedCloudMirror) follows the paint model's deltas exactly, and
// a differential renderer (5.7) fed with them shows what a full render of the painted object shows.
#include "relaxed_connectivity/paint/painted_cloud_mirror.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <tuple>

#include "paint_test_surfaces.h"
#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/paint_transfer.h"
#include "relaxed_connectivity/paint/paint_type_reader.h"
#include "relaxed_connectivity/paint/painted_surface_io.h"
#include "relaxed_connectivity/paint/stroke_file.h"
#include "relaxed_connectivity/render/splat/differential_renderer.h"

namespace rc {
namespace {

std::string configPath(const std::string& relative) {
  return std::string(RC_SOURCE_DIR) + "/config/paint/" + relative;
}

using SurfelKey = std::tuple<double, double, double, double, double, double, double, int, int, int>;

/// The surfels of a cloud as a sorted list (order-free comparison), all render channels bitwise.
std::vector<SurfelKey> surfelKeys(const SurfelCloud& c) {
  std::vector<SurfelKey> keys;
  for (size_t i = 0; i < c.size(); ++i)
    keys.emplace_back(c.positions[i].x(), c.positions[i].y(), c.positions[i].z(), c.normals[i].x(),
                      c.normals[i].y(), c.normals[i].z(), c.radii[i], c.colors[i][0], c.colors[i][1],
                      c.colors[i][2]);
  std::sort(keys.begin(), keys.end());
  return keys;
}

/// The surfels of the listed originals, from a whole active cloud.
SurfelCloud groupsOf(const SurfelCloud& active, const std::vector<uint32_t>& originals) {
  const Attribute* father = active.attributes.find(kSurfelFather);
  SurfelCloud out;
  for (size_t i = 0; i < active.size(); ++i) {
    const uint32_t f = uint32_t(father->get(i));
    if (std::find(originals.begin(), originals.end(), f) == originals.end()) continue;
    out.positions.push_back(active.positions[i]);
    out.normals.push_back(active.normals[i]);
    out.radii.push_back(active.radii[i]);
    out.colors.push_back(active.colors[i]);
  }
  return out;
}

Camera boardCamera() {
  Camera camera = Camera::perspective(320, 240, 40 * M_PI / 180);
  camera.lookAt(Vec3(0.05, -0.12, 0.1), Vec3(0, 0, 0));
  return camera;
}

struct StrokeComparison {
  size_t deltas = 0, painted = 0, over_two = 0;
  int worst = 0;
  double mean_painted = 0;  ///< mean of the largest channel difference over the painted pixels
};

/// Paints the straight stroke with `paint_name` on a board, following every delta with a mirror and a
/// differential renderer, and compares its image with a full render of the painted board.
StrokeComparison paintAndCompare(const std::string& paint_name) {
  PaintSurface surface(paint_test::planeCloud(0.06, 0.002));
  PaintedCloudMirror mirror;
  mirror.reset(surface.activeCloud());
  surface.takeChangedOriginals();
  StrokeComparison result;
  EXPECT_EQ(mirror.size(), surface.activeCount());

  DifferentialRenderConfig config;
  config.splat.threads = 2;
  DifferentialSurfelRenderer renderer(config);
  const Camera camera = boardCamera();
  renderer.renderFull(mirror.cloud(), camera);

  const StrokeSampler sampler(readStrokeFile(configPath("strokes/straight.csv")));
  Brush brush(readBrushPreset(configPath("brushes/round.yaml")));
  const PaintType paint = readPaintType(configPath("paints/" + paint_name + ".yaml"));
  loadBrush(brush.skin(), paint);
  auto pose = [&](double t) { return sampler.at(t).pose(); };
  const double dt = 1.0 / 60;
  brush.reset(pose(sampler.startTime()));
  SurfelCloud before = surface.activeCloud();
  size_t deltas = 0, differential = 0, largest = 0;
  for (double t = sampler.startTime() + dt; t <= sampler.startTime() + sampler.duration(); t += dt) {
    brush.advance(dt, pose(t), &surface);
    transferPaint(brush, surface, paint, dt);
    const std::vector<uint32_t> changed = surface.takeChangedOriginals();
    if (changed.empty()) continue;
    ++deltas;
    SurfelCloud removed, added;
    const SurfelCloud delta =
        surface.activeCloudOf(changed, /*paint_columns=*/false);  // as paint_model sends it
    EXPECT_EQ(delta.attributes.columns().size(), 2u);             // father and reflectivity: no paint columns
    mirror.applyDelta(changed, delta, &removed, &added);
    // What went is exactly what the changed originals showed before, what came what they show now.
    EXPECT_EQ(surfelKeys(removed), surfelKeys(groupsOf(before, changed)));
    EXPECT_EQ(surfelKeys(added), surfelKeys(surface.activeCloudOf(changed)));
    EXPECT_EQ(mirror.size(), surface.activeCount());
    DifferentialStats stats;
    renderer.update(mirror.cloud(), removed, added, camera, &stats);
    differential += stats.update == RenderUpdate::kDifferential;
    largest = std::max(largest, removed.size() + added.size());
    before = surface.activeCloud();
  }
  EXPECT_GT(deltas, 60u);
  EXPECT_EQ(differential, deltas);
  EXPECT_GT(surface.childCount(), 500u);
  EXPECT_EQ(surfelKeys(mirror.cloud()), surfelKeys(surface.activeCloud()));

  // The differential image against a full render of the painted board (same camera): paint resampling keeps
  // the geometry, so only float rounding and the kept visibility bounds differ.
  DifferentialSurfelRenderer reference(config);
  reference.renderFull(surface.activeCloud(), camera);
  size_t& painted = result.painted;
  size_t& over_two = result.over_two;
  int& worst = result.worst;
  const RenderImages& a = renderer.images();
  const RenderImages& b = reference.images();
  const RenderImages unpainted = [&] {
    DifferentialSurfelRenderer r(config);
    r.renderFull(PaintSurface(paint_test::planeCloud(0.06, 0.002)).activeCloud(), camera);
    return r.images();
  }();
  for (size_t p = 0; p < a.color.size(); ++p) {
    int d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(a.color[p][c]) - int(b.color[p][c])));
    worst = std::max(worst, d);
    over_two += d > 2;
    if (b.color[p] == unpainted.color[p]) continue;
    ++painted;
    result.mean_painted += d;
  }
  result.deltas = deltas;
  result.mean_painted /= double(std::max<size_t>(painted, 1));
  std::printf(
      "%s: %zu deltas (largest %zu surfels), %zu painted pixels, worst %d levels, mean %.2f over the "
      "painted pixels, %zu pixels over 2\n",
      paint_name.c_str(), deltas, largest, painted, worst, result.mean_painted, over_two);
  return result;
}

// Watercolour resamples without changing the geometry: the differential image equals a full render to one
// level although every event un-splats and splats thousands of surfels.
TEST(PaintedCloudMirror, FollowsAPaintedStrokeAndFeedsTheDifferentialRenderer) {
  const StrokeComparison c = paintAndCompare("watercolour");
  EXPECT_GT(c.painted, 1000u);  // the stroke is visible
  EXPECT_LE(c.worst, 1);
}

// Acrylic leaves bristle imprints (0.1 mm, 5.6.3), deeper than the depth tolerance of the small children: a
// full render separates the ridges by depth, the partial update keeps the unpainted board's visibility bounds
// and blends them (the thesis' stated limitation, 5.7). Measured 2026-11-29: worst 48 levels, mean 1.4 levels
// over the painted pixels with exact silhouettes (worst 96, mean 2.8 with the filtered footprint); a full
// update (camera motion, the next full cloud) shows the ridges.
TEST(PaintedCloudMirror, ImprintsDifferOnlyWithinTheStatedBound) {
  const StrokeComparison c = paintAndCompare("acrylic");
  EXPECT_GT(c.painted, 2000u);
  EXPECT_LT(c.mean_painted, 3.0);
  EXPECT_LE(c.over_two, c.painted / 2);
}

TEST(PaintedCloudMirror, BadDeltasAreRejectedAndChangeNothing) {
  PaintSurface surface(paint_test::planeCloud(0.01, 0.002));
  PaintedCloudMirror mirror;
  mirror.reset(surface.activeCloud());
  const std::vector<SurfelKey> state = surfelKeys(mirror.cloud());
  const SurfelCloud some = surface.activeCloudOf({3, 4});
  SurfelCloud removed, added;
  try {
    mirror.applyDelta({3}, some, &removed, &added);  // a surfel of original 4, which is not listed
    FAIL() << "a surfel whose father is not listed was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("father 4"), std::string::npos) << e.what();
  }
  SurfelCloud no_father = some;
  no_father.attributes.remove(kSurfelFather);
  EXPECT_THROW(mirror.applyDelta({3, 4}, no_father, &removed, &added), std::invalid_argument);
  SurfelCloud no_colours = some;
  no_colours.colors.clear();
  EXPECT_THROW(mirror.applyDelta({3, 4}, no_colours, &removed, &added), std::invalid_argument);
  SurfelCloud no_normals = surface.activeCloud();
  no_normals.normals.clear();
  EXPECT_THROW(mirror.reset(no_normals), std::invalid_argument);
  EXPECT_TRUE(removed.empty() && added.empty());
  EXPECT_EQ(surfelKeys(mirror.cloud()), state);

  // An original listed without surfels empties its group; a repeated one is harmless; a new one is added.
  mirror.applyDelta({3, 3}, SurfelCloud(), &removed, &added);
  EXPECT_EQ(removed.size(), 1u);
  EXPECT_TRUE(mirror.surfelsOf(3).empty());
  EXPECT_EQ(mirror.size(), state.size() - 1);
  mirror.applyDelta({3, 4}, some, nullptr, nullptr);
  EXPECT_EQ(surfelKeys(mirror.cloud()), state);
  for (uint32_t i = 0; i < surface.originalCount(); ++i)
    for (uint32_t index : mirror.surfelsOf(i))
      ASSERT_EQ(mirror.cloud().positions[index], surface.originals().positions[i]);
}

}  // namespace
}  // namespace rc
