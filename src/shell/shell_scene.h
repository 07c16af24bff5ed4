// A thin-shell scene (thesis chapter 7, parameters of appendix F.1): what config/shell/*.yaml describes. The
// rest surfels, node sampling, material (elasticity, damping and the plasticity / fracture / anisotropy
// blocks a scene switches on by listing them), gravity, ground, pinned boxes (optionally moving), initial
// placement and velocity, balloon pressure with a ramp, a weak point, frames and outputs. shell_scene_reader
// reads it, ShellSimulation (shell_simulation) steps it, runShellScene (shell_scene_run) runs its frames. The
// schema is documented at the top of config/shell/fig7_4_mask.yaml.
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/shell/shell_material.h"
#include "relaxed_connectivity/shell/shell_nodes.h"
#include "relaxed_connectivity/shell/shell_probes.h"
#include "relaxed_connectivity/shell/shell_solver.h"
#include "relaxed_connectivity/shell/shell_static.h"

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

/// What a run computes (key analysis): the explicit dynamics over the frames; the static equilibrium under
/// the loads and gravity with the held regions (shell_static.h; output frames 0 and 1); or the lowest `modes`
/// natural modes about the rest shape (shell_modal.h; output frames 1..modes the shapes, scaled to a tenth of
/// the shell's diagonal).
enum class ShellAnalysis { kDynamic, kStatic, kModal };

/// Key held (static and modal): the nodes whose rest positions lie in [lo, hi] hold the listed components at
/// their rest position plus `displacement`.
struct ShellSceneHeld {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  std::array<bool, 3> components = {true, true, true};
  Vec3 displacement = Vec3::Zero();
};

/// Key loads (static): on the nodes in [lo, hi], or on the node nearest `point`, a total `force` spread by
/// the nodes' rest areas and / or a `traction` per unit rest area.
struct ShellSceneLoad {
  bool at_point = false;
  Vec3 point = Vec3::Zero();
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  Vec3 force = Vec3::Zero(), traction = Vec3::Zero();
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
  ShellAnalysis analysis = ShellAnalysis::kDynamic;
  std::vector<ShellSceneHeld> held;   ///< static and modal
  std::vector<ShellSceneLoad> loads;  ///< static
  ShellStaticOptions static_options;  ///< key static: {load_steps, max_iterations, tolerance}
  int modes = 6;                      ///< modal
  /// dynamic: <name>_probes.csv in the output folder (shell_probes.h), a row at the start and per frame.
  std::vector<ShellProbe> probes;
};

}  // namespace rc
