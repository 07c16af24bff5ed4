#include "relaxed_connectivity/sph/gpu/sph_gpu_host_solver.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Small systems run on fewer threads (barriers cost more than the work, see SphFluidSolver).
int hostThreads(size_t n) {
  return int(std::max<size_t>(1, std::min<size_t>(omp_get_max_threads(), n / 2048)));
}

/// Gathers v into the order `order` (v'[s] = v[order[s]]) through the scratch `tmp`.
template <class T>
void gather(std::vector<T>& v, const std::vector<uint32_t>& order, std::vector<T>& tmp) {
  tmp.resize(v.size());
  const long n = long(v.size());
#pragma omp parallel for schedule(static) num_threads(hostThreads(v.size()))
  for (long s = 0; s < n; ++s) tmp[s] = v[order[s]];
  v.swap(tmp);
}

}  // namespace

template <class R>
SphGpuHostSolver<R>::SphGpuHostSolver(const SphGpuSystem<R>& system)
    : params_(system.params), solids_(system.solids), planes_(system.planes), dt_(system.dt) {
  const SphGpuParticleArrays<R>& a = system.particles;
  n_ = a.size();
  if (a.velocity.size() != n_ || a.material.size() != n_ || a.transform.size() != n_)
    throw std::invalid_argument("SphGpuHostSolver: particle arrays differ in size (" + std::to_string(n_) +
                                " positions)");
  if (solids_.size() != size_t(params_.max_phase) + 1 || planes_.size() != size_t(params_.num_planes))
    throw std::invalid_argument("SphGpuHostSolver: solids or planes do not match the parameters");
  if (!(dt_ > R(0))) throw std::invalid_argument("SphGpuHostSolver: dt must be > 0");
  pos_mass_ = a.pos_mass;
  velocity_ = a.velocity;
  material_ = a.material;
  transform_ = a.transform;
  id_.resize(n_);
  for (size_t i = 0; i < n_; ++i) id_[i] = uint32_t(i);
  eval_vel_.resize(n_);
  for (size_t i = 0; i < n_; ++i) {
    eval_vel_[i] = velocity_[i];
    if (sphKind(material_[i]) == kSphGpuStaticBoundary) eval_vel_[i] = {R(0), R(0), R(0), R(0)};
  }
  acceleration_.assign(n_, {R(0), R(0), R(0), R(0)});
  xsph_ = elastic_force_ = acceleration_;
  pressure_.assign(n_, R(0));
  pressure_term_ = strain_ = pressure_;
  neighbor_masks_.assign(n_ * 9, 0);
  neighbor_count_.assign(n_, 0);
  cell_start_.assign(size_t(params_.dims[0]) * params_.dims[1] * params_.dims[2] + 1, 0);
  sortByCell();
  evaluate();
  checkFlags();
}

template <class R>
SphGpuState<R> SphGpuHostSolver<R>::state() {
  SphGpuState<R> st;
  st.n = uint32_t(n_);
  st.pos_mass = pos_mass_.data();
  st.velocity = velocity_.data();
  st.eval_vel = eval_vel_.data();
  st.pressure = pressure_.data();
  st.pressure_term = pressure_term_.data();
  st.material = material_.data();
  st.acceleration = acceleration_.data();
  st.xsph = xsph_.data();
  st.elastic_force = elastic_force_.data();
  st.transform = transform_.data();
  st.strain = strain_.data();
  st.cell_start = cell_start_.data();
  st.neighbor_masks = neighbor_masks_.data();
  st.neighbor_count = neighbor_count_.data();
  st.error_flags = &error_flags_;
  return st;
}

