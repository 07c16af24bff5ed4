#include "relaxed_connectivity/shell/shell_scene_run.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/shell/shell_scene_analysis.h"

namespace rc {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

size_t writeFrame(const ShellSimulation& sim, const std::string& dir, int frame) {
  const ShellSceneOutput& out = sim.scene().output;
  char suffix[32];
  std::snprintf(suffix, sizeof suffix, "_%04d.ply", frame);
  const std::filesystem::path folder(dir);
  size_t files = 0;
  if (out.surfels) {
    writeCloud((folder / (sim.scene().name + "_surfels" + suffix)).string(), sim.surfels());
    ++files;
  }
  if (out.cracks && sim.crackCount() > 0) {
    writeCloud((folder / (sim.scene().name + "_cracks" + suffix)).string(), sim.crackSurfels());
    ++files;
  }
  return files;
}

/// analysis dynamic: the frames, an instability ending the run.
void runFrames(ShellSimulation& sim, bool write, const ShellRunOptions& options, ShellRunStats* stats) {
  const ShellScene& scene = sim.scene();
  std::ofstream probes;
  std::vector<std::vector<uint32_t>> probe_nodes;
  if (!scene.probes.empty() && options.write_files) {
    for (size_t k = 0; k < scene.probes.size(); ++k)
      probe_nodes.push_back(
          shellNodesInBox(sim.solver().nodes(), scene.probes[k].lo, scene.probes[k].hi,
                          scene.path + ": probes[" + std::to_string(k) + "] (" + scene.probes[k].name + ")"));
    std::filesystem::create_directories(options.out_dir);
    const std::string path = (std::filesystem::path(options.out_dir) / (scene.name + "_probes.csv")).string();
    probes.open(path);
    if (!probes) throw std::runtime_error("runShellScene: cannot write " + path);
    writeShellProbeHeader(probes, scene.probes);
  }
  auto probe = [&] {
    if (!probes.is_open()) return;
    std::vector<ShellRegionMeasures> regions;
    for (const std::vector<uint32_t>& nodes : probe_nodes)
      regions.push_back(measureShellRegion(sim.solver(), nodes));
    writeShellProbeRow(probes, sim.solver().time(), measureShell(sim.solver()), regions);
  };
  probe();
  try {
    for (int f = 1; f <= scene.frame_count; ++f) {
      const ShellFrameReport r = sim.advanceFrame();
      stats->forces_ms += r.forces_ms;
      stats->material_ms += r.material_ms;
      stats->surface_ms += r.surface_ms;
      stats->frames = f;
      if (write && f % scene.output.every == 0) {
        stats->files += writeFrame(sim, options.out_dir, f);
        if (options.on_written_frame) options.on_written_frame(sim, f);
      }
      probe();
      if (options.on_frame) options.on_frame(r);
    }
  } catch (const ShellInstabilityError& e) {
    stats->instability = e.what();
  }
  if (stats->frames > 0) {
    stats->forces_ms /= stats->frames;
    stats->material_ms /= stats->frames;
    stats->surface_ms /= stats->frames;
  }
}

/// analysis static (frame 1: the equilibrium) or modal (frames 1..modes: the shapes, scaled to a tenth of the
/// shell's diagonal).
void runAnalysis(ShellSimulation& sim, const ShellRunOptions& options, ShellRunStats* stats) {
  const ShellScene& scene = sim.scene();
  const ShellNodes& nodes = sim.solver().nodes();
  if (scene.analysis == ShellAnalysis::kStatic) {
    const ShellStaticResult r = solveShellSceneStatic(sim);
    stats->analysis = "static";
    stats->static_iterations = r.iterations;
    stats->static_residual = r.residual;
    stats->max_displacement = r.max_displacement;
    stats->held_reactions = r.held_reactions;
    stats->load_displacements = r.load_displacements;
    stats->hessian_colors = r.hessian_colors;
    stats->analysis_seconds = r.seconds;
    stats->frames = 1;
    if (options.write_files) {
      stats->files += writeFrame(sim, options.out_dir, 1);
      if (options.on_written_frame) options.on_written_frame(sim, 1);
    }
    return;
  }
  const ShellModalResult r = solveShellSceneModal(sim);
  stats->analysis = "modal";
  stats->frequencies.assign(r.frequencies.data(), r.frequencies.data() + r.frequencies.size());
  stats->rigid_modes = r.rigid_modes;
  stats->hessian_colors = r.hessian_colors;
  stats->analysis_seconds = r.seconds;
  Vec3 lo = nodes.rest_positions[0], hi = lo;
  for (const Vec3& p : nodes.rest_positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  std::vector<Vec3> x(nodes.size());
  for (int m = 0; m < int(r.frequencies.size()); ++m) {
    double largest = 0.0;
    for (size_t i = 0; i < nodes.size(); ++i)
      largest = std::max(largest, r.modes.col(m).segment<3>(3 * i).norm());
    const double scale = largest > 0.0 ? 0.1 * (hi - lo).norm() / largest : 0.0;
    for (size_t i = 0; i < nodes.size(); ++i)
      x[i] = nodes.rest_positions[i] + scale * r.modes.col(m).segment<3>(3 * i);
    sim.mutableSolver().setPositions(x);
    sim.animateSurface();
    stats->frames = m + 1;
    if (options.write_files) {
      stats->files += writeFrame(sim, options.out_dir, m + 1);
      if (options.on_written_frame) options.on_written_frame(sim, m + 1);
    }
  }
  sim.mutableSolver().setPositions(nodes.rest_positions);
  sim.animateSurface();
}

}  // namespace

ShellRunStats runShellScene(const ShellScene& scene, const ShellRunOptions& options) {
  ShellRunStats stats;
  stats.name = scene.name;
  stats.frame_count = scene.frame_count;
  const Clock::time_point t0 = Clock::now();
  ShellSimulation sim(scene);
  stats.setup_ms = msSince(t0);
  stats.nodes = sim.solver().nodes().size();
  stats.sampling = sim.solver().nodes().sampling;
  stats.surfels = scene.surfels.size();
  stats.mean_radius_start = sim.meanRadius();
  if (sim.membraneBalance()) {
    stats.membrane_balanced = true;
    stats.membrane_balance = *sim.membraneBalance();
  }
  const bool write = options.write_files && scene.output.every > 0;
  if (write) {
    std::filesystem::create_directories(options.out_dir);
    stats.files += writeFrame(sim, options.out_dir, 0);
    if (options.on_written_frame) options.on_written_frame(sim, 0);
  }
  if (scene.analysis != ShellAnalysis::kDynamic) {
    runAnalysis(sim, write ? options : ShellRunOptions{options.out_dir, false, {}, {}}, &stats);
  } else {
    runFrames(sim, write, options, &stats);
  }
  stats.fibers = sim.fiberCount();
  stats.cracks = sim.crackCount();
  stats.steps = sim.solver().stepCount();
  stats.time = sim.solver().time();
  stats.mean_radius_end = sim.meanRadius();
  if (sim.crackCount() > 0) {
    stats.first_crack_time = sim.material()->cracks().front().time;
    stats.last_crack_time = sim.material()->cracks().back().time;
    if (scene.balloon.enabled) stats.tear_pressure = scene.balloon.pressureAt(stats.first_crack_time);
  }
  return stats;
}

std::string shellRunStatsJson(const ShellRunStats& s) {
  std::string instability;
  for (char c : s.instability) {
    if (c == '"' || c == '\\') instability += '\\';
    instability += c;
  }
  char buf[1024];
  std::snprintf(
      buf, sizeof buf,
      "{\"scene\": \"%s\", \"nodes\": %zu, \"fibers\": %zu, \"surfels\": %zu, \"cracks\": %zu, "
      "\"frames\": %d, \"frame_count\": %d, \"steps\": %zu, \"time\": %.6g, \"setup_ms\": %.1f, "
      "\"ms_per_frame\": {\"forces\": %.2f, \"material\": %.2f, \"surface\": %.2f, \"total\": %.2f}, "
      "\"mean_radius\": {\"start\": %.6g, \"end\": %.6g}, \"files\": %zu, \"instability\": ",
      s.name.c_str(), s.nodes, s.fibers, s.surfels, s.cracks, s.frames, s.frame_count, s.steps, s.time,
      s.setup_ms, s.forces_ms, s.material_ms, s.surface_ms, s.forces_ms + s.material_ms + s.surface_ms,
      s.mean_radius_start, s.mean_radius_end, s.files);
  char tail[512];
  std::snprintf(tail, sizeof tail,
                ", \"cracks_at\": {\"first\": %.6g, \"last\": %.6g, \"tear_pressure\": %.6g}",
                s.first_crack_time, s.last_crack_time, s.tear_pressure);
  std::string balance = ", \"membrane_balance\": null";
  if (s.membrane_balanced) {
    char b[256];
    const ShellMembraneBalanceReport& m = s.membrane_balance;
    std::snprintf(b, sizeof b,
                  ", \"membrane_balance\": {\"constrained_nodes\": %zu, \"residual_before\": %.4g, "
                  "\"residual_after\": %.4g, \"clamped_fibers\": %zu, \"factors\": [%.4g, %.4g]}",
                  m.constrained_nodes, m.residual_before, m.residual_after, m.clamped_fibers, m.min_factor,
                  m.max_factor);
    balance = b;
  }
  auto vectors = [](const std::vector<Vec3>& v) {
    std::string out = "[";
    char item[96];
    for (size_t k = 0; k < v.size(); ++k) {
      std::snprintf(item, sizeof item, "%s[%.9g, %.9g, %.9g]", k ? ", " : "", v[k].x(), v[k].y(), v[k].z());
      out += item;
    }
    return out + "]";
  };
  std::string analysis = ", \"analysis\": \"" + s.analysis + "\"";
  char numbers[256];
  if (s.analysis == "static") {
    std::snprintf(numbers, sizeof numbers,
                  ", \"static\": {\"iterations\": %d, \"residual\": %.3g, \"max_displacement\": %.9g, "
                  "\"hessian_colors\": %zu, \"seconds\": %.3f, \"held_reactions\": ",
                  s.static_iterations, s.static_residual, s.max_displacement, s.hessian_colors,
                  s.analysis_seconds);
    analysis += numbers + vectors(s.held_reactions) +
                ", \"load_displacements\": " + vectors(s.load_displacements) + "}";
  } else if (s.analysis == "modal") {
    std::snprintf(numbers, sizeof numbers,
                  ", \"modal\": {\"rigid_modes\": %d, \"hessian_colors\": %zu, \"seconds\": %.3f, "
                  "\"frequencies\": [",
                  s.rigid_modes, s.hessian_colors, s.analysis_seconds);
    analysis += numbers;
    for (size_t k = 0; k < s.frequencies.size(); ++k) {
      std::snprintf(numbers, sizeof numbers, "%s%.9g", k ? ", " : "", s.frequencies[k]);
      analysis += numbers;
    }
    analysis += "]}";
  }
  return std::string(buf) + (s.instability.empty() ? "null" : "\"" + instability + "\"") + tail + balance +
         analysis + "}";
}

}  // namespace rc
