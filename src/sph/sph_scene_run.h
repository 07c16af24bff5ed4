// Runs a loaded SPH scene frame by frame (the code path of the rc_sph tool): steps the solver, writes the
// particle and surface outputs the scene asks for, reports progress per frame, and collects run statistics
// (step sizes, timings, conservation measures, instability).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_scene.h"
#include "relaxed_connectivity/sph/sph_scene_setup.h"
#include "relaxed_connectivity/sph/sph_simulation.h"
#include "relaxed_connectivity/sph/sph_thermal.h"

namespace rc {

/// Progress after one frame.
struct SphFrameReport {
  int frame = 0;  ///< 1-based
  int frame_count = 0;
  uint64_t steps = 0;        ///< all steps so far
  uint64_t frame_steps = 0;  ///< steps of this frame
  double time = 0.0;         ///< simulated time at the end of the frame
  double dt = 0.0;           ///< last full (not shortened) step
  SphStepLimit limit = SphStepLimit::kMaxDt;
  double frame_seconds = 0.0;  ///< wall time of the frame's steps
};

struct SphRunOptions {
  std::string out_dir;  ///< particle and surface files go here (created); empty: none are written
  std::function<void(const SphFrameReport&)> on_frame;
  /// Scenes with `enable: [temperature]`: the model stepped after every solver step (made by
  /// makeSphThermal when null; pass one to read its temperatures after the run).
  std::shared_ptr<SphThermalModel> thermal;
};

struct SphRunStats {
  std::string scene;
  size_t particles = 0, fluid_particles = 0;  ///< at the start; fluid: integrated particles of phase 0
  size_t particles_end = 0;                   ///< at the end (particles + emitted)
  /// Fluid sources (scene key sources): their number, the particles and mass they emitted (also those of
  /// the layer due at the start) and the lattice points they skipped as occupied (SphFluidSource).
  size_t sources = 0, emitted = 0, source_skipped = 0;
  double emitted_mass = 0.0;
  size_t solids = 0, solid_particles = 0;  ///< elastic objects (enable: [elasticity]) and their particles
  int frames = 0;                          ///< completed frames
  int frame_count = 0;
  uint64_t steps = 0;
  int threads = 0;
  double simulated_time = 0.0;
  double mean_dt = 0.0;       ///< simulated time / steps
  double min_dt = 0.0;        ///< smallest step not shortened to end a frame
  double mean_step_us = 0.0;  ///< wall time per step
  double max_step_us = 0.0;   ///< slowest step (steps ending a frame are timed as a group: their mean)
  double us_per_particle_step = 0.0;  ///< mean_step_us / the mean particle count of the steps
  double wall_seconds = 0.0;          ///< stepping only (no output)
  double output_seconds = 0.0;
  /// Conservation: fluid mass (relative change, emitted mass excluded: (M_end - M_start - emitted) /
  /// M_start), fluid momentum, and the impulse the boundaries (walls, planes, moving boxes) exerted:
  /// P_end - P_start - M g t (zero for a free fluid: then it is the momentum error); with sources also less
  /// the emitted momentum and the gravity impulse on the emitted mass since its emission.
  double mass_drift = 0.0;
  Vec3 momentum_start = Vec3::Zero(), momentum_end = Vec3::Zero(), boundary_impulse = Vec3::Zero();
  /// Measures over the integrated particles (fluid and solids).
  /// Energy E = kinetic + compression (equation of state) + elastic - sum m g . x, after step 1 and at the
  /// end; energy_change = (end - first) / |first| (viscosity, XSPH and plane hits dissipate, moving
  /// boundaries add work; sources add the energy of the particles they emit). NaN (null in JSON) when no step
  /// completed.
  double energy_first = 0.0, energy_end = 0.0, energy_change = 0.0;
  double max_density_error = 0.0;  ///< max over all steps of max |rho - rho_0| / rho_0 (fluid)
  /// Solids only: elastic energy of the force terms at the end (NaN when no step completed) and the max
  /// over all steps and solids of SphElasticStats::max_strain.
  double elastic_energy = 0.0, max_strain = 0.0;
  std::string instability;  ///< empty: stable; else the solver's message (step and likely cause)
  uint64_t instability_step = 0;
  /// Temperature (`enable: [temperature]`): heat sum m c T of the non-held conducting particles at the start
  /// and end, the temperature range at the end, and phase changes of the run (8.35, 8.36).
  bool thermal = false;
  double heat_start = 0.0, heat_end = 0.0;
  double min_temperature = 0.0, max_temperature = 0.0;
  uint64_t melted = 0, frozen = 0;
  /// Written particle files (and the .pvd), surface meshes and skins (<name>_skin<k>_NNNN.obj / .ply).
  std::vector<std::string> files;
};

/// Runs scene.frame_count frames of scene.frame_time on the simulation (not stepped yet; the sources' first
/// layers are emitted here). Outputs (options.out_dir): particle files, surface meshes and the solids' skins.
/// Frames end exactly on multiples of frame_time, like SphFluidSolver::advance(frame_time) per frame, and
/// give the same state bitwise. An unstable step stops the run (it is reported in SphRunStats::instability,
/// nothing is thrown); I/O errors throw. With temperature, the thermal model steps after every solver step
/// with that step's dt, and particle files get temperature and phase. Scenes with sources emit their due
/// layers before the first step and after every step (after the thermal model; new particles get the source's
/// temperature) and call SphFluidSolver::particlesChanged() when particles were added: every per-particle
/// array of the solver, its force terms and the thermal model grows with the particles.
SphRunStats runSphScene(SphSimulation& simulation, const SphRunOptions& options = {});
/// The same on `solver` (made by makeSphSolver(scene), possibly with changed threads) with options.thermal
/// (made by makeSphThermal when null); a simulation brings its own thermal model.
SphRunStats runSphScene(const SphScene& scene, SphFluidSolver& solver, const SphRunOptions& options = {});

/// The statistics as one line of JSON (no newline); non-finite numbers become null. particles_end is always
/// there; scenes with sources add sources, emitted, emitted_mass and source_skipped. Scenes with solids
/// add solids, solid_particles, elastic_energy and max_strain; scenes with temperature add heat_start,
/// heat_end, min_temperature, max_temperature, melted and frozen.
std::string sphRunStatsJson(const SphRunStats& stats);

}  // namespace rc
