// An SPH scene (thesis 8): what config/sph/*.yaml describes. Solver parameters (8.1.4, appendix F.2),
// particles of the fluid blocks and solids, fluid sources, boundary walls / boxes / cylinders / planes,
// moving boundary boxes, frames, particle and surface outputs and the optional physics a scene switches on.
// sph_scene_reader reads it, SphSimulation (sph_simulation) steps it, runSphScene (sph_scene_run) runs its
// frames. The schema is documented at the top of config/sph/dam_break_2d.yaml.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_fluid_source.h"
#include "relaxed_connectivity/sph/sph_object_penalty.h"
#include "relaxed_connectivity/sph/sph_particles.h"
#include "relaxed_connectivity/sph/sph_skinning.h"
#include "relaxed_connectivity/sph/sph_surface.h"
#include "relaxed_connectivity/sph/sph_thermal.h"

namespace rc {

/// A bad scene file: the message reads "<file>:<line>:<column>: <problem>".
class SphSceneError : public std::runtime_error {
 public:
  explicit SphSceneError(const std::string& message) : std::runtime_error(message) {}
};

/// Particle files written while a scene runs: the initial state (frame 0) and every `every`-th frame.
struct SphParticleOutput {
  int every = 0;  ///< 0: no particle output
  bool ply = false;
  bool vtp = false;
  bool enabled() const { return every > 0 && (ply || vtp); }
};

/// Probes written while a scene runs (key `probes`): <name>_probes.csv in the output folder, a row at the
/// start and after every frame (sph_probes.h): the liquid body's measures and, per point, the density and
/// pressure there.
struct SphProbeOutput {
  bool enabled = false;
  std::vector<Vec3> points;
};

/// Surface meshes written while a scene runs (`enable: [surface]`, key output.surface; thesis 8.2.7):
/// marching cubes on the colour field of the integrated particles (fluid and solids), frame 0 and every
/// `every`-th frame, as <name>_surface_NNNN.obj / .ply.
struct SphSurfaceOutput {
  bool enabled = false;
  int every = 1;
  bool obj = true, ply = false;
  SphSurfaceConfig config;  ///< smoothing_length, rest_density and threads are the solver's
};

/// One elastic object of the scene (`enable: [elasticity]`, key solids; thesis 8.2): its particles are
/// the `count` particles from `first` (kind kFluid, phases == phase), sampled on the closest-packing
/// lattice of elastic.lattice_spacing in the orientation `orientation`. Shapes: box {lo, hi}, sphere
/// {center, radius} and (3D) mesh {mesh: OBJ / PLY / OFF file relative to the scene file, scale: s |
/// [sx, sy, sz], translation}: the mesh placed at translation + R (scale x), sampled where its generalised
/// winding number exceeds 1/2 (closed meshes, or scans with small holes); `skin: {mesh: same}` skins it.
/// Optional solid keys: `fracture` {strain, rate, max_docking_rate, docking_rate_increase,
/// docking_rate_decrease (both 1/s^2: the rate changes by value * dt per step), docking_distance, seed}
/// (docking, 8.2.5), `plasticity` {yield_strain, flow_rate,
/// max_strain} (both work with fixed and adaptive steps: the solver announces each step's dt;
/// elastic.time_step is solver.fixed_dt, else solver.max_dt), and `anchor` {lo, hi}: the solid's particles in
/// that box become static boundary particles it is fixed to (kind kStaticBoundary, still of this phase;
/// Fig. 8.7 c).
struct SphSceneSolid {
  SphElasticConfig elastic;
  uint8_t phase = 1;
  Eigen::Matrix3d orientation = Eigen::Matrix3d::Identity();
  size_t first = 0, count = 0;
};

/// Particles [first, first + count) start at `temperature` (key `temperature` of a fluid box or solid).
struct SphSceneTemperature {
  size_t first = 0, count = 0;
  double temperature = 0.0;
};

/// Particles held at a temperature (key temperature.held: those inside the box [lo, hi] or the cylinder
/// {from, to, radius} at load time, any kind; a cooled rod or a heater). `phase` (if > 0) is written to their
/// phases: a seed fluid can freeze onto.
struct SphSceneHeld {
  std::vector<size_t> indices;
  double temperature = 0.0;
  uint8_t phase = 0;
};

/// Heat and phase transitions (`enable: [temperature]`, `[phase_transition]`; thesis 8.2.4): the model's
/// config (melting / freezing set by phase_transition), initial temperatures, heated planes, held particles.
/// The solid fluid freezes into is scene.solids entry `freezing_solid` (-1: none).
struct SphSceneThermal {
  bool enabled = false;
  SphThermalConfig config;
  std::vector<SphSceneTemperature> initial;
  std::vector<SphHeatedPlane> planes;
  std::vector<SphSceneHeld> held;
  int freezing_solid = -1;
};

/// Penalty collisions between the solids (`enable: [collisions]`, key collisions {stiffness,
/// contact_distance, damping, implicit, couple_global_implicit}; thesis 8.2.6, (8.37)): an SphObjectPenalty
/// term. contact_distance defaults to the smallest lattice spacing of the solids; couple_global_implicit
/// (default true) solves implicit contacts inside the global implicit goal solve of the solids they join.
struct SphSceneCollisions {
  bool enabled = false;
  SphObjectPenaltyConfig config;
};

/// A surface skinned to a solid (`enable: [skin]`, solid key `skin`; thesis 8.2.7, (8.38)): the rest mesh in
/// world coordinates (a mesh file, or the solid's own box / sphere at `resolution`), bound to the solid's
/// rest particles with support h (the solver's smoothing length). Written as <name>_skin<k>_NNNN.obj / .ply
/// (k: the solid's index) at frame 0 and every `every`-th frame, deformed by (8.38) with the transforms
/// fitted to the particles or the solid's lattice transforms A_i (8.23).
struct SphSceneSkin {
  size_t solid = 0;  ///< index into SphScene::solids
  TriangleMesh rest;
  SphSkin skin;
  bool lattice_transforms = false;  ///< transforms: lattice | fitted (default)
  int every = 1;                    ///< default: the particle output's every (else 1)
  bool obj = true, ply = false;
};

/// A loaded scene, ready for the solver: config is validated, particles are filled, planes collected.
struct SphScene {
  std::string name;  ///< `name:` or the file name without extension
  std::string path;  ///< the file it was read from
  SphFluidConfig config;
  SphParticles particles;
  std::vector<SphPlane> planes;
  std::vector<std::string> enabled_physics;  ///< the `enable:` list (only supported entries get here)
  int frame_count = 1;
  double frame_time = 0.0;  ///< simulated seconds per frame
  SphParticleOutput output;
  SphSurfaceOutput surface;
  SphProbeOutput probes;
  std::vector<SphSceneSolid> solids;
  SphSceneCollisions collisions;
  SphSceneThermal thermal;
  std::vector<SphSceneSkin> skins;  ///< in solid order, at most one per solid
  /// Fluid sources (key sources): runSphScene emits their layers before the first step and after every
  /// step; with temperature the new particles get the source's temperature (default: temperature.initial).
  std::vector<SphFluidSourceConfig> sources;
  /// Settings known to give wrong results, each "<file>:<line>:<column>: warning: <what and why>" (the scene
  /// still loads; rc_sph prints them, the sph_simulator node logs them).
  std::vector<std::string> warnings;
};

/// Optional physics a scene may list under `enable:`: elasticity (key solids), collisions (key collisions;
/// needs elasticity and two or more solids), surface (key output.surface), temperature (key temperature),
/// phase_transition (key phase_transition; needs temperature and elasticity) and skin (key skin of a solid;
/// needs elasticity). An unknown name is rejected. The keys of a physics not enabled are rejected.
const std::vector<std::string>& sphOptionalPhysics();

}  // namespace rc
