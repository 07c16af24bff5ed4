// Paint events (thesis 5.5): one main-loop event of the brush (advance) and the paint transfer (one paint
// buffer per tip, splats, exchange, resampling, gather) along a stroke over a sphere of 300k and 750k
// surfels, the time split into the two; the paint buffer's pixel size against the work and the surfels it
// creates; the speed/accuracy curve of the pixel size (wet paint per unit area across a straight stroke on a
// board against a reference at 1/16 of a brush surfel: RMS error, 10-90 % edge width, time, surfels); the
// background work (drying, diffusion, downsampling) and memory per surfel. Single-threaded. Prints tables;
// `--quick` uses fewer events; `--curve` runs only the curve; `--csv FILE` writes the curve.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench_paint_stroke.h"
#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/paint_downsampling.h"
#include "relaxed_connectivity/paint/paint_dryer.h"
#include "relaxed_connectivity/paint/paint_transfer.h"
#include "relaxed_connectivity/paint/paint_type_reader.h"
#include "relaxed_connectivity/paint/surface_diffusion.h"
#include "relaxed_connectivity/surface/analytic_shapes.h"

namespace {

using rc::Vec3;
using Clock = std::chrono::steady_clock;

using rc::bench::kEvent;
using rc::bench::kLean;
using rc::bench::kRadius;
using rc::bench::kSpeed;
using rc::bench::median;
using rc::bench::strokePose;

struct Run {
  std::vector<double> brush_us, paint_us, buffer_us, exchange_us, resample_us;
  size_t children = 0, pixels = 0;
};

Run stroke(const rc::BrushPreset& preset, const rc::PaintType& paint, const rc::SurfelCloud& object,
           const rc::PaintTransferOptions& options, int events) {
  rc::PaintSurface surface(object);
  rc::Brush brush(preset);
  brush.reset(strokePose(0, preset.bristle_length, -0.002));
  Run run;
  for (int e = 1; e <= 30 + events; ++e) {
    const auto t0 = Clock::now();
    brush.advance(kEvent, strokePose(e, preset.bristle_length, 0.006), &surface);
    const auto t1 = Clock::now();
    const rc::PaintEventStats s = rc::transferPaint(brush, surface, paint, kEvent, options);
    const auto t2 = Clock::now();
    if (e <= 30) continue;
    run.brush_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    run.paint_us.push_back(std::chrono::duration<double, std::micro>(t2 - t1).count());
    run.buffer_us.push_back(1e6 * s.buffer_seconds);
    run.exchange_us.push_back(1e6 * s.exchange_seconds);
    run.resample_us.push_back(1e6 * s.resample_seconds);
    run.pixels += size_t(s.penetrated_pixels);
  }
  run.children = surface.childCount();
  return run;
}

/// The plane z = 0 sampled every h over [-half, half]^2 (normals +z, radii 0.75 h, white).
rc::SurfelCloud board(double half, double h) {
  rc::SurfelCloud c;
  const int n = int(std::round(half / h));
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) c.positions.push_back(Vec3(i * h, j * h, 0));
  c.normals.assign(c.size(), Vec3::UnitZ());
  c.radii.assign(c.size(), 0.75 * h);
  return c;
}

/// A straight stroke along +x over the board, the stylus leaning 30 degrees back, pressed `press`; the
/// brush turned about its axis so that the flat brush's width lies across the stroke (along y).
Eigen::Isometry3d boardPose(double x, double bristle_length, double press) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() =
      (Eigen::Quaterniond::FromTwoVectors(Vec3(0, 0, -1), Vec3(-std::sin(kLean), 0, -std::cos(kLean))) *
       Eigen::AngleAxisd(0.5 * M_PI, Vec3::UnitZ()))
          .toRotationMatrix();
  t.translation() = Vec3(x, 0, bristle_length - press);
  return t;
}

constexpr double kBoardSpacing = 0.001, kProbeHalf = 0.01, kProbeStep = 5e-5, kBandHalf = 0.005,
                 kBandStep = 1e-4;

