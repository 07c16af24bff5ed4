// Probes of an SPH run (issue 22): measures of the liquid body (mass, kinetic energy, momentum, centre,
// extent and second moments) and pressure and density at fixed points, for scenes that check a run against a
// reference (the scene key `probes`; runSphScene writes one CSV row per frame).
#pragma once

#include <Eigen/Core>
#include <ostream>
#include <vector>

#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_particles.h"

namespace rc {

/// The liquid: fluid particles of phase 0 (solids excluded).
struct SphBodyMeasures {
  size_t particles = 0;
  double mass = 0.0, kinetic_energy = 0.0;
  Vec3 momentum = Vec3::Zero(), centre = Vec3::Zero();  ///< centre of mass
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();            ///< extent of the particle positions
  /// Mass-weighted central second moments sum m (x - c)(x - c)^T / M (a filled ellipse of semi-axes a, b:
  /// diag(a^2, b^2) / 4).
  Eigen::Matrix3d second_moments = Eigen::Matrix3d::Zero();
};
SphBodyMeasures measureSphBody(const SphParticles& particles);

/// Density and pressure at a point: the Shepard average sum V_j W_ij f_j / sum V_j W_ij over the liquid
/// particles within h (V_j = m_j / rho_j, W the poly6 kernel); NaN where no particle reaches the point.
struct SphPointSample {
  double density = 0.0, pressure = 0.0;
};
SphPointSample sampleSphPoint(const SphParticles& particles, const SphKernels& kernels, const Vec3& point);

/// CSV: the header, then one row per call (time, body measures, then density and pressure per point).
void writeSphProbeHeader(std::ostream& out, size_t points);
void writeSphProbeRow(std::ostream& out, double time, const SphBodyMeasures& body,
                      const std::vector<SphPointSample>& samples);

}  // namespace rc
