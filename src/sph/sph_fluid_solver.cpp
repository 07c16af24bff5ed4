#include "relaxed_connectivity/sph/sph_fluid_solver.h"

#include <omp.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace rc {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3g", v);
  return buf;
}

}  // namespace

namespace {
const SphFluidConfig& validated(const SphFluidConfig& config) {
  config.validate();
  return config;
}
}  // namespace

SphFluidSolver::SphFluidSolver(const SphFluidConfig& config, SphParticles particles)
    : config_(validated(config)),
      kernels_(config_.dimension, config_.smoothing_length),
      particles_(std::move(particles)) {
  num_threads_ = config_.num_threads > 0 ? config_.num_threads : omp_get_max_threads();
  validateParticles();
}

void SphFluidSolver::validateParticles() const {
  const SphParticles& p = particles_;
  const size_t n = p.size();
  auto fail = [](const std::string& what) { throw std::invalid_argument("SphParticles: " + what); };
  if (p.velocities.size() != n || p.masses.size() != n || p.densities.size() != n ||
      p.pressures.size() != n || p.forces.size() != n || p.kinds.size() != n || p.phases.size() != n)
    fail("all arrays must have the size of positions (" + std::to_string(n) + ")");
  for (size_t i = 0; i < n; ++i) {
    if (!p.positions[i].allFinite()) fail("position " + std::to_string(i) + " is not finite");
    if (!p.velocities[i].allFinite()) fail("velocity " + std::to_string(i) + " is not finite");
    if (!(p.masses[i] > 0.0) || !std::isfinite(p.masses[i]))
      fail("mass " + std::to_string(i) + " must be finite and > 0, got " + num(p.masses[i]));
    if (static_cast<uint8_t>(p.kinds[i]) > 2) fail("kind " + std::to_string(i) + " is unknown");
    if (config_.dimension == 2 && (p.positions[i].z() != 0.0 || p.velocities[i].z() != 0.0))
      fail("particle " + std::to_string(i) + " has z != 0 in a 2D simulation");
  }
}

void SphFluidSolver::addPlane(const SphPlane& plane) {
  if (!plane.normal.allFinite() || !(plane.normal.norm() > 0.0))
    throw std::invalid_argument("SphPlane.normal must be finite and non-zero");
  if (!std::isfinite(plane.offset)) throw std::invalid_argument("SphPlane.offset must be finite");
  if (!(plane.restitution >= 0.0 && plane.restitution <= 1.0))
    throw std::invalid_argument("SphPlane.restitution must be in [0, 1], got " + num(plane.restitution));
  if (!(plane.friction >= 0.0 && plane.friction <= 1.0))
    throw std::invalid_argument("SphPlane.friction must be in [0, 1], got " + num(plane.friction));
  if (config_.dimension == 2 && plane.normal.z() != 0.0)
    throw std::invalid_argument("SphPlane.normal must have z = 0 in 2D");
  SphPlane p = plane;
  const double len = plane.normal.norm();
  p.normal /= len;
  p.offset /= len;
  planes_.push_back(p);
}

double SphFluidSolver::pressureOf(double rho) const {
  const double ratio = rho / config_.rest_density;
  const double p =
      config_.stiffness * ((config_.gamma == 1.0 ? ratio : std::pow(ratio, config_.gamma)) - 1.0);  // (8.15)
  return p >= 0.0 ? p : config_.negative_pressure_scale * p;                                        // (8.16)
}

// e(rho) = int_{rho_0}^{rho} p(r) / r^2 dr >= 0, the compression energy per unit mass.
double SphFluidSolver::compressionEnergyOf(double rho) const {
  const double rho0 = config_.rest_density, k = config_.stiffness, g = config_.gamma;
  if (!(rho > 0.0)) return 0.0;
  double e = g == 1.0
                 ? k / rho0 * std::log(rho / rho0)
                 : k * std::pow(rho0, -g) * (std::pow(rho, g - 1.0) - std::pow(rho0, g - 1.0)) / (g - 1.0);
  e += k * (1.0 / rho - 1.0 / rho0);
  return rho >= rho0 ? e : config_.negative_pressure_scale * e;
}

void SphFluidSolver::computeForces() {
  validateParticles();
  const double dt = config_.fixed_dt > 0.0 ? config_.fixed_dt : stats_.dt;
  if (dt > 0.0) announceStep(dt);  // before the first adaptive step the terms keep their own dt
  computeForces(particles_.velocities);
  measureState();
}