struct StripeRun {
  std::vector<double> thickness;  // wet volume per unit area [per mm^2] across the stripe, mean along it
  double centre_alpha = 0;        // alpha of (5.8) at the probe on the stroke's axis
  double probe_x = 0;             // where the probe line crosses the stroke
  double event_us = 0;            // median paint transfer per event
  size_t children = 0, active = 0;
};

/// Paints a 2 cm stroke along +x with `preset` loaded with `paint` on a white board sampled every 1 mm, with
/// buffer pixels of `pixel`, and reads the wet paint per unit area (the volume of the active surfel nearest
/// each probe over its area: a child's pixel squared, an original's 1 mm squared) across the stroke every
/// 0.05 mm over +-10 mm, each the mean of the probes every 0.1 mm along the stroke over +-5 mm around
/// `probe_x` (NaN: the middle of the painted children's x range).
StripeRun stripe(const rc::BrushPreset& preset, const rc::PaintType& paint, double pixel, double probe_x) {
  rc::PaintSurface surface(board(0.03, kBoardSpacing));
  rc::Brush brush(preset);
  rc::loadBrush(brush.skin(), paint);
  const double l = preset.bristle_length;
  brush.reset(boardPose(-0.01, l, 0));
  rc::PaintTransferOptions options;
  options.pixel_size = pixel;
  std::vector<double> us;
  for (int e = 1; e <= 40; ++e) {
    const double press = 0.004 * std::min(1.0, e / 10.0), x = -0.01 + 0.02 * std::max(0, e - 10) / 30.0;
    brush.advance(kEvent, boardPose(x, l, press), &surface);
    const auto t0 = Clock::now();
    rc::transferPaint(brush, surface, paint, kEvent, options);
    if (e > 10) us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
  }
  StripeRun run;
  run.event_us = median(us);
  run.children = surface.childCount();
  run.active = surface.activeCount();
  std::vector<Vec3> positions;
  std::vector<const rc::PaintState*> states;
  std::vector<double> areas;
  double xmin = 1, xmax = -1;
  const rc::PaintSurface& painted = surface;  // (const: reading the children notifies no observer)
  for (size_t i = 0; i < painted.originalCount(); ++i) {
    if (painted.enabled(i)) {
      positions.push_back(painted.originals().positions[i]);
      states.push_back(&painted.originalPaint(i));
      areas.push_back(kBoardSpacing * kBoardSpacing);
    }
    for (const rc::ChildSurfel& c : painted.children(i)) {
      positions.push_back(c.position);
      states.push_back(&c.paint);
      areas.push_back(c.radius * c.radius);  // one child per pixel, its radius one pixel
      if (c.paint.wet_volume > 0)
        xmin = std::min(xmin, c.position.x()), xmax = std::max(xmax, c.position.x());
    }
  }
  run.probe_x = std::isnan(probe_x) ? 0.5 * (xmin + xmax) : probe_x;
  const rc::KdTree tree(positions);
  const int n = int(std::lround(kProbeHalf / kProbeStep)), m = int(std::lround(kBandHalf / kBandStep));
  for (int k = -n; k <= n; ++k) {
    double sum = 0;
    for (int j = -m; j <= m; ++j) {
      rc::Neighbor nb;
      tree.knn(Vec3(run.probe_x + j * kBandStep, k * kProbeStep, 0), 1, &nb);
      sum += states[nb.index]->wet_volume / (1e6 * areas[nb.index]);
      if (k == 0 && j == 0)
        run.centre_alpha = std::min(1.0, states[nb.index]->optical_density * states[nb.index]->wet_volume);
    }
    run.thickness.push_back(sum / (2 * m + 1));
  }
  return run;
}

/// The profile's plateau: the median of the probes above half its largest value.
double plateau(const std::vector<double>& t) {
  const double top = *std::max_element(t.begin(), t.end());
  std::vector<double> in;
  for (double v : t)
    if (v > 0.5 * top) in.push_back(v);
  return median(in);
}

