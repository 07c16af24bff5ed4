// Structure-of-arrays particle state of the SPH solver (thesis 8.1).
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

enum class SphParticleKind : uint8_t {
  kFluid = 0,           ///< integrated
  kStaticBoundary = 1,  ///< contributes density and pressure forces, never moves
  kMovingBoundary = 2,  ///< like static, but moves with its (user-set) velocity
};

/// Particle state, one entry per particle in every array. Boundary particles are not integrated; a moving
/// boundary particle is advected with the velocity the user stores in `velocities`. densities, pressures and
/// forces are outputs of the solver (forces include gravity; force = mass * acceleration).
struct SphParticles {
  std::vector<Vec3> positions;
  std::vector<Vec3> velocities;
  std::vector<double> masses;
  std::vector<double> densities;
  std::vector<double> pressures;
  std::vector<Vec3> forces;
  std::vector<SphParticleKind> kinds;
  std::vector<uint8_t>
      phases;  ///< 0: fluid; 1..255: the elastic solid of that id (8.2), for kFluid particles

  size_t size() const { return positions.size(); }
  bool empty() const { return positions.empty(); }

  /// Appends one particle (density, pressure, force zero; phase 0). Returns its index.
  size_t add(const Vec3& position, const Vec3& velocity, double mass, SphParticleKind kind) {
    positions.push_back(position);
    velocities.push_back(velocity);
    masses.push_back(mass);
    densities.push_back(0.0);
    pressures.push_back(0.0);
    forces.push_back(Vec3::Zero());
    kinds.push_back(kind);
    phases.push_back(0);
    return positions.size() - 1;
  }

  size_t count(SphParticleKind kind) const {
    size_t c = 0;
    for (SphParticleKind k : kinds) c += (k == kind);
    return c;
  }
};

}  // namespace rc