void SphFluidSolver::computeForces(const std::vector<Vec3>& velocities) {
  const size_t n = particles_.size();
  accelerations_.resize(n);
  xsph_.resize(n);
  // Small systems run on fewer threads (barriers cost more than the work); results do not depend on it.
  const int threads = static_cast<int>(std::max<size_t>(1, std::min<size_t>(num_threads_, n / 2048)));
  grid_.build(particles_.positions, config_.smoothing_length, threads);
  const std::vector<uint32_t>& order = grid_.order();
  s_pos_.resize(n);
  s_vel_.resize(n);
  s_acc_.resize(n);
  s_xsph_.resize(n);
  s_mass_.resize(n);
  s_rho_.resize(n);
  s_press_.resize(n);
  s_press_term_.resize(n);
  if (config_.tensile_correction > 0.0) s_tension_.resize(n);
  const bool continuity = config_.density == SphDensityMethod::kContinuity;
  if (continuity) {
    s_rho_given_.resize(n);
    s_rho_rate_.resize(n);
    s_vel_rate_.resize(n);
    density_rates_.resize(n, 0.0);  // particles only ever get appended
  }
  s_kind_.resize(n);
  row_begin_.resize(n);
  row_count_.resize(n);
  if (thread_lists_.size() < size_t(threads)) thread_lists_.resize(threads);
  if (thread_sq_dists_.size() < size_t(threads)) thread_sq_dists_.resize(threads);
  if (thread_candidates_.size() < size_t(threads)) thread_candidates_.resize(threads);
  thread_first_.assign(threads + 1, 0);
  for (int t = 0; t <= threads; ++t) thread_first_[t] = n * t / threads;

#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    const size_t first = thread_first_[t], last = thread_first_[t + 1];
    for (size_t s = first; s < last; ++s) {  // gather into cell order
      const uint32_t i = order[s];
      s_pos_[s] = particles_.positions[i];
      s_kind_[s] = particles_.kinds[i];
      s_vel_[s] = s_kind_[s] == SphParticleKind::kStaticBoundary ? Vec3::Zero() : velocities[i];
      s_mass_[s] = particles_.masses[i];
      if (continuity) {  // a particle without a density yet (new) starts at rest
        double& rho = particles_.densities[i];
        if (!(rho > 0.0)) rho = config_.rest_density;
        s_rho_given_[s] = rho;
        s_vel_rate_[s] =
            s_kind_[s] == SphParticleKind::kStaticBoundary ? Vec3::Zero() : particles_.velocities[i];
      }
    }
#pragma omp barrier
    densityPass(t);
#pragma omp barrier
    if (config_.boundary_pressure == SphBoundaryPressure::kExtrapolated) {
      boundaryPressurePass(t);
#pragma omp barrier
    }
    forcePass(t);
#pragma omp barrier
    for (size_t s = first; s < last; ++s) {  // scatter back
      const uint32_t i = order[s];
      particles_.densities[i] = s_rho_[s];
      particles_.pressures[i] = s_press_[s];
      accelerations_[i] = s_acc_[s];
      particles_.forces[i] = s_mass_[s] * s_acc_[s];
      xsph_[i] = s_xsph_[s];
      if (continuity) density_rates_[i] = s_rho_rate_[s];
    }
  }
  // The force terms run on as many threads as this computation: where the whole step is small enough to run
  // serially, a term's one parallel region per step would leave a worker spinning (libgomp's default wait
  // policy) through the rest of the step, which on a loaded machine made 2 threads 2-3x slower than 1.
  for (const auto& term : force_terms_) term->setThreadLimit(threads);
  addTermForces(velocities);
  size_t entries = 0;
  for (size_t s = 0; s < n; ++s) entries += row_count_[s];
  stats_.neighbors_per_particle = n ? double(entries) / double(n) : 0.0;
  forces_valid_ = true;
}

bool SphFluidSolver::neighborsCurrent() const {
  const size_t n = particles_.size();
  if (!forces_valid_ || grid_.size() != n || s_pos_.size() != n) return false;
  const std::vector<uint32_t>& order = grid_.order();
  for (size_t s = 0; s < n; ++s)
    if (s_pos_[s] != particles_.positions[order[s]]) return false;
  return true;
}

const uint32_t* SphFluidSolver::neighborRow(size_t s, uint32_t& count) const {
  size_t t = 0;
  while (thread_first_[t + 1] <= s) ++t;  // the thread that owns row s (a handful of threads)
  count = row_count_[s];
  return thread_lists_[t].data() + row_begin_[s];
}

void SphFluidSolver::addForceTerm(std::shared_ptr<SphForceTerm> term) {
  if (!term) throw std::invalid_argument("SphFluidSolver::addForceTerm: term is null");
  term->setThreadLimit(num_threads_);
  force_terms_.push_back(std::move(term));
  forces_valid_ = false;
}

// Forces of the extra terms (8.2) on the integrated particles, added to forces and accelerations.
void SphFluidSolver::addTermForces(const std::vector<Vec3>& velocities) {
  stats_.term_energy = 0.0;
  if (force_terms_.empty()) return;
  const size_t n = particles_.size();
  term_forces_.assign(n, Vec3::Zero());
  for (const auto& term : force_terms_) {
    // Elastic solids read their neighbourhoods from this evaluation's rows (no search of their own).
    term->setNeighborSource(this);
    term->addForces(particles_, velocities, term_forces_);
    term->setNeighborSource(nullptr);
    stats_.term_energy += term->potentialEnergy();
  }
  for (size_t i = 0; i < n; ++i) {
    if (particles_.kinds[i] != SphParticleKind::kFluid) continue;
    particles_.forces[i] += term_forces_[i];
    accelerations_[i] += term_forces_[i] / particles_.masses[i];
  }
}

