#include "relaxed_connectivity/sph/sph_object_penalty.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_lattice.h"

namespace rc {

namespace {

void require(bool ok, const char* field, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string("SphObjectPenaltyConfig.") + field + ": " + what);
}

bool isObjectParticle(const SphParticles& p, size_t i) {
  return p.phases[i] != 0 && p.kinds[i] == SphParticleKind::kFluid;
}

}  // namespace

void SphObjectPenaltyConfig::validate() const {
  require(stiffness > 0.0 && std::isfinite(stiffness), "stiffness",
          "(K_c) must be finite and > 0, got " + std::to_string(stiffness));
  require(contact_distance > 0.0 && std::isfinite(contact_distance), "contact_distance",
          "must be finite and > 0, got " + std::to_string(contact_distance));
  require(damping >= 0.0 && std::isfinite(damping), "damping",
          "must be finite and >= 0, got " + std::to_string(damping));
}

SphObjectPenalty::SphObjectPenalty(const SphObjectPenaltyConfig& config, const SphKernels& kernels)
    : config_(config), kernels_(kernels) {
  config_.validate();
  const double d = config_.contact_distance;
  if (d > kernels.h)
    throw std::invalid_argument("SphObjectPenalty: contact_distance " + std::to_string(d) +
                                " exceeds the kernel support h = " + std::to_string(kernels.h));
  volume_ = SphLattice(kernels.dimension, d).cellVolume();
  // kappa = max_{r < d} W(r) + |W'(r)| (d - r): the pair stiffness -d/dr of W(r) (d - r), sampled finely.
  const int samples = 1024;
  for (int k = 0; k <= samples; ++k) {
    const double r = d * k / samples;
    pair_stiffness_bound_ = std::max(pair_stiffness_bound_,
                                     kernels_.poly6(r * r) + std::abs(kernels_.poly6Derivative(r)) * (d - r));
  }
  pair_stiffness_bound_ *= 1.01;  // between the samples
}

double SphObjectPenalty::pairPotential(double distance) const {
  const double d = config_.contact_distance;
  if (!(distance < d)) return 0.0;
  const double r = std::max(distance, 0.0);
  // int_r^d W(s) (d - s) ds: the integrand is a polynomial of degree 7 in s, integrated exactly by
  // 4-point Gauss-Legendre.
  static const double nodes[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                  0.8611363115940526};
  static const double weights[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                    0.3478548451374538};
  const double half = 0.5 * (d - r), mid = 0.5 * (d + r);
  double sum = 0.0;
  for (int k = 0; k < 4; ++k) {
    const double s = mid + half * nodes[k];
    sum += weights[k] * kernels_.poly6(s * s) * (d - s);
  }
  return volume_ * config_.stiffness * half * sum;
}

size_t SphObjectPenalty::countObjects(const SphParticles& particles) {
  bool seen[256] = {false};
  size_t count = 0;
  for (size_t i = 0; i < particles.size(); ++i)
    if (isObjectParticle(particles, i) && !seen[particles.phases[i]]) {
      seen[particles.phases[i]] = true;
      ++count;
    }
  return count;
}

void SphObjectPenalty::beginStep(double dt) {
  if (!(dt >= 0.0) || !std::isfinite(dt))
    throw std::invalid_argument("SphObjectPenalty::beginStep: dt must be finite and >= 0, got " +
                                std::to_string(dt));
  step_dt_ = dt;
}

void SphObjectPenalty::setObjectStiffness(uint8_t phase, double stiffness) {
  if (!(stiffness >= 0.0) || !std::isfinite(stiffness))
    throw std::invalid_argument(
        "SphObjectPenalty::setObjectStiffness: stiffness must be finite and >= 0, got " +
        std::to_string(stiffness));
  object_stiffness_[phase] = stiffness;
}

void SphObjectPenalty::coupleGlobalImplicit(SphElasticSolid& solid) {
  if (!config_.implicit)
    throw std::invalid_argument(
        "SphObjectPenalty::coupleGlobalImplicit: needs implicit contact springs (config.implicit)");
  const SphElasticConfig& e = solid.config();
  if (e.model != SphElasticModel::kGoalPosition || !e.implicit_goal || !e.global_implicit_goal)
    throw std::invalid_argument(
        "SphObjectPenalty::coupleGlobalImplicit: solid of phase " + std::to_string(int(solid.phase())) +
        " has no global implicit goal springs (goal_position, implicit_goal: global)");
  if (!coupling_) coupling_ = std::make_shared<SphImplicitGoalCoupling>();
  if (solid.implicitCoupling() == coupling_) return;
  solid.setImplicitCoupling(coupling_);
  ++coupled_solids_;
}

