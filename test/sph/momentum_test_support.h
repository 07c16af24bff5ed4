#pragma once
// Linear and angular momentum of a particle system with the scales their relative errors are taken against.

#include <algorithm>

#include "relaxed_connectivity/sph/sph_particles.h"

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

/// Largest relative change of linear and angular momentum over one call of step(), for `steps` calls, and
/// the angular momentum before the first and after the last.
struct MomentumDrift {
  double worst_linear = 0.0, worst_angular = 0.0;
  Vec3 angular_start = Vec3::Zero(), angular_end = Vec3::Zero();
};

template <class Step>
MomentumDrift trackMomentum(const SphParticles& p, int steps, Step step) {
  MomentumDrift d;
  Vec3 p0, l0;
  double sp, sl;
  momenta(p, p0, l0, sp, sl);
  d.angular_start = l0;
  for (int s = 0; s < steps; ++s) {
    step();
    Vec3 p1, l1;
    momenta(p, p1, l1, sp, sl);
    d.worst_linear = std::max(d.worst_linear, (p1 - p0).norm() / sp);
    d.worst_angular = std::max(d.worst_angular, (l1 - l0).norm() / sl);
    p0 = p1;
    l0 = l1;
  }
  d.angular_end = l0;
  return d;
}

}  // namespace rc