// Density (8.4) and pressure (8.15)-(8.16) of the sorted particles [first, last); records the neighbour rows.
void SphFluidSolver::densityPass(int t) {
  const size_t first = thread_first_[t], last = thread_first_[t + 1];
  std::vector<uint32_t>& list = thread_lists_[t];
  size_t used = 0;
  const double h2 = kernels_.h2;
  std::vector<double>& sq_dists = thread_sq_dists_[t];
  CellCandidates& cand = thread_candidates_[t];
  SphSortedGrid::Run runs[9];
  size_t candidates = 0, padded = 0;
  uint32_t current_cell = std::numeric_limits<uint32_t>::max();
  const Vec3* pos = s_pos_.data();
  const double* mass = s_mass_.data();
  const double* given = config_.density == SphDensityMethod::kContinuity ? s_rho_given_.data() : nullptr;
  const bool poly6_gradient = config_.pressure_kernel == SphPressureKernel::kPoly6;
  for (size_t s = first; s < last; ++s) {
    const uint32_t c = grid_.cellOfSorted(s);
    if (c != current_cell) {
      // The candidates of the cell's block, shared by its particles, as structure of arrays (in run order),
      // padded to an even count by a point that is no neighbour of any particle. Only points closer than h
      // to the bounding box of the cell's particles (those of this thread) are kept: a point dropped is no
      // neighbour of any of them, and the kept ones stay in run order, so the rows are the same (the far
      // parts of the block's edge and corner cells drop out).
      current_cell = c;
      double box_lo[3] = {pos[s].x(), pos[s].y(), pos[s].z()};
      double box_hi[3] = {box_lo[0], box_lo[1], box_lo[2]};
      for (size_t s2 = s + 1; s2 < last && grid_.cellOfSorted(s2) == c; ++s2)
        for (int k = 0; k < 3; ++k) {
          box_lo[k] = std::min(box_lo[k], pos[s2][k]);
          box_hi[k] = std::max(box_hi[k], pos[s2][k]);
        }
      const int num_runs = grid_.neighborRuns(c, runs);
      size_t block = 0;
      for (int r = 0; r < num_runs; ++r) block += runs[r].end - runs[r].begin;
      if (cand.x.size() < block + 1) {
        cand.x.resize(block + 65);
        cand.y.resize(block + 65);
        cand.z.resize(block + 65);
        cand.index.resize(block + 65);
      }
      // The squared distance to the box is at most the squared distance to any particle in it, also as
      // rounded below (rounding is monotonic and the sums are taken in the same order); the slack covers
      // compilers that contract the sums into fused multiply-adds.
      const double box_h2 = h2 * (1.0 + 1e-9);
      size_t e = 0;
#ifdef __SSE2__
      // x and y in one register; max instructions, not branches (which the compiler makes of std::max).
      const __m128d zero = _mm_setzero_pd(), lo_xy = _mm_loadu_pd(box_lo), hi_xy = _mm_loadu_pd(box_hi);
      const __m128d lo_z = _mm_set_sd(box_lo[2]), hi_z = _mm_set_sd(box_hi[2]);
      for (int r = 0; r < num_runs; ++r)
        for (uint32_t j = runs[r].begin; j < runs[r].end; ++j) {
          const __m128d xy = _mm_loadu_pd(pos[j].data()), z = _mm_load_sd(pos[j].data() + 2);
          const __m128d b_xy = _mm_max_pd(zero, _mm_max_pd(_mm_sub_pd(lo_xy, xy), _mm_sub_pd(xy, hi_xy)));
          const __m128d b_z = _mm_max_sd(zero, _mm_max_sd(_mm_sub_sd(lo_z, z), _mm_sub_sd(z, hi_z)));
          const __m128d sq = _mm_mul_pd(b_xy, b_xy);
          const double d2 = _mm_cvtsd_f64(_mm_add_sd(_mm_add_sd(sq, _mm_unpackhi_pd(sq, sq)),
                                                     _mm_mul_sd(b_z, b_z)));  // (x^2 + y^2) + z^2
          _mm_store_sd(&cand.x[e], xy);  // branch-free: written, kept if within h of the box
          _mm_storeh_pd(&cand.y[e], xy);
          _mm_store_sd(&cand.z[e], z);
          cand.index[e] = j;
          e += size_t(d2 < box_h2);
        }
#else
      for (int r = 0; r < num_runs; ++r)
        for (uint32_t j = runs[r].begin; j < runs[r].end; ++j) {
          const double x = pos[j].x(), y = pos[j].y(), z = pos[j].z();
          const double bx = std::max(0.0, std::max(box_lo[0] - x, x - box_hi[0]));
          const double by = std::max(0.0, std::max(box_lo[1] - y, y - box_hi[1]));
          const double bz = std::max(0.0, std::max(box_lo[2] - z, z - box_hi[2]));
          cand.x[e] = x;  // branch-free: written, kept if within h of the box
          cand.y[e] = y;
          cand.z[e] = z;
          cand.index[e] = j;
          e += size_t((bx * bx + by * by) + bz * bz < box_h2);
        }
#endif
      candidates = e;
      padded = candidates + (candidates & 1);
      if (padded != candidates) {
        cand.x[e] = cand.y[e] = cand.z[e] = std::numeric_limits<double>::infinity();
        cand.index[e] = std::numeric_limits<uint32_t>::max();
      }
    }
    if (used + padded > list.size()) list.resize(std::max(2 * list.size(), used + padded + 4096));
    if (sq_dists.size() < padded) sq_dists.resize(padded);
    uint32_t* out = list.data() + used;
    double* d2s = sq_dists.data();
    const double px = pos[s].x(), py = pos[s].y(), pz = pos[s].z();
    const uint32_t self = uint32_t(s);
    size_t found = 0;
    // Branch-free: every candidate is written, the count advances only for neighbours (d < h, not s).
#ifdef __SSE2__
    const __m128d vx = _mm_set1_pd(px), vy = _mm_set1_pd(py), vz = _mm_set1_pd(pz), vh2 = _mm_set1_pd(h2);
    for (size_t e = 0; e < padded; e += 2) {  // two candidates at a time, the same arithmetic per lane
      const __m128d dx = _mm_sub_pd(_mm_loadu_pd(&cand.x[e]), vx);
      const __m128d dy = _mm_sub_pd(_mm_loadu_pd(&cand.y[e]), vy);
      const __m128d dz = _mm_sub_pd(_mm_loadu_pd(&cand.z[e]), vz);
      const __m128d d2 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), _mm_mul_pd(dz, dz));
      const int inside = _mm_movemask_pd(_mm_cmplt_pd(d2, vh2));
      const uint32_t j0 = cand.index[e], j1 = cand.index[e + 1];
      out[found] = j0;
      _mm_store_sd(&d2s[found], d2);
      found += size_t((inside & 1) & (j0 != self));
      out[found] = j1;
      _mm_storeh_pd(&d2s[found], d2);
      found += size_t(((inside >> 1) & 1) & (j1 != self));
    }
