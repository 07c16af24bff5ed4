// Densities by the continuity equation (SphDensityMethod::kContinuity): the rate of one particle over its
// neighbour row and the Shepard re-initialisation (SphFluidConfig::density_reinit_interval).
#include <cmath>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"

namespace rc {

double SphFluidSolver::continuityRate(size_t s, const uint32_t* row, size_t count,
                                      bool poly6_gradient) const {
  // drho_i/dt = sum_j m_j (v_i - v_j) . grad W_ij (Monaghan 1992, 3.8) with the pressure force's gradient:
  // the rate of the compression energy is then minus the power of the pressure forces.
  const Vec3 xi = s_pos_[s], vi = s_vel_rate_[s];
  const double h2 = kernels_.h2, inv_h = kernels_.inv_h;
  const double poly6_grad = -6.0 * kernels_.poly6_coeff / h2,
               spiky_grad = -3.0 * kernels_.spiky_coeff * inv_h;
  double rate = 0.0;
  for (size_t e = 0; e < count; ++e) {
    const uint32_t j = row[e];
    const Vec3 r = xi - s_pos_[j];
    const double d2 = r.squaredNorm();
    double g;  // grad W = g r
    if (poly6_gradient) {
      const double q = 1.0 - d2 / h2;
      g = poly6_grad * q * q;
    } else {
      const double d = std::sqrt(d2), u = 1.0 - d * inv_h;
      g = d > 0.0 ? spiky_grad * u * u / d : 0.0;
    }
    rate += s_mass_[j] * g * (vi - s_vel_rate_[j]).dot(r);
  }
  return rate;
}

void SphFluidSolver::reinitializeDensities() {
  SphParticles& p = particles_;
  const std::vector<uint32_t>& order = grid_.order();
  const size_t n = p.size();
  for (size_t s = 0; s < n; ++s) s_rho_given_[s] = p.densities[order[s]];  // this step's, sorted
  const double w0 = kernels_.poly6(0.0);
  const int threads = int(thread_first_.size()) - 1;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int t = 0; t < threads; ++t) {
    const uint32_t* list = thread_lists_[t].data();
    for (size_t s = thread_first_[t]; s < thread_first_[t + 1]; ++s) {
      if (s_kind_[s] != SphParticleKind::kFluid) continue;
      double mass_sum = s_mass_[s] * w0, volume_sum = s_mass_[s] / s_rho_given_[s] * w0;
      const uint32_t* row = list + row_begin_[s];
      for (uint32_t e = 0; e < row_count_[s]; ++e) {
        const uint32_t j = row[e];
        const double w = kernels_.poly6((s_pos_[s] - s_pos_[j]).squaredNorm());
        mass_sum += s_mass_[j] * w;
        volume_sum += s_mass_[j] / s_rho_given_[j] * w;
      }
      const uint32_t i = order[s];
      p.densities[i] = mass_sum / volume_sum;
      p.pressures[i] = pressureOf(p.densities[i]);
    }
  }
}

}  // namespace rc
