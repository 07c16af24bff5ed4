// Per-frame time of the thin-shell scenes of thesis Table 7.1 (config/shell: Figs. 7.5 bust, 7.10 balloon,
// 7.4 mask, 7.8 poster), split as the table is: forces (solver steps: forces and integration), fracture /
// material (plasticity, fracture tests and re-neighbouring) and surface (skinning of the dense surfels, once
// per frame), from ShellSimulation's frame reports. Each scene runs from its first frame; `--frames N` caps
// the frames per scene (default: bust 40 = all, balloon 150 = all (inflation, the tear from frame 83 on,
// relaxation), poster 45 with about 11 frames of tearing from frame 35, mask 30; about 3 minutes on 2 shared
// cores). Columns: mean
// over the frames run; for the tearing scenes a second row gives the mean over the frames in which new cracks
// appeared. The thesis numbers (Pentium 4, 3 GHz) are printed next to ours with the speed-up of the total.
// `--threads N` sets the OpenMP threads (default: OpenMP's; on a loaded machine 1 avoids waiting at barriers
// for descheduled threads).
// Usage: bench_shell_scenes [--frames N] [--threads N] [--scene-dir DIR]
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "relaxed_connectivity/shell/shell_scene_reader.h"
#include "relaxed_connectivity/shell/shell_simulation.h"

namespace {

using Clock = std::chrono::steady_clock;

struct ThesisRow {
  const char* figure;
  const char* file;
  int default_frames;
  int nodes, points;
  double forces, fracture, surface, total;  ///< ms per frame; fracture 0: none
};

struct PhaseMeans {
  int frames = 0;
  double forces = 0.0, material = 0.0, surface = 0.0, steps = 0.0;
  void add(const rc::ShellFrameReport& r) {
    ++frames;
    forces += r.forces_ms, material += r.material_ms, surface += r.surface_ms, steps += r.frame_steps;
  }
  double mean(double sum) const { return frames > 0 ? sum / frames : 0.0; }
  double total() const { return mean(forces + material + surface); }
};

struct SceneResult {
  std::string name;
  size_t nodes = 0, fibers_start = 0, fibers_end = 0, surfels = 0, cracks = 0;
  double setup_ms = 0.0;
  int first_tear_frame = 0;
  PhaseMeans all, tearing;
  std::string instability;
};

SceneResult runScene(const std::string& path, int frames) {
  SceneResult r;
  rc::ShellScene scene = rc::loadShellScene(path);
  scene.frame_count = frames;
  const Clock::time_point t0 = Clock::now();
  rc::ShellSimulation sim(scene);
  r.setup_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  r.name = scene.name;
  r.nodes = sim.solver().nodes().size();
  r.fibers_start = sim.fiberCount();
  r.surfels = scene.surfels.size();
  try {
    for (int f = 1; f <= frames; ++f) {
      const size_t cracks_before = sim.crackCount();
      const rc::ShellFrameReport report = sim.advanceFrame();
      r.all.add(report);
      if (sim.crackCount() > cracks_before) {
        r.tearing.add(report);
        if (r.first_tear_frame == 0) r.first_tear_frame = f;
      }
      std::fprintf(stderr, "\r%s frame %d/%d cracks %zu   ", r.name.c_str(), f, frames, sim.crackCount());
    }
  } catch (const rc::ShellInstabilityError& e) {
    r.instability = e.what();
  }
  std::fprintf(stderr, "\n");
  r.fibers_end = sim.fiberCount();
  r.cracks = sim.crackCount();
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  int max_frames = 0;
  std::string scene_dir =
      std::string(__FILE__).substr(0, std::string(__FILE__).rfind('/')) + "/../config/shell";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--frames") && i + 1 < argc) {
      max_frames = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc) {
      omp_set_num_threads(std::max(1, std::atoi(argv[++i])));
    } else if (!std::strcmp(argv[i], "--scene-dir") && i + 1 < argc) {
      scene_dir = argv[++i];
    } else {
      std::fprintf(stderr, "usage: %s [--frames N] [--threads N] [--scene-dir DIR]\n", argv[0]);
      return 2;
    }
  }
  // Table 7.1 (ms per frame; the bust and the mask have no fracture column).
  const ThesisRow thesis[] = {
      {"7.5", "fig7_5_bust.yaml", 40, 931, 9835, 7, 0, 64, 71},
      {"7.10", "fig7_10_balloon.yaml", 150, 1170, 24578, 24, 23, 166, 212},
      {"7.4", "fig7_4_mask.yaml", 30, 1987, 40880, 222, 0, 325, 547},
      {"7.8", "fig7_8_poster.yaml", 45, 11860, 240000, 1533, 6066, 1459, 9058},
  };
  std::vector<SceneResult> results;
  for (const ThesisRow& t : thesis) {
    const std::string path = scene_dir + "/" + t.file;
    try {
      results.push_back(runScene(path, max_frames > 0 ? max_frames : t.default_frames));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s\n", path.c_str(), e.what());
      return 1;
    }
  }
  std::printf(
      "Thin-shell scenes, ms per frame (mean over the frames run; 'tearing': frames in which cracks were "
      "added); %d OpenMP thread(s); thesis: Table 7.1 (Pentium 4, 3 GHz)\n\n",
      omp_get_max_threads());
  std::printf(
      "| Fig. | frames | nodes (thesis) | fibers start -> end | surfels (thesis) | cracks | steps / frame "
      "| forces | fracture / material | surface | total ms | thesis forces / fracture / surface / total "
      "| speed-up |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (size_t k = 0; k < results.size(); ++k) {
    const SceneResult& r = results[k];
    const ThesisRow& t = thesis[k];
    char fracture[32] = "-";
    if (t.fracture > 0) std::snprintf(fracture, sizeof fracture, "%.0f", t.fracture);
    auto row = [&](const PhaseMeans& p, const char* label) {
      std::printf(
          "| %s%s | %d | %zu (%d) | %zu -> %zu | %zu (%d) | %zu | %.0f | %.1f | %.1f | %.1f | %.1f | %.0f / "
          "%s / "
          "%.0f / %.0f | %.1fx |\n",
          t.figure, label, p.frames, r.nodes, t.nodes, r.fibers_start, r.fibers_end, r.surfels, t.points,
          r.cracks, p.mean(p.steps), p.mean(p.forces), p.mean(p.material), p.mean(p.surface), p.total(),
          t.forces, fracture, t.surface, t.total, p.total() > 0.0 ? t.total / p.total() : 0.0);
    };
    row(r.all, "");
    if (r.tearing.frames > 0) row(r.tearing, " tearing");
  }
  std::printf("\n");
  for (const SceneResult& r : results) {
    std::printf("%s: setup %.0f ms", r.name.c_str(), r.setup_ms);
    if (r.first_tear_frame > 0) std::printf(", first crack in frame %d", r.first_tear_frame);
    if (!r.instability.empty()) std::printf(", stopped: %s", r.instability.c_str());
    std::printf("\n");
  }
  return 0;
}
