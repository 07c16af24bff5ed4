// Thin-shell scene files (YAML, config/shell/*.yaml; thesis chapter 7, parameters of appendix F.1): the
// surfel source (a surfel or mesh file, or a generated sheet / sphere), node sampling, material (elasticity,
// damping and the plasticity / fracture / anisotropy blocks a scene switches on by listing them), gravity,
// ground, pinned boxes (optionally moving), initial placement and velocity, balloon pressure with a ramp, a
// weak point, frames and outputs. The schema is documented at the top of config/shell/fig7_4_mask.yaml.
// ShellSimulation runs a loaded scene frame by frame: solver step, material update (7.3) and, once per frame,
// surface animation of the dense surfels (7.4) with crack discontinuity surfels.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/surfel_cloud.h"
#include "shell/shell_material.h"
#include "shell/shell_membrane_balance.h"
#include "shell/shell_nodes.h"
#include "shell/shell_skinning.h"
#include "shell/shell_solver.h"

namespace rc {

/// A bad scene file: the message reads "<file>:<line>:<column>: <problem>".
class ShellSceneError : public std::runtime_error {
 public:
  explicit ShellSceneError(const std::string& message) : std::runtime_error(message) {}
};

/// Nodes whose rest position lies in [lo, hi] are pinned; they move with `velocity` (pulled edges).
struct ShellScenePin {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
};

/// Inflation of a closed shell (key balloon): pressure rises linearly from `start_pressure` to `pressure`
/// over `ramp_time` seconds (0: the full pressure at once), then stays. With `vent_time` > 0 the gas escapes
/// once the shell has torn: from the first crack on the pump stops and the pressure decays as
/// p_tear exp(-(t - t_tear) / vent_time).
struct ShellSceneBalloon {
  bool enabled = false;
  double pressure = 0.0;
  double start_pressure = 0.0;
  double ramp_time = 0.0;
  double vent_time = 0.0;  ///< 0: the pressure ignores tears
  double pressureAt(double t) const;
  /// Pressure at time t when the first crack was made at `tear_time` (negative: not torn yet).
  double pressureAt(double t, double tear_time) const;
};

/// Fibers centred at nodes within `radius` of `center` (rest positions) get these fracture thresholds.
struct ShellSceneWeakPoint {
  bool enabled = false;
  Vec3 center = Vec3::Zero();
  double radius = 0.0;
  double stretch_threshold = 0.0;  ///< strain; 0 keeps the material's
  double bend_threshold = 0.0;     ///< radians; 0 keeps the material's
};

/// Anisotropic stiffness (7.3.4): a fiber along unit `direction` gets K_s * stretch_ratio, K_b * bend_ratio,
/// across it the material's; in between weighted by cos^2 of the angle.
struct ShellSceneAnisotropy {
  bool enabled = false;
  Vec3 direction = Vec3::UnitX();
  double stretch_ratio = 1.0, bend_ratio = 1.0;
};

/// Files written while a scene runs, at frame 0 and every `every`-th frame: <name>_surfels_NNNN.ply (the
/// dense surfels skinned to the nodes) and <name>_cracks_NNNN.ply (crack discontinuity surfels, when any).
struct ShellSceneOutput {
  int every = 1;  ///< 0: no files
  bool surfels = true;
  bool cracks = true;
};

/// A loaded scene: the rest surfels in world coordinates plus everything needed to build the simulation.
struct ShellScene {
  std::string name;  ///< `name:` or the file name without extension
  std::string path;
  SurfelCloud surfels;  ///< rest surfels (positions, unit normals; colours / radii if the source has them)
  ShellNodeOptions nodes;
  ShellMaterial material;
  /// material.balance_membrane: calibrate the fiber stretch factors so a uniform stretch is in tangential
  /// equilibrium (balanceMembraneStiffness), e.g. for a pressurised balloon.
  bool balance_membrane = false;
  bool plasticity = false, fracture = false;  ///< blocks present
  ShellMaterialOptions material_options;
  ShellSceneAnisotropy anisotropy;
  ShellSolverOptions solver;
  std::vector<ShellScenePin> pins;
  Vec3 initial_velocity = Vec3::Zero();
  ShellSceneBalloon balloon;
  ShellSceneWeakPoint weak_point;
  int frame_count = 1;
  int steps_per_frame = 0;    ///< > 0: this many solver steps per frame
  double frame_time = 0.0;    ///< else: step until this much simulated time per frame has passed
  size_t skinning_nodes = 8;  ///< ShellSkinningOptions::node_count
  ShellSceneOutput output;
};

/// Reads a scene file. Throws ShellSceneError naming the file, line and problem (syntax, unknown key, wrong
/// type, bad value, unreadable surfel file).
ShellScene loadShellScene(const std::string& path);
/// Same for YAML text; `source_name` stands for the file name in error messages and relative file paths
/// are resolved against its folder.
ShellScene parseShellScene(const std::string& yaml_text, const std::string& source_name);

/// Per-frame timing and state.
struct ShellFrameReport {
  int frame = 0, frame_count = 0;
  double time = 0.0;
  size_t steps = 0, frame_steps = 0;
  double dt = 0.0;
  size_t cracks = 0;
  double forces_ms = 0.0;    ///< solver steps (forces and integration), this frame
  double material_ms = 0.0;  ///< plasticity and fracture (with re-neighbouring), this frame
  double surface_ms = 0.0;   ///< dense surface animation (skinning, rebinding after cracks), this frame
  double pressure = 0.0;
};

/// A running scene.
class ShellSimulation {
 public:
  explicit ShellSimulation(const ShellScene& scene);

