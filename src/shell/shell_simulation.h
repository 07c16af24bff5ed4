// A running thin-shell scene (thesis 7): solver steps, material update (7.3) and, once per frame, the surface
// animation of the dense surfels (7.4) with crack discontinuity surfels. The object that rc_shell, the
// shell_sim node and the benchmarks advance.
#pragma once

#include <memory>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/shell/shell_material.h"
#include "relaxed_connectivity/shell/shell_membrane_balance.h"
#include "relaxed_connectivity/shell/shell_scene.h"
#include "relaxed_connectivity/shell/shell_skinning.h"
#include "relaxed_connectivity/shell/shell_solver.h"

namespace rc {

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
  /// Takes `steps` solver steps (inside the current frame; the frame count stays) and animates the surface;
  /// throws ShellInstabilityError. A later advanceFrame() still ends at its frame's time.
  ShellFrameReport advanceSteps(int steps);
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
  // Animates the surface and fills the report's state fields (time, steps, cracks, pressure).
  void finishReport(ShellFrameReport* report);

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

}  // namespace rc