/// The 10-90 % width of the stripe's two edges (mean of both) [m], levels relative to the profile's plateau:
/// from each end of the probe line, the distance between the first probes at 10 % and at 90 %.
double edgeWidth(const std::vector<double>& t) {
  const double p = plateau(t);
  const auto first = [&](double level, bool from_left) {
    for (size_t k = 0; k < t.size(); ++k) {
      const size_t i = from_left ? k : t.size() - 1 - k;
      if (t[i] >= level * p) return double(k);
    }
    return double(t.size());
  };
  return 0.5 * kProbeStep * ((first(0.9, true) - first(0.1, true)) + (first(0.9, false) - first(0.1, false)));
}

/// Resident memory of this process [bytes].
double residentBytes() {
  long pages = 0, resident = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    std::fclose(f);
  }
  return double(resident) * 4096.0;
}

void speedAccuracyCurve(const std::string& config, const char* csv_path) {
  rc::PaintType paint = rc::readPaintType(config + "paints/acrylic.yaml");
  paint.imprint_depth = 0;  // no bristle ridges: they would pattern the stripe (and alias at coarse pixels)
  constexpr int kRuns = 3;
  std::printf(
      "\nSpeed/accuracy of the paint buffer's pixel size: a 2 cm stroke along +x on a white board sampled\n"
      "every 1 mm, acrylic without imprints, the flat brush's width across the stroke. Measured: the wet "
      "paint\n"
      "per unit area (volume of the active surfel nearest a probe over its area) across the stroke every\n"
      "0.05 mm over +-10 mm, each the mean of probes every 0.1 mm along 1 cm of the stroke's middle, "
      "against\n"
      "a reference run at 1/16 of a brush surfel (0.031 mm). RMS error: over the probes, relative to the\n"
      "reference's plateau. Edge: the 10-90 %% width of the stripe's edges (mean of both; levels relative "
      "to\n"
      "each run's own plateau). Alpha: (5.8)'s min(rho V_w, 1) at the stroke's centre. Paint us: median "
      "over\n"
      "%d runs of the median of 30 events' paint transfer. Surfels: active surfels on the board after the\n"
      "stroke (of them children).\n\n",
      kRuns);
  std::printf("%-6s %9s %11s %10s %10s %9s %9s %8s %9s\n", "brush", "pixel", "px/brush sf", "RMS error",
              "edge mm", "alpha", "paint us", "surfels", "children");
  FILE* csv = csv_path ? std::fopen(csv_path, "w") : nullptr;
  if (csv)
    std::fprintf(csv,
                 "brush,pixel_mm,pixels_per_brush_surfel,rms_error,edge_width_mm,reference_edge_width_mm,"
                 "centre_alpha,paint_us,surfels,children\n");
  for (const char* name : {"round", "flat"}) {
    const rc::BrushPreset preset = rc::readBrushPreset(config + "brushes/" + name + ".yaml");
    const StripeRun reference = stripe(preset, paint, preset.surfel_spacing / 16, std::nan(""));
    const double reference_plateau = plateau(reference.thickness),
                 reference_edge = edgeWidth(reference.thickness);
    std::printf("%-6s %6.3f mm %11.0f %10s %10.2f %9.3f %9.0f %8zu %9zu   (reference, 1 run)\n", name,
                1e3 * preset.surfel_spacing / 16, 16.0, "-", 1e3 * reference_edge, reference.centre_alpha,
                reference.event_us, reference.active, reference.children);
    for (const double fraction : {2.0, 1.0, 0.75, 0.5, 0.35, 0.25, 0.125}) {
      const double pixel = fraction * preset.surfel_spacing;
      StripeRun r;
      std::vector<double> us;
      for (int k = 0; k < kRuns; ++k) {
        r = stripe(preset, paint, pixel, reference.probe_x);
        us.push_back(r.event_us);
      }
      double sum = 0;
      for (size_t k = 0; k < r.thickness.size(); ++k)
        sum += (r.thickness[k] - reference.thickness[k]) * (r.thickness[k] - reference.thickness[k]);
      const double rms = std::sqrt(sum / double(r.thickness.size())) / reference_plateau,
                   edge = edgeWidth(r.thickness);
      std::printf("%-6s %6.3f mm %11.2f %10.4f %10.2f %9.3f %9.0f %8zu %9zu\n", name, 1e3 * pixel,
                  1.0 / fraction, rms, 1e3 * edge, r.centre_alpha, median(us), r.active, r.children);
      if (csv)
        std::fprintf(csv, "%s,%.4f,%.3f,%.6f,%.4f,%.4f,%.4f,%.1f,%zu,%zu\n", name, 1e3 * pixel,
                     1.0 / fraction, rms, 1e3 * edge, 1e3 * reference_edge, r.centre_alpha, median(us),
                     r.active, r.children);
    }
  }
  if (csv) std::fclose(csv);
  std::printf(
      "Left out: the reference is this model at a finer buffer, not an analytic stripe (the brush's own\n"
      "sampling sets the edge); probes read the nearest surfel, not a rendered image; the brush's advance\n"
      "(not timed here); the visible colour: (5.8) takes the wet volume per surfel, which falls with the\n"
      "pixel's area (the alpha column), so it is not compared across pixel sizes.\n");
}