  /// Simulates one frame and animates the surface; throws ShellInstabilityError.
  ShellFrameReport advanceFrame();
  /// Crack surfels sit this many crack radii inside their material (behind their normal), so each binds to
  /// its own side; the crack plane is that far in front of each.
  static constexpr double kCrackSurfelInset = 0.25;
  /// Deforms the dense surfels (and crack surfels) to the current node positions; returns the milliseconds.
  double animateSurface();

  const ShellScene& scene() const { return scene_; }
  const ShellSolver& solver() const { return *solver_; }
  /// The solver, e.g. to push nodes (velocities) between frames.
  ShellSolver& mutableSolver() { return *solver_; }
  const ShellMaterialModel* material() const { return model_.get(); }
  /// The membrane calibration made at construction (null unless the scene asks for balance_membrane).
  const ShellMembraneBalanceReport* membraneBalance() const {
    return scene_.balance_membrane ? &membrane_balance_ : nullptr;
  }
  size_t crackCount() const { return model_ ? model_->cracks().size() : 0; }
  size_t fiberCount() const { return solver_->fibers().size(); }
  const SurfelCloud& surfels() const { return surfels_; }      ///< deformed dense surfels
  const SurfelCloud& crackSurfels() const { return cracks_; }  ///< deformed discontinuity surfels
  int frame() const { return frame_; }
  /// Re-bindings after cracks in which some dense surfel was left without a visible node (that surfel kept
  /// its old binding; the others were re-bound).
  size_t skinningFallbacks() const { return skinning_fallbacks_; }
  /// Mean distance of the nodes from their centroid (a balloon's radius).
  double meanRadius() const;
  /// Largest |x| and |v| over the nodes; infinite if any is not finite.
  double maxCoordinate() const;
  double maxSpeed() const;

 private:
  void takeStep(ShellFrameReport* report);

  ShellScene scene_;
  std::unique_ptr<ShellSolver> solver_;
  std::unique_ptr<ShellMaterialModel> model_;
  std::shared_ptr<double> pressure_;
  ShellMembraneBalanceReport membrane_balance_;
  std::unique_ptr<ShellSkinning> skinning_, crack_skinning_;
  size_t bound_cracks_ = 0;
  size_t skinning_fallbacks_ = 0;
  SurfelCloud surfels_, cracks_;
  int frame_ = 0;
};

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
};

/// Builds the simulation, runs all frames, writes the outputs. An instability ends the run and is reported
/// in the stats (other errors throw).
ShellRunStats runShellScene(const ShellScene& scene, const ShellRunOptions& options);
/// One-line JSON of the stats.
std::string shellRunStatsJson(const ShellRunStats& stats);

}  // namespace rc
