// rc_sph: runs an SPH scene file (thesis chapter 8; config/sph/*.yaml).
//   rc_sph SCENE.yaml [--frames N] [--out DIR] [--threads T] [--quiet]
// Writes the particle and surface files the scene asks for (output.particles, output.surface) to DIR, prints
// a progress line per frame on stderr and one JSON line of run statistics on stdout. Exit codes: 0 ok, 1
// other error (I/O, arguments), 2 bad scene file, 3 the simulation became unstable.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>

#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"

int main(int argc, char** argv) {
  CLI::App app{"rc_sph: weakly compressible SPH scenes: fluids (thesis 8.1), elastic solids (8.2)"};
  std::string scene_path, out_dir = ".";
  int frames = 0, threads = -1;
  bool quiet = false;
  app.add_option("scene", scene_path, "scene file (config/sph/*.yaml)")->required();
  app.add_option("--frames", frames, "frames to simulate (default: the scene's frames.count)")
      ->check(CLI::PositiveNumber);
  app.add_option("--out", out_dir, "folder for the particle and surface files the scene asks for")
      ->capture_default_str();
  app.add_option("--threads", threads, "OpenMP threads (0 = all; default: the scene's solver.threads)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--quiet", quiet, "no progress line");
  CLI11_PARSE(app, argc, argv);

  rc::SphScene scene;
  try {
    scene = rc::loadSphScene(scene_path);
  } catch (const rc::SphSceneError& e) {
    std::fprintf(stderr, "rc_sph: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rc_sph: %s: %s\n", scene_path.c_str(), e.what());
    return 2;
  }
  for (const std::string& warning : scene.warnings) std::fprintf(stderr, "rc_sph: %s\n", warning.c_str());
  if (frames > 0) scene.frame_count = frames;
  if (threads >= 0) scene.config.num_threads = threads;

  const bool tty = isatty(fileno(stderr));
  rc::SphRunOptions options;
  options.out_dir = out_dir;
  if (!quiet)
    options.on_frame = [&](const rc::SphFrameReport& r) {
      const double us = r.frame_steps ? 1e6 * r.frame_seconds / double(r.frame_steps) : 0.0;
      std::fprintf(stderr, "%sframe %d/%d  t %.4f s  steps %llu (+%llu)  dt %.3e s (%s)  %.1f us/step%s",
                   tty ? "\r" : "", r.frame, r.frame_count, r.time, (unsigned long long)r.steps,
                   (unsigned long long)r.frame_steps, r.dt, rc::toString(r.limit), us,
                   tty && r.frame < r.frame_count ? "   " : "\n");
      std::fflush(stderr);
    };
  try {
    rc::SphSimulation simulation(scene);
    const rc::SphRunStats stats = rc::runSphScene(simulation, options);
    if (!quiet && tty && stats.frames < stats.frame_count) std::fprintf(stderr, "\n");
    std::printf("%s\n", rc::sphRunStatsJson(stats).c_str());
    if (!stats.instability.empty()) {
      std::fprintf(stderr, "rc_sph: %s\n", stats.instability.c_str());
      return 3;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rc_sph: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
