#pragma once
// Linear and angular momentum of a particle system with the scales their relative errors are taken against.

#include "sph/sph_particles.h"

namespace rc {

/// linear = sum m v, angular = sum x x m v; scale_p = sum |m v|, scale_l = sum |x| |m v|.
inline void momenta(const SphParticles& p, Vec3& linear, Vec3& angular, double& scale_p, double& scale_l) {
  linear.setZero();
  angular.setZero();
  scale_p = scale_l = 0.0;
  for (size_t i = 0; i < p.size(); ++i) {
    const Vec3 mv = p.masses[i] * p.velocities[i];
    linear += mv;
    angular += p.positions[i].cross(mv);
    scale_p += mv.norm();
    scale_l += p.positions[i].norm() * mv.norm();
  }
}

}  // namespace rc