#else
    for (size_t e = 0; e < candidates; ++e) {
      const double dx = cand.x[e] - px, dy = cand.y[e] - py, dz = cand.z[e] - pz;
      const double d2 = dx * dx + dy * dy + dz * dz;
      out[found] = cand.index[e];
      d2s[found] = d2;
      found += size_t((d2 < h2) & (cand.index[e] != self));
    }
#endif
    for (size_t e = 0; e < found; ++e) {  // (1 - d^2/h^2)^3, apart from the sum: vectorised
      const double q = 1.0 - d2s[e] / h2;
      d2s[e] = q * q * q;
    }
    double sum = 0.0;                                                 // sum_j m_j (1 - d^2/h^2)^3
    for (size_t e = 0; e < found; ++e) sum += mass[out[e]] * d2s[e];  // in neighbour order, as always
    double rho = kernels_.poly6_coeff * (mass[s] + sum);              // (8.4), self term included
    if (given && s_kind_[s] == SphParticleKind::kFluid) {
      const double rate = continuityRate(s, out, found, poly6_gradient);
      s_rho_rate_[s] = rate;
      rho = given[s] + continuity_dt_ * rate;
    } else if (given) {
      s_rho_rate_[s] = 0.0;
    }
    row_begin_[s] = static_cast<uint32_t>(used);
    row_count_[s] = static_cast<uint32_t>(found);
    used += found;
    s_rho_[s] = rho;
    double p = pressureOf(rho);
    if (s_kind_[s] != SphParticleKind::kFluid) p = std::max(p, 0.0);  // walls never pull
    s_press_[s] = p;
    s_press_term_[s] = p / (rho * rho);
    if (config_.tensile_correction > 0.0)  // Monaghan 2000: R_i for particles under tension
      s_tension_[s] = p < 0.0 ? config_.tensile_correction * -s_press_term_[s] : 0.0;
  }
}

