#include "relaxed_connectivity/sph/sph_thermal.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/LU>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"

namespace rc {

namespace {

void require(bool ok, const char* field, const std::string& problem) {
  if (!ok) throw std::invalid_argument(std::string("SphThermalConfig.") + field + ": " + problem);
}

bool finite(double v) {
  return std::isfinite(v);
}

uint64_t splitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

}  // namespace

void SphThermalConfig::validate() const {
  require(conductivity >= 0.0 && finite(conductivity), "conductivity",
          "must be finite and >= 0, got " + std::to_string(conductivity));
  require(heat_capacity > 0.0 && finite(heat_capacity), "heat_capacity",
          "must be finite and > 0, got " + std::to_string(heat_capacity));
  require(rest_density > 0.0 && finite(rest_density), "rest_density",
          "must be finite and > 0, got " + std::to_string(rest_density));
  require(finite(initial_temperature), "initial_temperature", "must be finite");
  require(finite(ambient_temperature), "ambient_temperature", "must be finite");
  require(ambient_rate >= 0.0 && finite(ambient_rate), "ambient_rate",
          "must be finite and >= 0, got " + std::to_string(ambient_rate));
  require(stability_factor > 0.0 && stability_factor <= 1.0, "stability_factor",
          "must be in (0, 1], got " + std::to_string(stability_factor));
  require(max_substeps >= 1, "max_substeps", "must be >= 1, got " + std::to_string(max_substeps));
  require(num_threads >= 0, "num_threads", "must be >= 0 (0 = all), got " + std::to_string(num_threads));
  require(melting_rate >= 0.0 && finite(melting_rate), "melting_rate",
          "must be finite and >= 0, got " + std::to_string(melting_rate));
  require(finite(melting_temperature), "melting_temperature", "must be finite");
  require(freezing_rate >= 0.0 && finite(freezing_rate), "freezing_rate",
          "must be finite and >= 0, got " + std::to_string(freezing_rate));
  require(finite(freezing_temperature), "freezing_temperature", "must be finite");
  require(freezing_phase >= 1, "freezing_phase", "must be a solid id >= 1 (0 is the fluid)");
  require(finite(min_solid_neighbors), "min_solid_neighbors", "must be finite");
  require(max_relative_speed > 0.0, "max_relative_speed",
          "must be > 0 (infinity: no limit), got " + std::to_string(max_relative_speed));
  require(max_lattice_force > 0.0, "max_lattice_force",
          "must be > 0 (infinity: no limit), got " + std::to_string(max_lattice_force));
}

SphThermalModel::SphThermalModel(const SphThermalConfig& config) : config_(config) {
  config_.validate();
  num_threads_ = config_.num_threads > 0 ? config_.num_threads : omp_get_max_threads();
}

void SphThermalModel::setTemperature(size_t first, size_t count, double temperature) {
  if (!finite(temperature))
    throw std::invalid_argument("SphThermalModel::setTemperature: temperature must be finite");
  if (temperatures_.size() < first + count) temperatures_.resize(first + count, config_.initial_temperature);
  std::fill(temperatures_.begin() + first, temperatures_.begin() + first + count, temperature);
}

void SphThermalModel::holdTemperature(const std::vector<size_t>& indices, double temperature) {
  if (!finite(temperature))
    throw std::invalid_argument("SphThermalModel::holdTemperature: temperature must be finite");
  for (size_t i : indices) {
    if (held_.size() <= i) held_.resize(i + 1, 0);
    held_[i] = 1;
    setTemperature(i, 1, temperature);
  }
}

void SphThermalModel::release(const std::vector<size_t>& indices) {
  for (size_t i : indices)
    if (i < held_.size()) held_[i] = 0;
}

void SphThermalModel::addHeatedPlane(const SphHeatedPlane& plane) {
  const double len = plane.normal.norm();
  if (!(len > 0.0) || !plane.normal.allFinite())
    throw std::invalid_argument("SphHeatedPlane.normal: must be finite and non-zero");
  if (!(plane.distance > 0.0) || !finite(plane.distance))
    throw std::invalid_argument("SphHeatedPlane.distance: must be finite and > 0, got " +
                                std::to_string(plane.distance));
  if (!(plane.transfer_rate >= 0.0) || !finite(plane.transfer_rate))
    throw std::invalid_argument("SphHeatedPlane.transfer_rate: must be finite and >= 0");
  if (!finite(plane.offset) || !finite(plane.temperature) || !finite(plane.heat_flux))
    throw std::invalid_argument("SphHeatedPlane: offset, temperature and heat_flux must be finite");
  SphHeatedPlane p = plane;
  p.normal /= len;
  p.offset /= len;
  planes_.push_back(p);
}

void SphThermalModel::setFreezingSolid(std::shared_ptr<SphElasticSolid> solid) {
  if (solid && solid->phase() != config_.freezing_phase)
    throw std::invalid_argument("SphThermalModel::setFreezingSolid: the solid's phase " +
                                std::to_string(solid->phase()) + " differs from freezing_phase " +
                                std::to_string(config_.freezing_phase));
  freezing_solid_ = std::move(solid);
}

double SphThermalModel::meltingRate(double temperature) const {
  return std::max(0.0, config_.melting_rate * (temperature - config_.melting_temperature));  // (8.35)
}

double SphThermalModel::freezingRate(double temperature, double solid_neighbors, double c_v,
                                     double c_f) const {
  // (8.36). Each factor is clamped at 0 separately: as printed, a hot particle (T > T_f) with fewer than
  // n_min solid neighbours would get a positive rate from the product of two negative factors.
  return config_.freezing_rate * std::max(0.0, config_.freezing_temperature - temperature) *
         std::max(0.0, solid_neighbors - config_.min_solid_neighbors) * std::min(1.0, c_v) *
         std::min(1.0, c_f);
}

double SphThermalModel::uniformRandom(uint64_t seed, uint64_t step, uint64_t particle) {
  uint64_t x = splitMix64(seed);
  x = splitMix64(x ^ step);
  x = splitMix64(x ^ (particle * 0xD6E8FEB86659FD93ULL));
  return double(x >> 11) * 0x1.0p-53;
}

double SphThermalModel::totalHeat(const SphParticles& particles) const {
  double heat = 0.0;
  for (size_t i = 0; i < particles.size() && i < temperatures_.size(); ++i)
    if (particles.kinds[i] == SphParticleKind::kFluid && !isHeld(i))
      heat += particles.masses[i] * config_.heat_capacity * temperatures_[i];
  return heat;
}

const SphThermalStats& SphThermalModel::step(SphFluidSolver& solver, double dt) {
  const SphFluidSolver* rows = solver.neighborsCurrent() ? &solver : nullptr;
  // A phase change (8.35, 8.36) moves no particle: the next step's first half-kick uses the forces of this
  // step's end, and its force evaluation sees the new phases (no extra evaluation, as for any force that
  // changes between steps).
  advance(solver.particles(), solver.kernels(), dt, rows);
  return stats_;
}

bool SphThermalModel::step(SphParticles& particles, const SphKernels& kernels, double dt) {
  return advance(particles, kernels, dt, nullptr);
}

bool SphThermalModel::advance(SphParticles& particles, const SphKernels& kernels, double dt,
                              const SphFluidSolver* solver) {
  if (!(dt >= 0.0) || !finite(dt))
    throw std::invalid_argument("SphThermalModel::step: dt must be finite and >= 0, got " +
                                std::to_string(dt));
  const size_t n = particles.size();
  if (temperatures_.size() < n) temperatures_.resize(n, config_.initial_temperature);
  if (held_.size() < n) held_.resize(n, 0);
  ++step_count_;
  stats_ = SphThermalStats();
  stats_.step = step_count_;
  stats_.dt = dt;
  if (solver)
    buildNeighborsFrom(*solver);
  else
    buildNeighbors(particles, kernels);
  diffuse(particles, dt);
  const bool changed = transitions(particles, kernels, dt);
  stats_.total_heat = totalHeat(particles);
  return changed;
}

void SphThermalModel::setMember(size_t s, uint32_t i, const SphParticles& particles) {
  s_index_[s] = i;
  points_[s] = particles.positions[i];
  const double rho = config_.use_particle_densities && particles.densities[i] > 0.0 ? particles.densities[i]
                                                                                    : config_.rest_density;
  s_mc_[s] = particles.masses[i] * config_.heat_capacity;
  s_vol_[s] = particles.masses[i] / rho;
}

void SphThermalModel::buildNeighbors(const SphParticles& particles, const SphKernels& kernels) {
  const size_t n = particles.size();
  members_.clear();
  points_.clear();
  for (size_t i = 0; i < n; ++i)
    if (particles.kinds[i] == SphParticleKind::kFluid || held_[i]) {
      members_.push_back(static_cast<uint32_t>(i));
      points_.push_back(particles.positions[i]);
    }
  const size_t m = members_.size();
  stats_.participants = m;
  // Threads only for large sets (parallel regions cost more than they save on small ones).
  const int threads = static_cast<int>(std::max<size_t>(1, std::min<size_t>(num_threads_, m / 2048)));
  grid_.build(points_, kernels.h, threads);
  s_index_.resize(m);
  s_mc_.resize(m);
  s_vol_.resize(m);
  for (size_t s = 0; s < m; ++s) {
    setMember(s, members_[grid_.order()[s]], particles);  // now in sorted order
  }
  row_start_.resize(m + 1);
  row_start_[0] = 0;
  const double h2 = kernels.h2;
#pragma omp parallel for num_threads(threads) schedule(static)
  for (long s = 0; s < static_cast<long>(m); ++s) {
    SphSortedGrid::Run runs[9];
    const int num_runs = grid_.neighborRuns(grid_.cellOfSorted(s), runs);
    size_t count = 0;
    for (int r = 0; r < num_runs; ++r)
      for (uint32_t j = runs[r].begin; j < runs[r].end; ++j)
        count += (j != uint32_t(s) && (points_[j] - points_[s]).squaredNorm() < h2);
    row_start_[s + 1] = count;
  }
  for (size_t s = 0; s < m; ++s) row_start_[s + 1] += row_start_[s];
  nbr_.resize(row_start_[m]);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (long s = 0; s < static_cast<long>(m); ++s) {
    SphSortedGrid::Run runs[9];
    const int num_runs = grid_.neighborRuns(grid_.cellOfSorted(s), runs);
    size_t k = row_start_[s];
    for (int r = 0; r < num_runs; ++r)
      for (uint32_t j = runs[r].begin; j < runs[r].end; ++j)
        if (j != uint32_t(s) && (points_[j] - points_[s]).squaredNorm() < h2) nbr_[k++] = j;
  }
  fillCoefficients(kernels, threads);
}

void SphThermalModel::buildNeighborsFrom(const SphFluidSolver& solver) {
  const SphParticles& particles = solver.particles();
  const std::vector<uint32_t>& order = solver.neighborGrid().order();
  const size_t n = order.size();
  // Participants in the solver's cell order (a subsequence of it).
  thermal_of_.resize(n);
  solver_pos_.clear();
  for (size_t t = 0; t < n; ++t) {
    const uint32_t i = order[t];
    const bool member = particles.kinds[i] == SphParticleKind::kFluid || held_[i];
    thermal_of_[t] = member ? static_cast<int32_t>(solver_pos_.size()) : -1;
    if (member) solver_pos_.push_back(static_cast<uint32_t>(t));
  }
  const size_t m = solver_pos_.size();
  stats_.participants = m;
  const int threads = static_cast<int>(std::max<size_t>(1, std::min<size_t>(num_threads_, m / 2048)));
  s_index_.resize(m);
  points_.resize(m);
  s_mc_.resize(m);
  s_vol_.resize(m);
  for (size_t s = 0; s < m; ++s) {
    setMember(s, order[solver_pos_[s]], particles);
  }
  row_start_.resize(m + 1);
  row_start_[0] = 0;
  for (size_t s = 0; s < m; ++s) {
    uint32_t count = 0;
    const uint32_t* row = solver.neighborRow(solver_pos_[s], count);
    size_t members = 0;
    for (uint32_t e = 0; e < count; ++e) members += thermal_of_[row[e]] >= 0;
    row_start_[s + 1] = row_start_[s] + members;
  }
  nbr_.resize(row_start_[m]);
  for (size_t s = 0; s < m; ++s) {
    uint32_t count = 0;
    const uint32_t* row = solver.neighborRow(solver_pos_[s], count);
    size_t k = row_start_[s];
    for (uint32_t e = 0; e < count; ++e) {
      const int32_t j = thermal_of_[row[e]];
      if (j >= 0) nbr_[k++] = static_cast<uint32_t>(j);
    }
  }
  fillCoefficients(solver.kernels(), threads);
}

void SphThermalModel::fillCoefficients(const SphKernels& kernels, int threads) {
  const size_t m = s_index_.size();
  coeff_.resize(row_start_[m]);
  stats_.pairs = row_start_[m];
  // g_ij = 2 k V_i V_j (-w'(r) / r), poly6: -w'(r) / r = 6 a / h^2 (1 - r^2/h^2)^2. The expression is
  // symmetric in i and j bit for bit, so the pair fluxes cancel exactly.
  const double h2 = kernels.h2;
  const double scale = 2.0 * config_.conductivity * 6.0 * kernels.poly6_coeff / h2;
#pragma omp parallel for num_threads(threads) schedule(static)
  for (long s = 0; s < static_cast<long>(m); ++s) {
    const Vec3 xs = points_[s];
    const double vs = s_vol_[s];
    for (size_t k = row_start_[s]; k < row_start_[s + 1]; ++k) {
      const uint32_t j = nbr_[k];
      const double d2 = (points_[j] - xs).squaredNorm();
      const double t = 1.0 - d2 / h2;
      coeff_[k] = scale * (vs * s_vol_[j]) * (t * t);
    }
  }
}

void SphThermalModel::diffuse(const SphParticles& particles, double dt) {
  const size_t m = s_index_.size();
  s_temp_.resize(m);
  s_next_.resize(m);
  for (size_t s = 0; s < m; ++s) s_temp_[s] = temperatures_[s_index_[s]];
  // Monotone limit: T_i' = (1 - dt D_i) T_i + dt sum_j g_ij T_j / (m_i c) is a convex combination for
  // dt D_i <= 1 (this also bounds the largest eigenvalue, 2 max D_i, inside the Euler stability region).
  double max_d = 0.0;
  for (size_t s = 0; s < m; ++s) {
    if (held_[s_index_[s]]) continue;
    double sum = 0.0;
    for (size_t k = row_start_[s]; k < row_start_[s + 1]; ++k) sum += coeff_[k];
    max_d = std::max(max_d, sum / s_mc_[s]);
  }
  stats_.stable_dt = max_d > 0.0 ? 1.0 / max_d : std::numeric_limits<double>::infinity();
  const double limit = config_.stability_factor * stats_.stable_dt;
  const double want = dt > 0.0 && std::isfinite(limit) ? std::ceil(dt / limit) : 1.0;
  if (want > config_.max_substeps)
    throw std::runtime_error("SphThermalModel::step: dt " + std::to_string(dt) + " needs " +
                             std::to_string(want) + " diffusion substeps (stable dt " +
                             std::to_string(stats_.stable_dt) + "), more than max_substeps " +
                             std::to_string(config_.max_substeps));
  const int substeps = static_cast<int>(std::max(1.0, want));
  stats_.substeps = substeps;
  const double h = dt / substeps;
  const double c = config_.heat_capacity;
  const double ambient_keep = std::exp(-config_.ambient_rate * h);
  const int threads = static_cast<int>(std::max<size_t>(1, std::min<size_t>(num_threads_, m / 2048)));
  for (int sub = 0; sub < substeps; ++sub) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long s = 0; s < static_cast<long>(m); ++s) {
      const uint32_t i = s_index_[s];
      const double ti = s_temp_[s];
      if (held_[i]) {
        s_next_[s] = ti;
        continue;
      }
      double flow = 0.0;
      for (size_t k = row_start_[s]; k < row_start_[s + 1]; ++k) flow += coeff_[k] * (s_temp_[nbr_[k]] - ti);
      double t = ti + h * flow / s_mc_[s];
      for (const SphHeatedPlane& p : planes_) {
        if (p.normal.dot(points_[s]) - p.offset > p.distance) continue;
        t = p.temperature + (t - p.temperature) * std::exp(-p.transfer_rate * h);
        t += h * p.heat_flux / c;
      }
      if (config_.ambient_rate > 0.0)
        t = config_.ambient_temperature + (t - config_.ambient_temperature) * ambient_keep;
      s_next_[s] = t;
    }
    s_temp_.swap(s_next_);
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (size_t s = 0; s < m; ++s) {
    const uint32_t i = s_index_[s];
    temperatures_[i] = s_temp_[s];
    if (held_[i]) continue;
    lo = std::min(lo, s_temp_[s]);
    hi = std::max(hi, s_temp_[s]);
  }
  stats_.min_temperature = lo;
  stats_.max_temperature = hi;
  (void)particles;
}

