// Running an FEM scene's frames (rc_fem, tests, benchmarks): the frame loop over FemSimulation, the output
// files (VTU series with a PVD index, OBJ surfaces), progress per frame and the run statistics as JSON.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "relaxed_connectivity/fem/fem_scene.h"
#include "relaxed_connectivity/fem/fem_simulation.h"

namespace rc {

/// Progress after one frame.
struct FemFrameReport {
  int frame = 0;  ///< 1-based
  int frame_count = 0;
  double time = 0.0;
  long steps = 0;
  int nodes = 0, elements = 0, bodies = 0, cuts = 0;
  long frame_iterations = 0;  ///< solver iterations of this frame
  double frame_seconds = 0.0;
};

struct FemRunOptions {
  std::string out_dir;  ///< files go here (created); empty: none are written
  std::function<void(const FemFrameReport&)> on_frame;
};

struct FemRunStats {
  std::string scene;
  int nodes_start = 0, elements_start = 0;
  int nodes = 0, elements = 0, bodies = 0, cuts = 0;
  int crack_faces = 0;                         ///< at the end, all bodies
  long slivers_removed = 0, slivers_kept = 0;  ///< thin cut elements merged / kept, all cuts
  int frames = 0, frame_count = 0;
  long steps = 0;
  double simulated_time = 0.0;
  FemPhaseTimes times;
  double wall_seconds = 0.0;  ///< integration + dynamics + topology (no output)
  long solver_iterations = 0;
  int max_step_iterations = 0;
  long unconverged_solves = 0;
  double min_ground_distance = 0.0;  ///< at the end
  double kinetic_energy = 0.0;       ///< at the end, all bodies
  /// analysis: static (fem_static.h): the largest displacement, per held region the sum of its reactions,
  /// per load region the mean displacement of its nodes.
  bool static_analysis = false;
  double max_displacement = 0.0;
  std::vector<Vec3> held_reactions, load_displacements;
  /// analysis: modal (fem_modal.h): the natural frequencies [Hz], ascending.
  bool modal_analysis = false;
  std::vector<double> frequencies;
  std::string error;  ///< empty: completed; else why the run stopped
  std::vector<std::string> files;
};

/// Runs scene.frame_count frames of scene.steps_per_frame steps, writing the outputs the scene asks for.
/// A failing step or cut stops the run (reported in FemRunStats::error); I/O errors throw. A static scene
/// is solved once (solveFemStatic); its outputs are frame 0 (rest) and frame 1 (the equilibrium).
FemRunStats runFemScene(const FemScene& scene, const FemRunOptions& options = {});

/// The statistics as one line of JSON (no newline); non-finite numbers become null.
std::string femRunStatsJson(const FemRunStats& stats);

}  // namespace rc
