// Rendering while painting (thesis 5.7, 5.8, Table 5.1): full updates of a 10 cm sphere of 300k and 750k
// surfels at 1280x720, with and without keeping the sums a differential update needs; differential updates
// along a painted stroke (every event's delta, as the paint model publishes it) and for recoloured patches of
// growing size, against the full update of the same state in the same run (the crossover sets the default
// max_delta_surfels); the accuracy of the differential image against a full render after the stroke. Prints
// tables; `--quick` fewer repetitions; `--csv FILE` writes every differential update (the scatter plot of
// scripts/plot_differential_rendering.py).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench_paint_stroke.h"
#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/paint_transfer.h"
#include "relaxed_connectivity/paint/paint_type_reader.h"
#include "relaxed_connectivity/paint/painted_cloud_mirror.h"
#include "relaxed_connectivity/render/splat/differential_renderer.h"
#include "relaxed_connectivity/surface/analytic_shapes.h"

namespace {

using rc::Vec3;
using rc::bench::kEvent;
using rc::bench::kRadius;
using rc::bench::median;
using rc::bench::strokePose;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

/// The painting view: 1280x720, 60 degrees, the sphere (and the stroke over its top) filling the height.
rc::Camera paintingCamera() {
  rc::Camera camera = rc::Camera::perspective(1280, 720, 60 * M_PI / 180);
  camera.lookAt(Vec3(0.05, -0.2, 0.14), Vec3(0, 0, 0.02));
  return camera;
}

rc::SurfelCloud coloredSphere(size_t count) {
  rc::SurfelCloud c = rc::AnalyticSphere(Vec3::Zero(), kRadius).sample(count);
  c.radii.assign(count, kRadius * std::sqrt(4.0 / count));
  c.colors.assign(count, rc::Rgba{230, 225, 210, 255});
  return c;
}

rc::DifferentialRenderConfig sessionConfig(int threads, bool cull) {
  rc::DifferentialRenderConfig config;
  config.splat.threads = threads;
  config.splat.backface_culling = cull;
  config.max_delta_surfels = size_t(1) << 40;  // never a full update: measure the partial one
  return config;
}

struct Difference {
  double mean = 0;
  int worst = 0;
  size_t over_two = 0;
};

Difference compare(const rc::RenderImages& a, const rc::RenderImages& b) {
  Difference d;
  for (size_t p = 0; p < a.color.size(); ++p) {
    int w = 0;
    for (int c = 0; c < 3; ++c) w = std::max(w, std::abs(int(a.color[p][c]) - int(b.color[p][c])));
    d.mean += w;
    d.worst = std::max(d.worst, w);
    d.over_two += w > 2;
  }
  d.mean /= double(std::max<size_t>(a.color.size(), 1));
  return d;
}

void fullUpdates(int runs) {
  std::printf(
      "Full update at 1280x720 (Table 5.1): colour + depth images, the 10 cm sphere filling the view "
      "height;\n"
      "median (min-max) of %d frames after 2 warm-up frames. render: SurfelRenderer alone; full update: the\n"
      "same frame keeping the sums for differential updates (DifferentialSurfelRenderer::renderFull).\n"
      "Target: >= 30 full updates/s at 750k on 2 cores. Thesis (GPU, 2007): a full update per 30 Hz frame "
      "was\n"
      "out of reach at 300k-750k surfels, hence differential updates.\n\n",
      runs);
  std::printf("%-8s %-7s %-6s %18s %22s %10s %10s\n", "surfels", "threads", "faces", "render ms",
              "full update ms", "updates/s", "keep cost");
  for (const size_t count : {size_t(300000), size_t(750000)}) {
    const rc::SurfelCloud sphere = coloredSphere(count);
    const rc::Camera camera = paintingCamera();
    for (const int threads : {1, 2}) {
      for (const bool cull : {false, true}) {
        const rc::DifferentialRenderConfig config = sessionConfig(threads, cull);
        rc::SurfelRenderer plain(config.splat);
        rc::DifferentialSurfelRenderer differential(config);
        rc::RenderImages images;
        std::vector<double> render_ms, full_ms;
        for (int r = 0; r < runs + 2; ++r) {  // interleaved: both see the same machine state
          auto t = Clock::now();
          plain.render(sphere, camera, &images);
          if (r >= 2) render_ms.push_back(msSince(t));
          t = Clock::now();
          differential.renderFull(sphere, camera);
          if (r >= 2) full_ms.push_back(msSince(t));
        }
        const double full = median(full_ms);
        std::printf("%-8zu %-7d %-6s %7.1f (%.1f-%.1f) %11.1f (%.1f-%.1f) %10.1f %9.2fx\n", count, threads,
                    cull ? "front" : "both", median(render_ms),
                    *std::min_element(render_ms.begin(), render_ms.end()),
                    *std::max_element(render_ms.begin(), render_ms.end()), full,
                    *std::min_element(full_ms.begin(), full_ms.end()),
                    *std::max_element(full_ms.begin(), full_ms.end()), 1e3 / full, full / median(render_ms));
      }
    }
  }
}

struct Sample {
  const char* kind;
  size_t updated, tiles, fragments;
  double ms;
};

/// Paints the shared stroke (round brush, acrylic) over the 750k sphere; every event's delta goes through a
/// mirror into the differential renderer. Returns the samples; prints the accuracy against a full render.
std::vector<Sample> strokeDeltas(const std::string& config_dir, int events, double* full_ms) {
  const rc::SurfelCloud sphere = coloredSphere(750000);
  rc::PaintSurface surface(sphere);
  const rc::BrushPreset preset = rc::readBrushPreset(config_dir + "brushes/round.yaml");
  const rc::PaintType paint = rc::readPaintType(config_dir + "paints/acrylic.yaml");
  rc::Brush brush(preset);
  rc::loadBrush(brush.skin(), paint);
  brush.reset(strokePose(0, preset.bristle_length, -0.002));
  rc::PaintedCloudMirror mirror;
  mirror.reset(surface.activeCloud());
  surface.takeChangedOriginals();
  const rc::Camera camera = paintingCamera();
  rc::DifferentialSurfelRenderer renderer(sessionConfig(2, false));
  std::vector<double> full_runs;  // steady state: the first frame also allocates
  for (int r = 0; r < 5; ++r) {
    rc::DifferentialStats full;
    renderer.renderFull(mirror.cloud(), camera, &full);
    if (r > 0) full_runs.push_back(full.total_ms);
  }
  *full_ms = median(full_runs);
  std::vector<Sample> samples;
  std::vector<double> apply_ms;
  for (int e = 1; e <= events; ++e) {
    brush.advance(kEvent, strokePose(e, preset.bristle_length, 0.006), &surface);
    rc::transferPaint(brush, surface, paint, kEvent);
    const std::vector<uint32_t> changed = surface.takeChangedOriginals();
    if (changed.empty()) continue;
    const auto t = Clock::now();
    rc::SurfelCloud removed, added;
    mirror.applyDelta(changed, surface.activeCloudOf(changed), &removed, &added);
    apply_ms.push_back(msSince(t));
    rc::DifferentialStats stats;
    renderer.update(mirror.cloud(), removed, added, camera, &stats);
    samples.push_back(
        {"stroke", removed.size() + added.size(), stats.tiles, stats.fragments, stats.total_ms});
  }
  rc::DifferentialSurfelRenderer reference(sessionConfig(2, false));
  reference.renderFull(surface.activeCloud(), camera);
  const Difference d = compare(renderer.images(), reference.images());
  std::printf(
      "\nAccuracy after the stroke (%zu deltas, %zu active surfels): the differential image against a full\n"
      "render of the painted sphere: mean %.3f levels over the image, worst %d, %zu pixels off by more than "
      "2\n"
      "(acrylic's imprints move surfels by 0.1 mm; the partial update keeps the full render's visibility "
      "bounds,\n"
      "5.7). Mirror (delta -> removed/added lists): median %.3f ms per event.\n",
      samples.size(), surface.activeCount(), d.mean, d.worst, d.over_two, median(apply_ms));
  return samples;
}

constexpr size_t kPatchSizes[] = {500, 1000, 2500, 5000, 10000, 20000, 40000, 80000, 160000};

/// Recolours the k surfels nearest a point of the visible cap: k removed + k added.
std::vector<Sample> patchDeltas(int runs) {
  const rc::SurfelCloud sphere = coloredSphere(750000);
  const rc::Camera camera = paintingCamera();
  rc::DifferentialSurfelRenderer renderer(sessionConfig(2, false));
  renderer.renderFull(sphere, camera);
  std::vector<Sample> samples;
  std::vector<size_t> order(sphere.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  int spot = 0;
  for (const size_t k : kPatchSizes) {
    for (int r = 0; r < runs; ++r, ++spot) {
      const double a = 0.7 * spot;  // spots over the cap facing the camera
      const Vec3 centre = kRadius * Vec3(0.3 * std::cos(a), -0.4 + 0.2 * std::sin(a), 0.8).normalized();
      std::nth_element(order.begin(), order.begin() + k, order.end(), [&](size_t x, size_t y) {
        return (sphere.positions[x] - centre).squaredNorm() < (sphere.positions[y] - centre).squaredNorm();
      });
      std::vector<size_t> chosen(order.begin(), order.begin() + k);
      rc::SurfelCloud removed = sphere, added;
      removed.select(chosen);
      added = removed;
      for (rc::Rgba& c : added.colors) c = rc::Rgba{uint8_t(40 + spot % 200), 80, 160, 255};
      rc::DifferentialStats stats;
      renderer.update(sphere, removed, added, camera, &stats);  // (the state itself is not needed here)
      samples.push_back({"patch", 2 * k, stats.tiles, stats.fragments, stats.total_ms});
      renderer.update(sphere, added, removed, camera, &stats);  // back
    }
  }
  return samples;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  const char* csv_path = nullptr;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--quick")) quick = true;
    if (!std::strcmp(argv[a], "--csv") && a + 1 < argc) csv_path = argv[++a];
  }
  const std::string config_dir = std::string(RC_SOURCE_DIR) + "/config/paint/";
  fullUpdates(quick ? 3 : 9);

  double stroke_full_ms = 0;
  std::vector<Sample> samples = strokeDeltas(config_dir, quick ? 120 : 300, &stroke_full_ms);
  std::vector<Sample> patches = patchDeltas(quick ? 3 : 7);

  std::printf(
      "\nDifferential updates on the 750k sphere at 1280x720, 2 threads (un-splat + splat + renormalise the\n"
      "touched tiles, set-up included; a full update of the same state in this run: %.1f ms). Stroke: every\n"
      "event's delta of the painted stroke (round brush, acrylic), binned by surfels updated (removed + "
      "added);\n"
      "patch: the k nearest surfels recoloured (2k updated), median of the runs. Thesis (GPU, 2007): 5,000\n"
      "surfels in 15 ms; target <= 2 ms.\n\n",
      stroke_full_ms);
  std::printf("%-7s %-18s %8s %10s %10s %12s %10s\n", "kind", "surfels updated", "deltas", "median ms",
              "max ms", "tiles", "vs full");
  auto report = [&](const char* kind, const std::vector<Sample>& all, size_t lo, size_t hi) {
    std::vector<double> ms;
    std::vector<double> tiles;
    for (const Sample& s : all)
      if (s.updated >= lo && s.updated < hi) {
        ms.push_back(s.ms);
        tiles.push_back(double(s.tiles));
      }
    if (ms.empty()) return;
    char range[32];
    std::snprintf(range, sizeof(range), "%zu-%zu", lo, hi - 1);
    std::printf("%-7s %-18s %8zu %10.3f %10.3f %12.0f %9.3fx\n", kind, range, ms.size(), median(ms),
                *std::max_element(ms.begin(), ms.end()), median(tiles), median(ms) / stroke_full_ms);
  };
  const size_t bins[] = {1, 500, 1000, 2000, 3000, 4000, 5000, 7500, 10000};
  for (size_t b = 0; b + 1 < sizeof(bins) / sizeof(bins[0]); ++b)
    report("stroke", samples, bins[b], bins[b + 1]);
  for (const size_t k : kPatchSizes) report("patch", patches, 2 * k, 2 * k + 1);
  std::printf(
      "\nLeft out: the paint model's work (bench_paint_model), the message transport and the image copy "
      "into\n"
      "the ROS message (measured end to end by the session: docs/benchmarks.md, latency).\n");

  if (csv_path) {
    FILE* f = std::fopen(csv_path, "w");
    if (!f) {
      std::fprintf(stderr, "bench_paint_rendering: cannot write %s\n", csv_path);
      return 1;
    }
    std::fprintf(f, "kind,updated_surfels,ms,tiles,fragments\n");
    for (const std::vector<Sample>* set : {&samples, &patches})
      for (const Sample& s : *set)
        std::fprintf(f, "%s,%zu,%.4f,%zu,%zu\n", s.kind, s.updated, s.ms, s.tiles, s.fragments);
    std::fprintf(f, "full,750000,%.4f,0,0\n", stroke_full_ms);
    std::fclose(f);
    std::printf("wrote %s\n", csv_path);
  }
  return 0;
}