// Boundary pressures extrapolated from the fluid (Adami et al. 2012, eq. 27; see SphBoundaryPressure) of the
// sorted boundary particles [first, last). Reads only fluid pressures and densities of the density pass.
void SphFluidSolver::boundaryPressurePass(int t) {
  const size_t first = thread_first_[t], last = thread_first_[t + 1];
  const uint32_t* list = thread_lists_[t].data();
  const double h2 = kernels_.h2, rho0 = config_.rest_density;
  const Vec3 gravity = config_.gravity;
  for (size_t s = first; s < last; ++s) {
    if (s_kind_[s] == SphParticleKind::kFluid) continue;
    const Vec3 xw = s_pos_[s];
    double sum_w = 0.0, sum_pw = 0.0;
    Vec3 sum_rho_r = Vec3::Zero();
    const uint32_t* row = list + row_begin_[s];
    for (uint32_t e = 0, ne = row_count_[s]; e < ne; ++e) {
      const uint32_t f = row[e];
      if (s_kind_[f] != SphParticleKind::kFluid) continue;
      const Vec3 r = xw - s_pos_[f];
      const double q = 1.0 - r.squaredNorm() / h2;
      const double w = q * q * q;  // poly6 up to its constant, which cancels
      sum_w += w;
      sum_pw += s_press_[f] * w;
      sum_rho_r += (s_rho_[f] * w) * r;
    }
    const double p = sum_w > 0.0 ? std::max(0.0, (sum_pw + gravity.dot(sum_rho_r)) / sum_w) : 0.0;
    // Invert (8.15) for the wall density.
    const double ratio = p / config_.stiffness + 1.0;
    const double rho = rho0 * (config_.gamma == 1.0 ? ratio : std::pow(ratio, 1.0 / config_.gamma));
    s_rho_[s] = rho;
    s_press_[s] = p;
    s_press_term_[s] = p / (rho * rho);
    if (config_.tensile_correction > 0.0) s_tension_[s] = 0.0;  // p >= 0
  }
}

// Accelerations (8.14) with the symmetric pressure force (8.17) and viscosity (8.18), and the XSPH velocity
// correction (8.19), of the sorted fluid particles [first, last). Pair terms are computed so that the term of
// (i, j) is exactly the negative of the term of (j, i).
void SphFluidSolver::forcePass(int t) {
  // Without viscosity or the tensile correction their terms are zero (adding them changes no sum), so they
  // are compiled out.
  const bool flags[3] = {config_.pressure_kernel == SphPressureKernel::kPoly6, config_.viscosity != 0.0,
                         config_.tensile_correction > 0.0};
  forcePassWith<>(t, flags);
}

template <bool... kFlags>
void SphFluidSolver::forcePassWith(int t, const bool* flags) {
  if constexpr (sizeof...(kFlags) == 3) {
    forcePassOf<kFlags...>(t);
  } else {
    if (flags[sizeof...(kFlags)])
      forcePassWith<kFlags..., true>(t, flags);
    else
      forcePassWith<kFlags..., false>(t, flags);
  }
}

template <bool kPoly6Pressure, bool kViscosity, bool kTensile>
void SphFluidSolver::forcePassOf(int t) {
  const size_t first = thread_first_[t], last = thread_first_[t + 1];
  const uint32_t* list = thread_lists_[t].data();
  const double inv_h = kernels_.inv_h;
  const double spiky_grad = -3.0 * kernels_.spiky_coeff * inv_h;  // w^'(d) = spiky_grad (1 - d/h)^2
  const double poly6_grad = -6.0 * kernels_.poly6_coeff / kernels_.h2;
  const double visc = config_.viscosity * kernels_.viscosity_coeff;
  const double xi = config_.xsph, poly6 = kernels_.poly6_coeff, h2 = kernels_.h2;
  const Vec3 gravity = config_.gravity;
  const Vec3* pos = s_pos_.data();
  const Vec3* vel = s_vel_.data();
  const double* mass = s_mass_.data();
  const double* rho = s_rho_.data();
  const double* press_term = s_press_term_.data();
  const double* tension = kTensile ? s_tension_.data() : nullptr;
  // f = W(r) / W(Delta p) = (q / q_p)^3 for poly6, q = 1 - r^2/h^2; f^4 = (q / q_p)^12.
  const double inv_q_spacing =
      kTensile ? 1.0 / (1.0 - config_.tensile_spacing * config_.tensile_spacing / h2) : 0.0;
  const SphParticleKind* kind = s_kind_.data();
  for (size_t s = first; s < last; ++s) {
    if (kind[s] != SphParticleKind::kFluid) {
      s_acc_[s].setZero();
      s_xsph_[s].setZero();
      continue;
    }
    const Vec3 xi_pos = pos[s], vi = vel[s];
    const double mi = mass[s], rhoi = rho[s], pti = press_term[s];
    Vec3 force = Vec3::Zero(), smooth = Vec3::Zero();
    const uint32_t* row = list + row_begin_[s];
    for (uint32_t e = 0, ne = row_count_[s]; e < ne; ++e) {
      const uint32_t j = row[e];
      const Vec3 r = xi_pos - pos[j];
      const double d2 = r.squaredNorm();
      const double mm = mi * mass[j];
      const double q = 1.0 - d2 / h2;
      // -grad_i of pressure: -m_i m_j (p_i/rho_i^2 + p_j/rho_j^2) grad W^(r_ij)   (8.17)
      const double pressure = pti + press_term[j];
      if (kTensile) {
        // + (R_i + R_j) f^4 (Monaghan 2000), along the spiky gradient whatever the pressure kernel: poly6's
        // vanishes as r -> 0 and would let a pair that came close stay paired.
        const double a = q * inv_q_spacing, a2 = a * a, a4 = a2 * a2;  // a = (W(r) / W(Delta p))^(1/3)
        const double d = std::sqrt(d2), u = 1.0 - d * inv_h;
        if (d > 0.0)
          force -= ((tension[s] + tension[j]) * (a4 * a4 * a4) * mm * (spiky_grad * u * u / d)) * r;
      }
      if (kPoly6Pressure) {
        force -= (pressure * mm * (poly6_grad * q * q)) * r;  // grad W = poly6_grad q^2 r
      } else {
        const double d = std::sqrt(d2);
        const double u = 1.0 - d * inv_h;
        if (d > 0.0) force -= (pressure * mm * (spiky_grad * u * u / d)) * r;
      }
      const Vec3 dv = vel[j] - vi;
      if (kViscosity) {
        // mu V_i V_j lap W (v_j - v_i)   (8.12), (8.18)
        const double u = 1.0 - std::sqrt(d2) * inv_h;
        force += (visc * mm / (rhoi * rho[j]) * u) * dv;
      }
      if (kind[j] == SphParticleKind::kFluid)
        smooth += (mass[j] / (0.5 * (rhoi + rho[j])) * poly6 * q * q * q) * dv;  // (8.19)
    }
    s_acc_[s] = force / mi + gravity;
    s_xsph_[s] = xi * smooth;
  }
}

