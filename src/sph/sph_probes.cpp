#include "relaxed_connectivity/sph/sph_probes.h"

#include <cmath>
#include <limits>

namespace rc {
namespace {

bool isLiquid(const SphParticles& p, size_t i) {
  return p.kinds[i] == SphParticleKind::kFluid && p.phases[i] == 0;
}

}  // namespace

SphBodyMeasures measureSphBody(const SphParticles& p) {
  SphBodyMeasures b;
  b.lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  b.hi = -b.lo;
  for (size_t i = 0; i < p.size(); ++i) {
    if (!isLiquid(p, i)) continue;
    ++b.particles;
    b.mass += p.masses[i];
    b.kinetic_energy += 0.5 * p.masses[i] * p.velocities[i].squaredNorm();
    b.momentum += p.masses[i] * p.velocities[i];
    b.centre += p.masses[i] * p.positions[i];
    b.lo = b.lo.cwiseMin(p.positions[i]);
    b.hi = b.hi.cwiseMax(p.positions[i]);
  }
  if (b.particles == 0) return SphBodyMeasures();
  b.centre /= b.mass;
  for (size_t i = 0; i < p.size(); ++i) {
    if (!isLiquid(p, i)) continue;
    const Vec3 d = p.positions[i] - b.centre;
    b.second_moments += p.masses[i] * d * d.transpose();
  }
  b.second_moments /= b.mass;
  return b;
}

SphPointSample sampleSphPoint(const SphParticles& p, const SphKernels& kernels, const Vec3& point) {
  const double h2 = kernels.h * kernels.h;
  double weight = 0, density = 0, pressure = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (!isLiquid(p, i) || !(p.densities[i] > 0)) continue;
    const double r2 = (p.positions[i] - point).squaredNorm();
    if (r2 >= h2) continue;
    const double w = p.masses[i] / p.densities[i] * kernels.poly6(r2);
    weight += w;
    density += w * p.densities[i];
    pressure += w * p.pressures[i];
  }
  if (!(weight > 0)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan};
  }
  return {density / weight, pressure / weight};
}

void writeSphProbeHeader(std::ostream& out, size_t points) {
  out << "time,particles,mass,kinetic_energy,momentum_x,momentum_y,momentum_z,centre_x,centre_y,centre_z,"
         "lo_x,lo_y,lo_z,hi_x,hi_y,hi_z,m_xx,m_yy,m_zz,m_xy,m_xz,m_yz";
  for (size_t k = 0; k < points; ++k) out << ",density_" << k << ",pressure_" << k;
  out << "\n";
}

void writeSphProbeRow(std::ostream& out, double time, const SphBodyMeasures& b,
                      const std::vector<SphPointSample>& samples) {
  const auto precision = out.precision(10);
  out << time << "," << b.particles << "," << b.mass << "," << b.kinetic_energy;
  for (const Vec3* v : {&b.momentum, &b.centre, &b.lo, &b.hi})
    for (int k = 0; k < 3; ++k) out << "," << (*v)[k];
  const Eigen::Matrix3d& m = b.second_moments;
  out << "," << m(0, 0) << "," << m(1, 1) << "," << m(2, 2) << "," << m(0, 1) << "," << m(0, 2) << ","
      << m(1, 2);
  for (const SphPointSample& s : samples) out << "," << s.density << "," << s.pressure;
  out << "\n";
  out.precision(precision);
}

}  // namespace rc