void backgroundWork(const std::string& config, const rc::SurfelCloud& sphere) {
  std::printf(
      "\nBackground work on the painted 750k sphere (the node's defaults per 60 Hz tick), median of 20 "
      "calls:\n\n");
  const rc::PaintType water = rc::readPaintType(config + "paints/watercolour.yaml");
  const rc::BrushPreset preset = rc::readBrushPreset(config + "brushes/round.yaml");
  const double before = residentBytes();
  rc::PaintSurface surface(sphere);
  const double per_original = (residentBytes() - before) / double(surface.originalCount());
  rc::Brush brush(preset);
  rc::loadBrush(brush.skin(), water);
  brush.reset(strokePose(0, preset.bristle_length, -0.002));
  for (int e = 1; e <= 150; ++e) {
    brush.advance(kEvent, strokePose(e, preset.bristle_length, 0.006), &surface);
    rc::transferPaint(brush, surface, water, kEvent);
  }
  const auto timeOf = [](auto&& work) {
    std::vector<double> ms;
    for (int k = 0; k < 20; ++k) {
      const auto t0 = Clock::now();
      work(k);
      ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
    return median(ms);
  };
  rc::PaintDryer dryer(water.drying_rate, water.drying);
  const double dry_ms = timeOf([&](int k) { dryer.run(surface, 0.1 * k, 2000); });
  const auto wetCount = [&] {
    size_t wet = 0;
    for (size_t i = 0; i < surface.originalCount(); ++i) {
      wet += surface.enabled(i) && surface.originalPaint(i).wet_volume > 0;
      for (const rc::ChildSurfel& c : surface.children(i)) wet += c.paint.wet_volume > 0;
    }
    return wet;
  };
  struct DiffusionRow {
    size_t max_surfels, region = 0, wet = 0, wet_total = 0;
    double ms = 0;
  };
  std::vector<DiffusionRow> diffusion_rows;
  for (const size_t max_surfels : {size_t(1000), size_t(4000), size_t(20000)}) {
    rc::SurfaceDiffusionOptions o;
    o.max_surfels = max_surfels;
    rc::SurfaceDiffusion diffusion(water.diffusion, o);
    DiffusionRow row{max_surfels};
    row.wet_total = wetCount();  // (the rows run one after the other: the wet area grows)
    row.ms = timeOf([&](int) {
      const rc::SurfaceDiffusionStats st = diffusion.run(surface, o.time_step);
      row.region = std::max(row.region, st.surfels), row.wet = std::max(row.wet, st.wet_surfels);
    });
    diffusion_rows.push_back(row);
  }
  rc::PaintDownsampler downsampler;
  const double down_ms = timeOf([&](int) { downsampler.run(surface, 200); });
  std::printf("%-34s %10s %12s\n", "work", "ms / call", "ms / second");
  std::printf("%-34s %10.3f %12.1f\n", "drying, 2000 originals per tick", dry_ms, 60 * dry_ms);
  for (const DiffusionRow& r : diffusion_rows)
    std::printf("%-34s %10.3f %12.1f   (%zu surfels, %zu of the %zu wet ones per sweep)\n",
                ("diffusion sweep, max_surfels " + std::to_string(r.max_surfels)).c_str(), r.ms, 20 * r.ms,
                r.region, r.wet, r.wet_total);
  std::printf("%-34s %10.3f %12.1f\n", "downsampling, 200 fathers per tick", down_ms, 60 * down_ms);
  std::printf(
      "\nDiffusion runs one sweep per 0.05 s of simulated time over at most max_surfels surfels around the "
      "wet ones\n(the node's ~diffusion_surfels, default 4000): a wet area larger than that is diffused in "
      "turns, "
      "each part\nspreading slower than (5.14) by the share it gets (speed against accuracy).\n"
      "\nMemory: %.0f bytes per original surfel (resident set growth when the 750k object is built: "
      "geometry, "
      "paint,\nkd-tree, collision grid); a child surfel takes sizeof(ChildSurfel) = %zu bytes in its "
      "father's "
      "list (%zu\nchildren after 150 events).\n",
      per_original, sizeof(rc::ChildSurfel), surface.childCount());
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, curve_only = false;
  const char* csv_path = nullptr;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--quick")) quick = true;
    if (!std::strcmp(argv[a], "--curve")) curve_only = true;
    if (!std::strcmp(argv[a], "--csv") && a + 1 < argc) csv_path = argv[++a];
  }
  const int events = quick ? 60 : 300;
  const std::string config = std::string(RC_SOURCE_DIR) + "/config/paint/";
  if (curve_only) {
    speedAccuracyCurve(config, csv_path);
    return 0;
  }
  const rc::PaintType paint = rc::readPaintType(config + "paints/acrylic.yaml");
  std::printf(
      "Paint events along a stroke over a 10 cm sphere at %.2f m/s (1/30 s per event), acrylic paint, one "
      "core;\n"
      "median over %d events after 30 warm-up events. Thesis (Pentium 4): 30 events/s; target >= 120 "
      "events/s.\n\n",
      kSpeed, events);
  std::printf("%-8s %-6s %8s %9s %9s %9s %9s %9s %9s %9s %8s %8s\n", "surfels", "brush", "pixel", "brush us",
              "buffer", "exchange", "resample", "paint us", "event us", "events/s", "px/event", "children");
  for (const size_t count : {size_t(300000), size_t(750000)}) {
    rc::SurfelCloud sphere = rc::AnalyticSphere(Vec3::Zero(), kRadius).sample(count);
    sphere.radii.assign(count, kRadius * std::sqrt(4.0 / count));
    for (const char* name : {"round", "flat"}) {
      const rc::BrushPreset preset = rc::readBrushPreset(config + "brushes/" + name + ".yaml");
      for (const double pixels_per_surfel : {0.5, 1.0, 2.0}) {
        rc::PaintTransferOptions options;
        options.pixel_size = pixels_per_surfel * preset.surfel_spacing;
        const Run r = stroke(preset, paint, sphere, options, events);
        const double event = median(r.brush_us) + median(r.paint_us);
        std::printf("%-8zu %-6s %5.2f mm %9.1f %9.1f %9.1f %9.1f %9.1f %9.1f %9.0f %8.0f %8zu\n", count, name,
                    1e3 * options.pixel_size, median(r.brush_us), median(r.buffer_us), median(r.exchange_us),
                    median(r.resample_us), median(r.paint_us), event, 1e6 / event, double(r.pixels) / events,
                    r.children);
      }
    }
  }
  std::printf(
      "\nThe brush's skin spacing is 0.5 mm (both presets); 0.5 mm pixels are the thesis' choice (a pixel "
      "about one\n"
      "brush surfel). Left out: drying and diffusion (background work, below), rendering, the ROS "
      "messages.\n");
  speedAccuracyCurve(config, csv_path);
  rc::SurfelCloud sphere = rc::AnalyticSphere(Vec3::Zero(), kRadius).sample(750000);
  sphere.radii.assign(sphere.size(), kRadius * std::sqrt(4.0 / double(sphere.size())));
  backgroundWork(config, sphere);
  return 0;
}