void SphFluidSolver::chooseTimeStep(double requested_dt) {
  const double h = config_.smoothing_length, cfl = config_.cfl;
  const SphParticles& p = particles_;
  double max_speed = 0.0, max_acc = 0.0, max_rho = config_.rest_density;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.kinds[i] == SphParticleKind::kStaticBoundary) continue;
    max_speed = std::max(max_speed, p.velocities[i].norm());
    if (p.kinds[i] != SphParticleKind::kFluid) continue;
    max_acc = std::max(max_acc, accelerations_[i].norm());
    max_rho = std::max(max_rho, p.densities[i]);
  }
  const double c = std::sqrt(config_.stiffness * config_.gamma / config_.rest_density *
                             std::pow(max_rho / config_.rest_density, config_.gamma - 1.0));
  stats_.dt_speed = max_speed > 0.0 ? cfl * h / max_speed : kInf;
  stats_.dt_sound = cfl * h / c;
  // Explicit viscosity is stable for dt <= 2 / lambda_max, lambda_max = 2 nu int L dV = 2 nu (15 | 40/3) /
  // h^2 (3D | 2D) on a filled neighbourhood.
  const double nu = config_.viscosity / config_.rest_density;
  const double lap_integral = (config_.dimension == 3 ? 15.0 : 40.0 / 3.0) / (h * h);
  stats_.dt_viscosity = nu > 0.0 ? cfl / (nu * lap_integral) : kInf;
  stats_.dt_force = max_acc > 0.0 ? cfl * std::sqrt(h / max_acc) : kInf;
  stats_.dt_elastic = kInf;
  for (const auto& term : force_terms_)
    stats_.dt_elastic = std::min(stats_.dt_elastic, term->stableTimeStep(p, cfl));
  if (config_.fixed_dt > 0.0) {
    stats_.dt = config_.fixed_dt;
    stats_.limit = SphStepLimit::kFixed;
  } else {
    stats_.dt = config_.max_dt;
    stats_.limit = SphStepLimit::kMaxDt;
    const std::pair<double, SphStepLimit> limits[] = {{stats_.dt_speed, SphStepLimit::kSpeed},
                                                      {stats_.dt_sound, SphStepLimit::kSoundSpeed},
                                                      {stats_.dt_viscosity, SphStepLimit::kViscosity},
                                                      {stats_.dt_force, SphStepLimit::kForce},
                                                      {stats_.dt_elastic, SphStepLimit::kElastic}};
    for (const auto& l : limits)
      if (l.first < stats_.dt) {
        stats_.dt = l.first;
        stats_.limit = l.second;
      }
  }
  if (requested_dt > 0.0 && requested_dt < stats_.dt) stats_.dt = requested_dt;
}

void SphFluidSolver::collideWithPlanes(size_t i) {
  Vec3& x = particles_.positions[i];
  Vec3& v = particles_.velocities[i];
  for (const SphPlane& plane : planes_) {
    const double depth = plane.offset - plane.normal.dot(x);
    if (depth <= 0.0) continue;
    x += depth * plane.normal;
    const double vn = plane.normal.dot(v);
    if (vn < 0.0) {
      const Vec3 tangential = v - vn * plane.normal;
      v = (1.0 - plane.friction) * tangential - plane.restitution * vn * plane.normal;
    }
  }
}

const SphStepStats& SphFluidSolver::step() {
  return advanceOneStep(0.0);
}

