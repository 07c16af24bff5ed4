// Paint events (thesis 5.5): one main-loop event of the brush (advance) and the paint transfer (one paint
// buffer per tip, splats, exchange, resampling, gather) along a stroke over a sphere of 300k and 750k
// surfels, the time split into the two; and the paint buffer's pixel size against the work and the surfels it
// creates. Single-threaded. Prints tables; `--quick` uses fewer events.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/paint_transfer.h"
#include "relaxed_connectivity/paint/paint_type_reader.h"
#include "relaxed_connectivity/surface/analytic_shapes.h"

namespace {

using rc::Vec3;
using Clock = std::chrono::steady_clock;

constexpr double kRadius = 0.1, kEvent = 1.0 / 30, kSpeed = 0.1, kLean = 0.5235987755982988;

/// The stroke of bench_paint_brush: a great circle over the sphere, the stylus leaning 30 degrees back.
Eigen::Isometry3d strokePose(int e, double bristle_length, double press) {
  const double angle = kSpeed * kEvent * e / kRadius - 0.5;
  const Vec3 up(std::sin(angle), 0, std::cos(angle)), ahead(std::cos(angle), 0, -std::sin(angle));
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() =
      Eigen::Quaterniond::FromTwoVectors(Vec3(0, 0, -1), -std::cos(kLean) * up - std::sin(kLean) * ahead)
          .toRotationMatrix();
  t.translation() = (kRadius + bristle_length - press) * up;
  return t;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

struct Run {
  std::vector<double> brush_us, paint_us;
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
    run.pixels += size_t(s.penetrated_pixels);
  }
  run.children = surface.childCount();
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int events = quick ? 60 : 300;
  const std::string config = std::string(RC_SOURCE_DIR) + "/config/paint/";
  const rc::PaintType paint = rc::readPaintType(config + "paints/acrylic.yaml");
  std::printf(
      "Paint events along a stroke over a 10 cm sphere at %.2f m/s (1/30 s per event), acrylic paint, one "
      "core;\n"
      "median over %d events after 30 warm-up events. Thesis (Pentium 4): 30 events/s; target >= 120 "
      "events/s.\n\n",
      kSpeed, events);
  std::printf("%-8s %-6s %8s %11s %11s %11s %10s %14s %12s\n", "surfels", "brush", "pixel", "brush us",
              "paint us", "event us", "events/s", "pixels/event", "children");
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
        std::printf("%-8zu %-6s %6.2f mm %11.1f %11.1f %11.1f %10.0f %14.0f %12zu\n", count, name,
                    1e3 * options.pixel_size, median(r.brush_us), median(r.paint_us), event, 1e6 / event,
                    double(r.pixels) / events, r.children);
      }
    }
  }
  std::printf(
      "\nThe brush's skin spacing is 0.5 mm (both presets); 0.5 mm pixels are the thesis' choice (a pixel "
      "about one\n"
      "brush surfel). Left out: drying and diffusion (background work), rendering, the ROS messages.\n");
  return 0;
}
