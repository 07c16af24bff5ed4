// rc_fem: runs an FEM scene file (thesis chapter 9; config/fem/*.yaml).
//   rc_fem SCENE.yaml [--frames N] [--out DIR] [--every K] [--ascii] [--no-vtu] [--obj] [--quiet]
// Writes per-frame .vtu files with polyhedron cells (and a .pvd series) and boundary OBJ surfaces to DIR,
// prints a progress line per frame on stderr and one JSON line of run statistics on stdout. Exit codes: 0 ok,
// 1 other error (I/O, arguments), 2 bad scene file, 3 the simulation failed (a cut or a non-finite state).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>

#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/fem/fem_scene_run.h"

int main(int argc, char** argv) {
  CLI::App app{"rc_fem: finite elements on convex polyhedra with cutting (thesis chapter 9)"};
  std::string scene_path, out_dir = ".";
  int frames = 0, every = -1;
  bool quiet = false, ascii = false, no_vtu = false, obj = false;
  app.add_option("scene", scene_path, "scene file (config/fem/*.yaml)")->required();
  app.add_option("--frames", frames, "frames to simulate (default: the scene's frames.count)")
      ->check(CLI::PositiveNumber);
  app.add_option("--out", out_dir, "folder for the .vtu / .pvd / .obj files")->capture_default_str();
  app.add_option("--every", every, "write every K-th frame (0: no files; default: the scene's output.every)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--ascii", ascii, "ASCII .vtu arrays (default: the scene's output.encoding)");
  app.add_flag("--no-vtu", no_vtu, "no .vtu / .pvd files");
  app.add_flag("--obj", obj, "also write boundary surfaces as OBJ");
  app.add_flag("--quiet", quiet, "no progress line");
  CLI11_PARSE(app, argc, argv);

  rc::FemScene scene;
  try {
    scene = rc::loadFemScene(scene_path);
  } catch (const rc::FemSceneError& e) {
    std::fprintf(stderr, "rc_fem: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rc_fem: %s: %s\n", scene_path.c_str(), e.what());
    return 2;
  }
  if (frames > 0) scene.frame_count = frames;
  if (every >= 0) scene.output.every = every;
  if (ascii) scene.output.encoding = rc::VtuEncoding::kAscii;
  if (no_vtu) scene.output.vtu = false;
  if (obj) scene.output.obj = true;

  const bool tty = isatty(fileno(stderr));
  rc::FemRunOptions options;
  options.out_dir = out_dir;
  if (!quiet)
    options.on_frame = [&](const rc::FemFrameReport& r) {
      std::fprintf(
          stderr,
          "%sframe %d/%d  t %.4f s  steps %ld  nodes %d  elements %d  bodies %d  cuts %d  iterations %ld"
          "  %.1f ms%s",
          tty ? "\r" : "", r.frame, r.frame_count, r.time, r.steps, r.nodes, r.elements, r.bodies, r.cuts,
          r.frame_iterations, 1e3 * r.frame_seconds, tty && r.frame < r.frame_count ? "   " : "\n");
      std::fflush(stderr);
    };
  try {
    const rc::FemRunStats stats = rc::runFemScene(scene, options);
    if (!quiet && tty && stats.frames < stats.frame_count) std::fprintf(stderr, "\n");
    std::printf("%s\n", rc::femRunStatsJson(stats).c_str());
    if (!stats.error.empty()) {
      std::fprintf(stderr, "rc_fem: %s\n", stats.error.c_str());
      return 3;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rc_fem: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