const SphStepStats& SphFluidSolver::stepUntil(double end_time) {
  const double remaining = end_time - time_;
  if (!(remaining > 0.0) || !std::isfinite(remaining))
    throw std::invalid_argument("SphFluidSolver::stepUntil: end_time " + num(end_time) +
                                " must lie after the current time " + num(time_));
  advanceOneStep(remaining);
  if (remaining <= stats_.dt) {  // as advance() ends its last step
    time_ = end_time;
    stats_.time = end_time;
  }
  return stats_;
}

const SphStepStats& SphFluidSolver::advance(double duration,
                                            const std::function<void(const SphStepStats&)>& after_step) {
  if (!(duration >= 0.0) || !std::isfinite(duration))
    throw std::invalid_argument("SphFluidSolver::advance: duration must be finite and >= 0, got " +
                                num(duration));
  const double end = time_ + duration;
  while (time_ < end) {
    const double remaining = end - time_;
    advanceOneStep(remaining);
    if (remaining <= stats_.dt) {
      time_ = end;
      stats_.time = end;
      if (after_step) after_step(stats_);
      break;
    }
    if (after_step) after_step(stats_);
  }
  return stats_;
}

const SphStepStats& SphFluidSolver::advanceOneStep(double requested_dt) {
  const auto t0 = std::chrono::steady_clock::now();
  SphParticles& p = particles_;
  const size_t n = p.size();
  if (!forces_valid_ || accelerations_.size() != n) {
    validateParticles();
    announceStep(config_.fixed_dt > 0.0 ? config_.fixed_dt : stats_.dt);
    computeForces(p.velocities);
    measureState();
  }
  chooseTimeStep(requested_dt);
  if (forces_dt_ == 0.0 && stats_.dt > 0.0) {
    // Forces of implicit terms evaluated without a step (the first adaptive step): again with its dt.
    bool implicit = false;
    for (const auto& term : force_terms_) implicit = implicit || term->implicitInStep();
    if (implicit) {
      announceStep(stats_.dt);
      computeForces(p.velocities);
      measureState();
    }
  }
  const double dt = stats_.dt;
  const double energy_before = stats_.kinetic_energy + stats_.compression_energy + stats_.term_energy;
  // Kick, drift (with the XSPH correction), predict.
  predicted_.resize(n);
  double gravity_work = 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (p.kinds[i] == SphParticleKind::kStaticBoundary) {
      predicted_[i].setZero();
      continue;
    }
    if (p.kinds[i] == SphParticleKind::kMovingBoundary) {
      p.positions[i] += dt * p.velocities[i];
      predicted_[i] = p.velocities[i];
      continue;
    }
    const Vec3 old = p.positions[i];
    p.velocities[i] += 0.5 * dt * accelerations_[i];
    p.positions[i] += dt * (p.velocities[i] + xsph_[i]);
    collideWithPlanes(i);
    predicted_[i] = p.velocities[i] + 0.5 * dt * accelerations_[i];
    gravity_work += p.masses[i] * config_.gravity.dot(p.positions[i] - old);
  }

  stats_.unstable = false;
  stats_.instability.clear();
  bool finite = true;
  for (size_t i = 0; i < n && finite; ++i) finite = p.positions[i].allFinite() && predicted_[i].allFinite();
  if (finite) {
    announceStep(dt);
    continuity_dt_ = dt;  // continuity densities: rho += dt D(x', v'), as x += dt v'
    computeForces(predicted_);
    continuity_dt_ = 0.0;
    for (size_t i = 0; i < n; ++i)  // final kick
      if (p.kinds[i] == SphParticleKind::kFluid) p.velocities[i] += 0.5 * dt * accelerations_[i];
    if (config_.density == SphDensityMethod::kContinuity && config_.density_reinit_interval > 0 &&
        (step_count_ + 1) % uint64_t(config_.density_reinit_interval) == 0)
      reinitializeDensities();
  }
  time_ += dt;
  ++step_count_;
  stats_.step = step_count_;
  stats_.time = time_;
  if (!measureState()) finite = false;
  const double kinetic = stats_.kinetic_energy;
  if (!finite || !std::isfinite(kinetic)) {
    stats_.unstable = true;
    stats_.instability = "non-finite positions or velocities";
  } else {
    // Energy available to the kinetic energy: what was there, gravity's work, what moving walls may add.
    const double floor =
        1e-16 * fluid_mass_ *
        (config_.soundSpeed() * config_.soundSpeed() + config_.gravity.norm() * config_.smoothing_length);
    const double inflow = std::max(gravity_work, 0.0) + fluid_mass_ * max_boundary_speed2_;
    const double available = energy_before + inflow + floor;
    // The window: restarted every instability_window steps and when fluid appears or changes phase.
    if (window_mass_ != fluid_mass_ || step_count_ - window_start_ > uint64_t(config_.instability_window)) {
      window_start_ = step_count_ - 1;
      window_energy_ = energy_before;
      window_mass_ = fluid_mass_;
      window_inflow_ = 0.0;
    }
    window_inflow_ += inflow;
    if (kinetic > config_.instability_energy_growth * available) {
      stats_.unstable = true;
      stats_.instability = "kinetic energy grew from " + num(energy_before) + " (+ gravity work " +
                           num(gravity_work) + ") to " + num(kinetic) + " in one step";
    } else if (config_.instability_window > 0 && force_terms_.empty() &&
               kinetic > config_.instability_window_growth * (window_energy_ + window_inflow_ + floor)) {
      stats_.unstable = true;
      stats_.instability = "kinetic energy grew from " + num(window_energy_) + " (+ " + num(window_inflow_) +
                           " from gravity and moving walls) to " + num(kinetic) + " in " +
                           std::to_string(step_count_ - window_start_) + " steps";
    } else if (config_.max_compression > 0 && stats_.max_compression > config_.max_compression) {
      stats_.unstable = true;
      stats_.instability = "fluid compressed by " + num(100 * stats_.max_compression) +
                           " % (max_compression " + num(100 * config_.max_compression) + " %)";
    }
  }
  stats_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (stats_.unstable) {
    stats_.instability = "SPH step " + std::to_string(step_count_) + " (t = " + num(time_) +
                         ") unstable: " + stats_.instability + "; likely cause: " + likelyCause();
    if (config_.throw_on_instability) throw SphInstabilityError(step_count_, stats_.instability);
  }
  return stats_;
}