void SphObjectPenalty::gatherStiffness(size_t s) {
  const double d2 = config_.contact_distance * config_.contact_distance;
  const Vec3 xs = s_pos_[s];
  const uint8_t phase = s_phase_[s];
  double k = 0.0;
  SphSortedGrid::Run runs[9];
  const int num_runs = grid_.neighborRuns(grid_.cellOfSorted(s), runs);
  for (int q = 0; q < num_runs; ++q)
    for (uint32_t j = runs[q].begin; j < runs[q].end; ++j) {
      if (s_phase_[j] == phase) continue;
      const double r2 = (s_pos_[j] - xs).squaredNorm();
      if (!(r2 < d2) || r2 <= 0.0) continue;
      k += 0.5 * (s_mass_[s] + s_mass_[j]) * kernels_.poly6(r2);
    }
  s_stiffness_[s] = k * volume_ * config_.stiffness / s_mass_[s] + object_stiffness_[phase];
}

void SphObjectPenalty::gatherForces(size_t s) {
  const double d = config_.contact_distance, d2 = d * d;
  const double k_c = config_.stiffness, c = config_.damping;
  const Vec3 xs = s_pos_[s], vs = s_vel_[s];
  const uint8_t phase = s_phase_[s];
  const double dt = step_dt_;
  const bool implicit = config_.implicit && dt > 0.0;
  const bool coupled = !s_coupled_.empty() && s_coupled_[s];
  if (coupled) s_springs_[s].clear();
  Vec3 force = Vec3::Zero();
  double energy = 0.0, min_dist = d;
  uint32_t contacts = 0, repulsive = 0;
  SphSortedGrid::Run runs[9];
  const int num_runs = grid_.neighborRuns(grid_.cellOfSorted(s), runs);
  for (int q = 0; q < num_runs; ++q)
    for (uint32_t j = runs[q].begin; j < runs[q].end; ++j) {
      if (s_phase_[j] == phase) continue;
      // Pair (s, j): F_sj is the force on j; s receives -F'_sj. The expression is antisymmetric bit for
      // bit (x_j - x_s = -(x_s - x_j) exactly), so the pair's two evaluations cancel exactly.
      const Vec3 rsj = s_pos_[j] - xs;
      const double r2 = rsj.squaredNorm();
      if (!(r2 < d2) || r2 <= 0.0) continue;  // coincident particles: no direction
      const double r = std::sqrt(r2);
      const Vec3 n = rsj / r;
      const double mean_mass = 0.5 * (s_mass_[s] + s_mass_[j]);
      const double scale = mean_mass * volume_ * kernels_.poly6(r2);
      const bool joint = coupled && s_coupled_[j];  // into the solids' implicit solve, once per pair
      if (joint && j > s) {
        SphContactSpring spring;
        spring.first = members_[s];
        spring.second = members_[j];
        spring.normal = n;
        spring.force = scale * k_c * (d - r);
        // -dN/dr of m V K_c W(r) (d - r); W' <= 0.
        spring.stiffness =
            mean_mass * volume_ * k_c * (kernels_.poly6(r2) - kernels_.poly6Derivative(r) * (d - r));
        spring.damping = scale * c;
        s_springs_[s].push_back(spring);
      }
      ++contacts;
      min_dist = std::min(min_dist, r);
      energy += 0.5 * mean_mass * pairPotential(r);  // each pair is visited from both ends
      if (joint) continue;
      // n . F_sj with F_sj = scale (K_c (d - r) n - c (v_j - v_s)); (8.37) keeps it along n if positive.
      const double approach = n.dot(s_vel_[j] - vs);
      double spring = k_c * (d - r);
      if (implicit) {  // locally implicit: backward Euler on the pair, direction held fixed
        const double k = std::max(s_stiffness_[s], s_stiffness_[j]);
        spring = k_c * ((d - r) - dt * approach) / (1.0 + dt * dt * k);
      }
      const double normal = scale * (spring - c * approach);
      if (normal > 0.0) {
        ++repulsive;
        force -= normal * n;
      }
    }
  s_force_[s] = force;
  s_energy_[s] = energy;
  s_min_dist_[s] = min_dist;
  s_contacts_[s] = contacts;
  s_repulsive_[s] = repulsive;
}

void SphObjectPenalty::computeForces(const SphParticles& particles, std::vector<Vec3>& forces) {
  forces.assign(particles.size(), Vec3::Zero());
  addForces(particles, particles.velocities, forces);
}