// Stable counting sort of the particles by cell, then every per-particle array follows.
template <class R>
void SphGpuHostSolver<R>::sortByCell() {
  const size_t cells = cell_start_.size() - 1;
  cell_of_.resize(n_);
  for (size_t s = 0; s < n_; ++s) cell_of_[s] = sphCellOf(params_, pos_mass_[s]);
  std::fill(cell_start_.begin(), cell_start_.end(), 0u);
  for (size_t s = 0; s < n_; ++s) ++cell_start_[cell_of_[s] + 1];
  for (size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  order_.resize(n_);
  std::vector<uint32_t> next(cell_start_.begin(), cell_start_.end() - 1);
  for (size_t s = 0; s < n_; ++s) order_[next[cell_of_[s]]++] = uint32_t(s);
  std::vector<SphGpuVec4<R>> tmp4;
  gather(pos_mass_, order_, tmp4);
  gather(velocity_, order_, tmp4);
  gather(eval_vel_, order_, tmp4);
  std::vector<uint32_t> tmpu;
  gather(material_, order_, tmpu);
  gather(id_, order_, tmpu);
  std::vector<SphGpuMat3<R>> tmpm;
  gather(transform_, order_, tmpm);
}

template <class R>
void SphGpuHostSolver<R>::evaluate() {
  const SphGpuState<R> st = state();
  const long n = long(n_);
  const int threads = hostThreads(n_);
  auto t0 = std::chrono::steady_clock::now();
#pragma omp parallel for schedule(static) num_threads(threads)
  for (long s = 0; s < n; ++s) sphDensity(params_, st, uint32_t(s));
  times_.density += secondsSince(t0);
  t0 = std::chrono::steady_clock::now();
  uint64_t entries = 0;
#pragma omp parallel for schedule(static) num_threads(threads) reduction(+ : entries)
  for (long s = 0; s < n; ++s) entries += sphForce(params_, st, uint32_t(s));
  size_t fluid = 0;
  for (uint32_t m : material_) fluid += sphKind(m) == kSphGpuFluid;
  neighbors_per_particle_ = fluid ? double(entries) / double(fluid) : 0.0;
  times_.force += secondsSince(t0);
  t0 = std::chrono::steady_clock::now();
  if (params_.max_phase > 0) {
#pragma omp parallel for schedule(static) num_threads(threads)
    for (long s = 0; s < n; ++s) elastic_force_[s] = {R(0), R(0), R(0), R(0)};
    SphGpuVec4<R>* force = elastic_force_.data();
    const auto add_force = [force](uint32_t j, const SphGpuVec3<R>& f) {
      SphGpuVec4<R>& t = force[j];
#pragma omp atomic
      t.x += f.x;
#pragma omp atomic
      t.y += f.y;
#pragma omp atomic
      t.z += f.z;
    };
#pragma omp parallel for schedule(dynamic, 256) num_threads(threads)
    for (long s = 0; s < n; ++s) sphElasticNeighborhood(params_, solids_.data(), st, uint32_t(s), add_force);
#pragma omp parallel for schedule(static) num_threads(threads)
    for (long s = 0; s < n; ++s) sphAddElasticAcceleration(st, uint32_t(s));
  }
  times_.elastic += secondsSince(t0);
}

template <class R>
void SphGpuHostSolver<R>::checkFlags() const {
  if (error_flags_ & kSphGpuNeighborOverflow)
    throw std::runtime_error("SphGpuHostSolver: a solid particle has more than " +
                             std::to_string(kSphGpuMaxSolidNeighbors) +
                             " neighbours of its solid (smoothing length too large for the lattice spacing)");
  if (error_flags_ & kSphGpuNonFinite)
    throw std::runtime_error("SphGpuHostSolver: non-finite positions or velocities after step " +
                             std::to_string(steps_) + " (time step too large?)");
}

template <class R>
void SphGpuHostSolver<R>::step(int steps) {
  for (int k = 0; k < steps; ++k) {
    const SphGpuState<R> st = state();
    const long n = long(n_);
    const int threads = hostThreads(n_);
    auto t0 = std::chrono::steady_clock::now();
#pragma omp parallel for schedule(static) num_threads(threads)
    for (long s = 0; s < n; ++s) sphKickDrift(params_, planes_.data(), st, uint32_t(s), dt_);
    times_.integrate += secondsSince(t0);
    t0 = std::chrono::steady_clock::now();
    sortByCell();
    times_.sort += secondsSince(t0);
    evaluate();
    const SphGpuState<R> sorted = state();
    t0 = std::chrono::steady_clock::now();
#pragma omp parallel for schedule(static) num_threads(threads)
    for (long s = 0; s < n; ++s) sphFinalKick(sorted, uint32_t(s), dt_);
    times_.integrate += secondsSince(t0);
    ++steps_;
    ++times_.steps;
    checkFlags();
  }
}

template <class R>
void SphGpuHostSolver<R>::download(SphGpuParticleArrays<R>& out) const {
  out.assignFromSorted(n_, id_.data(), pos_mass_.data(), velocity_.data(), material_.data(),
                       transform_.data(), eval_vel_.data(), pressure_.data(), acceleration_.data(),
                       strain_.data());
}

template class SphGpuHostSolver<float>;
template class SphGpuHostSolver<double>;

}  // namespace rc
