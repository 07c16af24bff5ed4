// rc_shell: runs a thin-shell scene file (thesis chapter 7; config/shell/*.yaml).
//   rc_shell SCENE.yaml [--frames N] [--out DIR] [--no-files] [--quiet]
//            [--render [--width W --height H --view X Y Z]]
// Writes the dense surfels (and crack discontinuity surfels) as PLY per output frame to DIR, prints a
// progress line per frame on stderr and one JSON line of run statistics on stdout (nodes, fibers, surfels,
// cracks, milliseconds per frame for forces / integration, material / fracture and surface animation, and
// the node sampling anisotropy of ShellNodes: median, worst, fraction above the threshold). Highly irregular
// node sampling (thesis 7.6) is reported as a warning on stderr. With --render, each written frame (the dense
// surfels, cut at cracks by the crack discontinuity surfels, 4.3) is also EWA-splatted (thesis 3.2) to
// DIR/<name>_NNNN.png by a camera framing the
// rest bounding box from a fixed direction, and the JSON line gets a "render" phase (ms per image). Exit
// codes: 0 ok, 1 other error (I/O, arguments), 2 bad scene file, 3 the simulation became unstable.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "relaxed_connectivity/render/csg/discontinuity_clipper.h"
#include "relaxed_connectivity/render/scene/framing_camera.h"
#include "relaxed_connectivity/render/splat/image_io.h"
#include "relaxed_connectivity/render/splat/surfel_renderer.h"
#include "relaxed_connectivity/shell/shell_scene_reader.h"
#include "relaxed_connectivity/shell/shell_scene_run.h"

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// Gives `cloud` normals and radii from its tangent axes where it has only those (crack surfels), so that
/// they survive SurfelCloud::append with the dense surfels (which have normals and radii, no axes).
void addNormalsAndRadiiFromAxes(rc::SurfelCloud* cloud) {
  if (!cloud->hasAxes()) return;
  if (!cloud->hasNormals()) {
    cloud->normals.resize(cloud->size());
    for (size_t i = 0; i < cloud->size(); ++i)
      cloud->normals[i] = cloud->axes1[i].cross(cloud->axes2[i]).normalized();
  }
  if (!cloud->hasRadii()) {
    cloud->radii.resize(cloud->size());
    for (size_t i = 0; i < cloud->size(); ++i)
      cloud->radii[i] = std::max(cloud->axes1[i].norm(), cloud->axes2[i].norm());
  }
}

/// Renders frames (dense surfels, cut by the crack discontinuity surfels) to <out>/<name>_NNNN.png with a
/// fixed camera.
class FrameRenderer {
 public:
  FrameRenderer(const rc::Camera& camera, std::string out_dir)
      : camera_(camera), out_dir_(std::move(out_dir)) {
    config_.outputs = rc::kOutputColor;
    renderer_ = std::make_unique<rc::SurfelRenderer>(config_);
  }

  void operator()(const rc::ShellSimulation& sim, int frame) {
    Clock::time_point t0 = Clock::now();
    const rc::SurfelCloud& cloud = sim.surfels();
    if (cloud.empty()) return;
    // Crack surfels are discontinuity surfels (4.3): invisible, they cut the dense surfels at the crack.
    // Skinned, each sits kCrackSurfelInset radii inside its material; its clip plane is the crack plane.
    std::unique_ptr<rc::DiscontinuityClipper> clipper;
    if (sim.crackCount() > 0 && !sim.crackSurfels().empty()) {
      rc::SurfelCloud cracks = sim.crackSurfels();
      addNormalsAndRadiiFromAxes(&cracks);
      for (size_t k = 0; k < cracks.size(); ++k)
        cracks.positions[k] +=
            rc::ShellSimulation::kCrackSurfelInset * cracks.radii[k] * cracks.normals[k].normalized();
      clipper = std::make_unique<rc::DiscontinuityClipper>(cloud, cracks);
      clipper->prepare();
    }
    renderer_->render(cloud, camera_, &images_, clipper.get());
    splat_ms_ += msSince(t0);
    t0 = Clock::now();
    char name[32];
    std::snprintf(name, sizeof name, "_%04d.png", frame);
    rc::writePng((std::filesystem::path(out_dir_) / (sim.scene().name + name)).string(), images_.color,
                 images_.width, images_.height);
    write_ms_ += msSince(t0);
    ++images_written_;
  }

  size_t images() const { return images_written_; }
  double splatMs() const { return splat_ms_; }  ///< totals over the images
  double writeMs() const { return write_ms_; }

