// Running a thin-shell scene's frames (rc_shell, tests, benchmarks): the frame loop over ShellSimulation, the
// PLY outputs (skinned surfels, crack surfels), progress per frame and the run statistics as JSON.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "relaxed_connectivity/shell/shell_simulation.h"

namespace rc {

struct ShellRunOptions {
  std::string out_dir = ".";
  bool write_files = true;
  std::function<void(const ShellFrameReport&)> on_frame;
  /// Called after each written output frame (frame 0 included) with the simulation (e.g. to render it).
  std::function<void(const ShellSimulation&, int frame)> on_written_frame;
};

struct ShellRunStats {
  std::string name;
  size_t nodes = 0, fibers = 0, surfels = 0, cracks = 0;
  int frames = 0, frame_count = 0;
  size_t steps = 0;
  double time = 0.0;
  double forces_ms = 0.0, material_ms = 0.0, surface_ms = 0.0;  ///< per frame (mean)
  double setup_ms = 0.0;
  double mean_radius_start = 0.0, mean_radius_end = 0.0;
  /// Simulation times of the first and the last crack and the pressure when the first one was made (balloon);
  /// negative without cracks.
  double first_crack_time = -1.0, last_crack_time = -1.0, tear_pressure = -1.0;
  bool membrane_balanced = false;
  ShellMembraneBalanceReport membrane_balance;
  size_t files = 0;
  std::string instability;      ///< the ShellInstabilityError message, if the run stopped on one
  ShellSamplingStats sampling;  ///< anisotropy of the node sampling (ShellNodes::sampling)
  // analysis static / modal (shell_scene_analysis.h)
  std::string analysis = "dynamic";
  int static_iterations = 0;
  double static_residual = 0.0, max_displacement = 0.0, analysis_seconds = 0.0;
  std::vector<Vec3> held_reactions, load_displacements;  ///< static, per region / load
  std::vector<double> frequencies;                       ///< modal [Hz]
  int rigid_modes = 0;                                   ///< modal
  size_t hessian_colors = 0;
};

/// Builds the simulation, runs all frames, writes the outputs. An instability ends the run and is reported
/// in the stats (other errors throw).
ShellRunStats runShellScene(const ShellScene& scene, const ShellRunOptions& options);
/// One-line JSON of the stats.
std::string shellRunStatsJson(const ShellRunStats& stats);

}  // namespace rc