void SphObjectPenalty::addForces(const SphParticles& particles, const std::vector<Vec3>& velocities,
                                 std::vector<Vec3>& forces) {
  const size_t n = particles.size();
  if (forces.size() != n || velocities.size() != n)
    throw std::invalid_argument(
        "SphObjectPenalty::addForces: forces and velocities must have one entry per "
        "particle");
  if (particles.phases.size() != n || particles.kinds.size() != n || particles.masses.size() != n)
    throw std::invalid_argument("SphObjectPenalty::addForces: particle arrays differ in size");
  SphObjectPenaltyStats st;
  st.min_distance = config_.contact_distance;
  st.objects = countObjects(particles);
  // Coupled solids hand over their systems at every evaluation with a step (they evaluate before this term).
  const bool coupled = coupled_solids_ > 0 && coupling_->pendingBlocks() > 0;
  coupling_stats_ = SphImplicitCouplingStats{};
  if (coupled_solids_ > 0) {
    const size_t expected = config_.implicit && step_dt_ > 0.0 ? coupled_solids_ : 0;
    if (coupling_->pendingBlocks() != expected)
      throw std::logic_error(
          "SphObjectPenalty::addForces: " + std::to_string(coupling_->pendingBlocks()) + " of the " +
          std::to_string(expected) +
          " coupled solids handed over their implicit systems; add this term to the solver "
          "after the solids it couples (coupleGlobalImplicit) and announce the same step");
  }
  if (st.objects < 2) {  // off: nothing to collide
    if (coupled) coupling_stats_ = coupling_->solve({}, forces);
    stats_ = st;
    return;
  }
  std::vector<Vec3> points;
  std::vector<uint32_t> members;
  for (size_t i = 0; i < n; ++i)
    if (isObjectParticle(particles, i)) {
      members.push_back(static_cast<uint32_t>(i));
      points.push_back(particles.positions[i]);
    }
  grid_.build(points, config_.contact_distance, 1, "SphObjectPenalty::addForces");
  const size_t m = members.size();
  members_.resize(m);
  s_pos_.resize(m);
  s_vel_.resize(m);
  s_mass_.resize(m);
  s_phase_.resize(m);
  for (size_t s = 0; s < m; ++s) {
    const uint32_t i = members[grid_.order()[s]];
    members_[s] = i;
    s_pos_[s] = particles.positions[i];
    s_vel_[s] = velocities[i];
    s_mass_[s] = particles.masses[i];
    s_phase_[s] = particles.phases[i];
  }
  s_force_.resize(m);
  s_energy_.resize(m);
  s_min_dist_.resize(m);
  s_contacts_.resize(m);
  s_repulsive_.resize(m);
  const long count = static_cast<long>(m);
  const int threads = static_cast<int>(std::max<long>(1, std::min<long>(threadLimit(), count / 512)));
  const bool implicit = config_.implicit && step_dt_ > 0.0;
  if (implicit) s_stiffness_.resize(m);
  s_coupled_.clear();
  if (coupled) {
    s_coupled_.resize(m);
    s_springs_.resize(m);
    for (size_t s = 0; s < m; ++s) s_coupled_[s] = coupling_->blockOf(members_[s]) >= 0;
  }
#pragma omp parallel num_threads(threads)
  {
    if (implicit) {
#pragma omp for schedule(static)
      for (long s = 0; s < count; ++s) gatherStiffness(static_cast<size_t>(s));
    }
#pragma omp for schedule(static)
    for (long s = 0; s < count; ++s) gatherForces(static_cast<size_t>(s));
  }
  // Serial reduction in sorted order: independent of the thread count.
  for (size_t s = 0; s < m; ++s) {
    forces[members_[s]] += s_force_[s];
    st.net_force += s_force_[s];
    st.energy += s_energy_[s];
    st.min_distance = std::min(st.min_distance, s_min_dist_[s]);
    st.contact_pairs += s_contacts_[s];
    st.repulsive_pairs += s_repulsive_[s];
  }
  st.contact_pairs /= 2;
  st.repulsive_pairs /= 2;
  if (coupled) {  // the contact springs between coupled solids, in sorted order
    springs_.clear();
    for (size_t s = 0; s < m; ++s)
      if (s_coupled_[s]) springs_.insert(springs_.end(), s_springs_[s].begin(), s_springs_[s].end());
    coupling_stats_ = coupling_->solve(springs_, forces);
    st.repulsive_pairs += coupling_stats_.active_contacts;
  }
  stats_ = st;
}

double SphObjectPenalty::stableTimeStep(const SphParticles& particles, double cfl) const {
  if (countObjects(particles) < 2) return std::numeric_limits<double>::infinity();
  double min_mass = std::numeric_limits<double>::infinity(), max_mass = 0.0;
  for (size_t i = 0; i < particles.size(); ++i)
    if (isObjectParticle(particles, i)) {
      min_mass = std::min(min_mass, particles.masses[i]);
      max_mass = std::max(max_mass, particles.masses[i]);
    }
  const double q = 0.5 * (1.0 + max_mass / min_mass);
  const double z = kernels_.dimension == 3 ? 12.0 : 6.0;  // kissing number: contacts per particle
  const double damping_omega = 2.0 * z * config_.damping * volume_ * kernels_.poly6(0.0) * q;
  if (config_.implicit) {
    // Contact CFL: two particles approaching at the largest speed each close at most cfl d per step.
    double max_speed2 = 0.0;
    for (size_t i = 0; i < particles.size(); ++i)
      if (isObjectParticle(particles, i))
        max_speed2 = std::max(max_speed2, particles.velocities[i].squaredNorm());
    const double contact = max_speed2 > 0.0 ? cfl * config_.contact_distance / (2.0 * std::sqrt(max_speed2))
                                            : std::numeric_limits<double>::infinity();
    return damping_omega > 0.0 ? std::min(contact, cfl * 2.0 / damping_omega) : contact;
  }
  const double omega =
      std::sqrt(2.0 * z * config_.stiffness * volume_ * pair_stiffness_bound_ * q) + damping_omega;
  return cfl * 2.0 / omega;
}

}  // namespace rc