 private:
  rc::Camera camera_;
  std::string out_dir_;
  rc::SplatConfig config_;
  std::unique_ptr<rc::SurfelRenderer> renderer_;
  rc::RenderImages images_;
  size_t images_written_ = 0;
  double splat_ms_ = 0.0, write_ms_ = 0.0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rc_shell: point-sampled thin shells: elasticity, plasticity, fracture (thesis chapter 7)"};
  std::string scene_path, out_dir = ".";
  int frames = 0;
  bool quiet = false, no_files = false, render = false;
  uint32_t width = 640, height = 480;
  std::vector<double> view = {0.8, -1.1, 0.7};
  app.add_option("scene", scene_path, "scene file (config/shell/*.yaml)")->required();
  app.add_option("--frames", frames, "frames to simulate (default: the scene's frames.count)")
      ->check(CLI::PositiveNumber);
  app.add_option("--out", out_dir, "folder for the PLY files the scene asks for")->capture_default_str();
  CLI::Option* no_files_flag = app.add_flag("--no-files", no_files, "write no PLY files (timing runs)");
  app.add_flag("--render", render, "also render each written frame to <name>_NNNN.png beside the PLY files")
      ->excludes(no_files_flag);
  app.add_option("--width", width, "rendered image width")
      ->check(CLI::Range(1, 65535))
      ->capture_default_str();
  app.add_option("--height", height, "rendered image height")
      ->check(CLI::Range(1, 65535))
      ->capture_default_str();
  app.add_option("--view", view, "camera position: rest box centre + this offset in box diagonals (x y z)")
      ->expected(3)
      ->capture_default_str();
  app.add_flag("--quiet", quiet, "no progress line");
  CLI11_PARSE(app, argc, argv);

  rc::ShellScene scene;
  try {
    scene = rc::loadShellScene(scene_path);
  } catch (const rc::ShellSceneError& e) {
    std::fprintf(stderr, "rc_shell: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rc_shell: %s: %s\n", scene_path.c_str(), e.what());
    return 2;
  }
  if (frames > 0) scene.frame_count = frames;

  rc::Camera camera;
  if (render) {
    if (scene.output.every <= 0) {
      std::fprintf(stderr,
                   "rc_shell: %s: --render renders the written output frames, but the scene writes none "
                   "(output.every: 0)\n",
                   scene_path.c_str());
      return 1;
    }
    try {
      rc::Vec3 lo, hi;
      scene.surfels.bounds(&lo, &hi);
      camera = rc::framingCamera(lo, hi, width, height, rc::Vec3(view[0], view[1], view[2]));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rc_shell: --view / rest bounds: %s\n", e.what());
      return 1;
    }
  }

  const bool tty = isatty(fileno(stderr));
  rc::ShellRunOptions options;
  options.out_dir = out_dir;
  options.write_files = !no_files;
  if (!quiet)
    options.on_frame = [&](const rc::ShellFrameReport& r) {
      std::fprintf(stderr,
                   "%sframe %d/%d  t %.4f s  steps %zu (+%zu)  dt %.3e s  cracks %zu  ms: forces %.1f  "
                   "material %.1f  surface %.1f%s",
                   tty ? "\r" : "", r.frame, r.frame_count, r.time, r.steps, r.frame_steps, r.dt, r.cracks,
                   r.forces_ms, r.material_ms, r.surface_ms, tty && r.frame < r.frame_count ? "   " : "\n");
      std::fflush(stderr);
    };
  std::unique_ptr<FrameRenderer> frame_renderer;
  if (render) {
    frame_renderer = std::make_unique<FrameRenderer>(camera, out_dir);
    options.on_written_frame = [&](const rc::ShellSimulation& sim, int frame) {
      (*frame_renderer)(sim, frame);
    };
  }
  try {
    const rc::ShellRunStats stats = rc::runShellScene(scene, options);
    if (!quiet && tty && stats.frames < stats.frame_count) std::fprintf(stderr, "\n");
    const rc::ShellSamplingStats& sampling = stats.sampling;
    if (!sampling.warning.empty()) std::fprintf(stderr, "rc_shell: warning: %s\n", sampling.warning.c_str());
    std::string json = rc::shellRunStatsJson(stats);
    auto number = [](double v) {
      char text[32];
      std::snprintf(text, sizeof text, "%.4g", v);
      return std::isfinite(v) ? std::string(text) : std::string("null");  // null: collinear neighbours
    };
    json.pop_back();  // the closing brace
    json += ", \"sampling_anisotropy\": {\"median\": " + number(sampling.median) +
            ", \"worst\": " + number(sampling.worst) +
            ", \"fraction_above\": " + number(sampling.fraction_above) +
            ", \"threshold\": " + number(sampling.threshold) +
            ", \"irregular\": " + (sampling.warning.empty() ? "false" : "true") + "}";
    if (frame_renderer) {
      const FrameRenderer& r = *frame_renderer;
      const double n = std::max<double>(1, r.images());
      json += ", \"render\": {\"images\": " + std::to_string(r.images()) +
              ", \"width\": " + std::to_string(width) + ", \"height\": " + std::to_string(height) +
              ", \"ms_per_image\": {\"splat\": " + number(r.splatMs() / n) +
              ", \"write\": " + number(r.writeMs() / n) +
              ", \"total\": " + number((r.splatMs() + r.writeMs()) / n) + "}}";
    }
    json += "}";
    std::printf("%s\n", json.c_str());
    if (!stats.instability.empty()) {
      std::fprintf(stderr, "rc_shell: %s\n", stats.instability.c_str());
      return 3;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rc_shell: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