bool SphThermalModel::transitions(SphParticles& particles, const SphKernels& kernels, double dt) {
  if ((!config_.melting && !config_.freezing) || dt <= 0.0) return false;
  const size_t m = s_index_.size();
  const uint8_t target = config_.freezing_phase;
  const SphElasticSolid* solid = freezing_solid_.get();
  const bool use_force = solid && std::isfinite(config_.max_lattice_force);
  const std::vector<Eigen::Matrix3d>* transforms = solid ? &solid->latticeTransforms() : nullptr;
  const bool have_transforms = transforms && transforms->size() == particles.size();
  new_phase_.resize(m);
  const int threads = static_cast<int>(std::max<size_t>(1, std::min<size_t>(num_threads_, m / 2048)));
#pragma omp parallel for num_threads(threads) schedule(static)
  for (long s = 0; s < static_cast<long>(m); ++s) {
    const uint32_t i = s_index_[s];
    const uint8_t phase = particles.phases[i];
    new_phase_[s] = phase;
    if (held_[i] || particles.kinds[i] != SphParticleKind::kFluid) continue;
    const double temperature = temperatures_[i];
    double rate = 0.0;
    uint8_t next = phase;
    if (phase != 0) {
      if (!config_.melting || (config_.melting_phase != 0 && phase != config_.melting_phase)) continue;
      rate = meltingRate(temperature);
      next = 0;
    } else {
      if (!config_.freezing || temperature >= config_.freezing_temperature) continue;
      // Solid neighbours, their mean velocity (c_v) and the hypothetical lattice force (c_F) of (8.36).
      size_t solid_neighbors = 0;
      Vec3 mean_velocity = Vec3::Zero(), lattice_force = Vec3::Zero();
      const Vec3& xi = particles.positions[i];
      for (size_t k = row_start_[s]; k < row_start_[s + 1]; ++k) {
        const uint32_t j = s_index_[nbr_[k]];
        if (particles.phases[j] != target) continue;
        ++solid_neighbors;
        mean_velocity += particles.velocities[j];
        if (!use_force || !have_transforms || particles.kinds[j] != SphParticleKind::kFluid) continue;
        // Goal position of i in j's lattice (8.29, without the deformation allowance) and the force
        // towards it in the form of (8.31).
        const Eigen::Matrix3d& a = (*transforms)[j];
        const Vec3 r = xi - particles.positions[j];
        const Vec3 goal = a * solid->lattice().point(solid->lattice().nearestIndex(a.inverse() * r));
        lattice_force += kernels.poly6(r.squaredNorm()) * (goal - r);
      }
      const double inf = std::numeric_limits<double>::infinity();
      double c_v = inf, c_f = inf;
      if (solid_neighbors > 0 && std::isfinite(config_.max_relative_speed)) {
        const double rel = (particles.velocities[i] - mean_velocity / double(solid_neighbors)).norm();
        if (rel > 0.0) c_v = config_.max_relative_speed / rel;
      }
      if (use_force) {
        const double f = solid->config().goal_stiffness * particles.masses[i] * solid->particleVolume() *
                         lattice_force.norm();
        if (f > 0.0) c_f = config_.max_lattice_force / f;
      }
      rate = freezingRate(temperature, double(solid_neighbors), c_v, c_f);
      next = target;
    }
    if (rate <= 0.0) continue;
    if (uniformRandom(config_.seed, step_count_, i) < -std::expm1(-rate * dt))
      new_phase_[s] = next;  // (8.34)
  }
  bool changed = false;
  for (size_t s = 0; s < m; ++s) {
    const uint32_t i = s_index_[s];
    if (new_phase_[s] == particles.phases[i]) continue;
    changed = true;
    if (new_phase_[s] == 0) {
      ++stats_.melted;
      continue;
    }
    ++stats_.frozen;
    // Join the lattice: adopt the transform of the nearest solid neighbour that has one (phases before
    // this step's changes).
    if (!have_transforms) continue;
    double best = std::numeric_limits<double>::infinity();
    uint32_t best_j = 0;
    for (size_t k = row_start_[s]; k < row_start_[s + 1]; ++k) {
      const uint32_t j = s_index_[nbr_[k]];
      if (particles.phases[j] != target || particles.kinds[j] != SphParticleKind::kFluid) continue;
      const double d2 = (particles.positions[j] - particles.positions[i]).squaredNorm();
      if (d2 < best) best = d2, best_j = j;
    }
    if (std::isfinite(best)) freezing_solid_->setLatticeTransform(i, (*transforms)[best_j]);
  }
  if (!changed) return false;
  for (size_t s = 0; s < m; ++s) particles.phases[s_index_[s]] = new_phase_[s];
  return true;
}

}  // namespace rc