void SphFluidSolver::announceStep(double dt) {
  forces_dt_ = dt;
  for (const auto& term : force_terms_) term->beginStep(dt);
}

bool SphFluidSolver::measureState() {
  const SphParticles& p = particles_;
  double kinetic = 0.0, compression = 0.0, max_speed = 0.0, max_err = 0.0, fluid_mass = 0.0,
         boundary_v2 = 0.0, max_compression = 0.0;
  const bool summation_walls = config_.boundary_pressure == SphBoundaryPressure::kSummation;
  const double rho0 = config_.rest_density;
  bool finite = true;
  for (size_t i = 0; i < p.size(); ++i) {  // serial: sums in a fixed order
    if (p.kinds[i] == SphParticleKind::kMovingBoundary)
      boundary_v2 = std::max(boundary_v2, p.velocities[i].squaredNorm());
    if (p.kinds[i] != SphParticleKind::kFluid) {
      // Summation walls: p_w = max(p(rho_w), 0) is the derivative of this energy (see SphBoundaryPressure).
      if (summation_walls && p.densities[i] > rho0)
        compression += p.masses[i] * compressionEnergyOf(p.densities[i]);
      continue;
    }
    const double v2 = p.velocities[i].squaredNorm();
    if (!std::isfinite(v2) || !p.positions[i].allFinite()) finite = false;
    kinetic += 0.5 * p.masses[i] * v2;
    compression += p.masses[i] * compressionEnergyOf(p.densities[i]);
    max_speed = std::max(max_speed, std::sqrt(v2));
    max_err = std::max(max_err, std::abs(p.densities[i] - config_.rest_density) / config_.rest_density);
    if (p.phases[i] == 0)  // liquid (solids, phase >= 1, press together at contacts)
      max_compression = std::max(max_compression, (p.densities[i] - rho0) / rho0);
    fluid_mass += p.masses[i];
  }
  stats_.kinetic_energy = kinetic;
  stats_.compression_energy = compression;
  stats_.max_speed = max_speed;
  stats_.max_density_error = max_err;
  stats_.max_compression = max_compression;
  fluid_mass_ = fluid_mass;
  max_boundary_speed2_ = boundary_v2;
  return finite && std::isfinite(kinetic);
}

std::string SphFluidSolver::likelyCause() const {
  const double dt = stats_.dt;
  const std::pair<double, const char*> limits[] = {{stats_.dt_sound, "sound-speed"},
                                                   {stats_.dt_speed, "CFL (speed)"},
                                                   {stats_.dt_viscosity, "viscosity"},
                                                   {stats_.dt_force, "force"},
                                                   {stats_.dt_elastic, "elastic wave speed"}};
  double worst = 1.0;
  const char* name = nullptr;
  double limit = 0.0;
  for (const auto& l : limits)
    if (dt / l.first > worst) {
      worst = dt / l.first;
      name = l.second;
      limit = l.first;
    }
  if (name) return "dt " + num(dt) + " exceeds the " + name + " limit " + num(limit);
  if (stats_.max_compression > 0.1)  // clumping: pairs pulled together
    return "particles clump (compressed by " + num(100 * stats_.max_compression) +
           " %): a tensile instability (negative_pressure_scale " + num(config_.negative_pressure_scale) +
           ") or too few neighbours (" + num(stats_.neighbors_per_particle) +
           " per particle; h / spacing too small), or a stiffness far too low";
  return "dt " + num(dt) + " is within all limits (sound " + num(stats_.dt_sound) + ", viscosity " +
         num(stats_.dt_viscosity) +
         "); check the particle spacing against h, boundary velocities and "
         "stiffness";
}

}  // namespace rc
