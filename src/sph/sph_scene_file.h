// SPH scene files (YAML, config/sph/*.yaml): solver parameters (thesis 8.1.4, appendix F.2), fluid blocks,
// boundary walls / boxes / planes, moving boundary boxes, frames, particle outputs and the optional physics a
// scene switches on. The schema is documented at the top of config/sph/dam_break_2d.yaml.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "sph/sph_fluid_solver.h"
#include "sph/sph_particles.h"

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
};

/// Optional physics a scene may list under `enable:`; none of them is implemented yet, so every entry is
/// rejected with "not implemented yet" (an unknown name is rejected as unknown).
const std::vector<std::string>& sphOptionalPhysics();

/// Reads a scene file. Throws SphSceneError naming the file, line and problem (syntax, unknown key, wrong
/// type, bad value, unsupported physics).
SphScene loadSphScene(const std::string& path);
/// Same for YAML text; `source_name` stands for the file name in error messages.
SphScene parseSphScene(const std::string& yaml_text, const std::string& source_name);

}  // namespace rc
