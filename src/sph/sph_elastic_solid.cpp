#include "relaxed_connectivity/sph/sph_elastic_solid.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include "relaxed_connectivity/sph/polar_decomposition.h"
#include "relaxed_connectivity/sph/sph_lattice_keys.h"

namespace rc {

namespace {

using Mat3 = Eigen::Matrix3d;

void require(bool ok, const char* field, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string("SphElasticConfig.") + field + ": " + what);
}

bool isRotation(const Mat3& q) {
  return q.allFinite() && (q.transpose() * q - Mat3::Identity()).norm() < 1e-9 && q.determinant() > 0.0;
}

// Scalar forms of the per-neighbour accumulations (always inlined, unlike Eigen's expression loops in the
// large neighbourhood function).
[[gnu::always_inline]] inline void addScaled(Vec3& a, double w, const Vec3& b) {
  a.x() += w * b.x();
  a.y() += w * b.y();
  a.z() += w * b.z();
}
/// m += w a b^T.
[[gnu::always_inline]] inline void addOuter(Mat3& m, double w, const Vec3& a, const Vec3& b) {
  const double wx = w * a.x(), wy = w * a.y(), wz = w * a.z();
  m(0, 0) += wx * b.x(), m(0, 1) += wx * b.y(), m(0, 2) += wx * b.z();
  m(1, 0) += wy * b.x(), m(1, 1) += wy * b.y(), m(1, 2) += wy * b.z();
  m(2, 0) += wz * b.x(), m(2, 1) += wz * b.y(), m(2, 2) += wz * b.z();
}
/// a x b, the formula of Eigen's cross (always inlined).
[[gnu::always_inline]] inline Vec3 crossOf(const Vec3& a, const Vec3& b) {
  return Vec3(a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(), a.x() * b.y() - a.y() * b.x());
}
/// m += w (|p|^2 I - p p^T), the inertia of a point of weight w at p.
[[gnu::always_inline]] inline void addInertia(Mat3& m, double w, const Vec3& p) {
  const double xx = p.x() * p.x(), yy = p.y() * p.y(), zz = p.z() * p.z();
  m(0, 0) += w * (yy + zz), m(1, 1) += w * (xx + zz), m(2, 2) += w * (xx + yy);
  const double xy = -w * p.x() * p.y(), xz = -w * p.x() * p.z(), yz = -w * p.y() * p.z();
  m(0, 1) += xy, m(1, 0) += xy, m(0, 2) += xz, m(2, 0) += xz, m(1, 2) += yz, m(2, 1) += yz;
}

/// w (|c|^2 I - c c^T), the value of this Eigen expression formed element by element (Eigen's temporaries
/// here stall on store forwarding).
[[gnu::always_inline]] inline Mat3 pointInertia(double w, const Vec3& c) {
  const double norm2 = c.squaredNorm(), off = norm2 * 0.0;
  Mat3 inertia;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) inertia(r, k) = w * ((r == k ? norm2 * 1.0 : off) - c[r] * c[k]);
  return inertia;
}

}  // namespace

void SphElasticConfig::validate() const {
  require(lattice_spacing > 0.0 && std::isfinite(lattice_spacing), "lattice_spacing",
          "must be finite and > 0, got " + std::to_string(lattice_spacing));
  require(youngs_modulus > 0.0 && std::isfinite(youngs_modulus), "youngs_modulus",
          "must be finite and > 0, got " + std::to_string(youngs_modulus));
  require(poisson_ratio >= 0.0 && poisson_ratio < 0.5, "poisson_ratio",
          "must be in [0, 0.5), got " + std::to_string(poisson_ratio));
  require(hourglass_control >= 0.0 && std::isfinite(hourglass_control), "hourglass_control",
          "must be finite and >= 0, got " + std::to_string(hourglass_control));
  require(goal_stiffness > 0.0 && std::isfinite(goal_stiffness), "goal_stiffness",
          "(K_e) must be finite and > 0, got " + std::to_string(goal_stiffness));
  require(deformation_allowance >= 0.0 && deformation_allowance <= 1.0, "deformation_allowance",
          "(s) must be in [0, 1], got " + std::to_string(deformation_allowance));
  require(implicit_step_factor >= 0.0 && std::isfinite(implicit_step_factor), "implicit_step_factor",
          "must be finite and >= 0, got " + std::to_string(implicit_step_factor));
  require(!global_implicit_goal || implicit_goal, "global_implicit_goal", "needs implicit_goal");
  require(implicit_tolerance > 0.0 && implicit_tolerance < 1.0, "implicit_tolerance",
          "must be in (0, 1), got " + std::to_string(implicit_tolerance));
  require(implicit_max_iterations >= 1, "implicit_max_iterations",
          "must be >= 1, got " + std::to_string(implicit_max_iterations));
  require(min_neighbors >= 2, "min_neighbors", "must be >= 2, got " + std::to_string(min_neighbors));
  require(fracture_strain >= 0.0, "fracture_strain", "must be >= 0, got " + std::to_string(fracture_strain));
  require(fracture_rate >= 0.0, "fracture_rate", "must be >= 0, got " + std::to_string(fracture_rate));
  require(max_docking_rate >= 0.0 && std::isfinite(max_docking_rate), "max_docking_rate",
          "must be finite and >= 0, got " + std::to_string(max_docking_rate));
  require(docking_rate_increase >= 0.0 && std::isfinite(docking_rate_increase), "docking_rate_increase",
          "(1/s^2) must be finite and >= 0, got " + std::to_string(docking_rate_increase));
  require(docking_rate_decrease >= 0.0 && std::isfinite(docking_rate_decrease), "docking_rate_decrease",
          "(1/s^2) must be finite and >= 0, got " + std::to_string(docking_rate_decrease));
  require(docking_distance > 0.0 && docking_distance <= 1.0, "docking_distance",
          "must be in (0, 1], got " + std::to_string(docking_distance));
  require(yield_strain >= 0.0, "yield_strain", "must be >= 0, got " + std::to_string(yield_strain));
  require(plastic_flow_rate >= 0.0 && std::isfinite(plastic_flow_rate), "plastic_flow_rate",
          "must be finite and >= 0, got " + std::to_string(plastic_flow_rate));
  require(max_plastic_strain > 0.0 && std::isfinite(max_plastic_strain), "max_plastic_strain",
          "must be finite and > 0, got " + std::to_string(max_plastic_strain));
  require(!(docking || plasticity()) || (time_step > 0.0 && std::isfinite(time_step)), "time_step",
          "must be finite and > 0 with docking or plasticity (the dt of unannounced evaluations), got " +
              std::to_string(time_step));
}

void assignLatticePoints(const SphLattice& lattice, const Mat3& transform, const std::vector<Vec3>& offsets,
                         SphLatticeAssignment& out) {
  const size_t n = offsets.size();
  out.indices.resize(n);
  out.assigned.resize(n);
  out.sq_dists.resize(n);
  Eigen::Vector3i* idx = out.indices.data();
  uint8_t* assigned = out.assigned.data();
  double* dist2 = out.sq_dists.data();
  const Vec3* offset = offsets.data();
  const Mat3 to_coordinates = lattice.inverseBasis() * transform.inverse();  // B^-1 A^-1
  constexpr int kHalf = SphLatticeAssignment::kTableHalfWidth, kWidth = 2 * kHalf;
  // One particle per lattice point: the closest keeps it (ties: lower index). A table of the lattice points
  // around the centre (entries of older calls are told apart by a stamp, so it is never cleared) or, when a
  // point lies outside it, a small open-addressing hash table holds the current keeper of each point.
  const auto compete = [&](int32_t& keeper, size_t k) {
    const int32_t other = keeper;  // k comes after `other`: it wins only when strictly closer.
    if (dist2[k] < dist2[size_t(other)]) {
      assigned[size_t(other)] = 0;
      keeper = int32_t(k);
    } else {
      assigned[k] = 0;
    }
  };
  if (out.table_stamps.size() != size_t(kWidth * kWidth * kWidth)) {
    out.table_stamps.assign(kWidth * kWidth * kWidth, 0);
    out.table_keepers.assign(kWidth * kWidth * kWidth, -1);
    out.stamp = 0;
  }
  if (++out.stamp == 0) {  // wrapped: forget all entries
    std::fill(out.table_stamps.begin(), out.table_stamps.end(), 0u);
    out.stamp = 1;
  }
  const uint32_t stamp = out.stamp;
  uint32_t* stamps = out.table_stamps.data();
  int32_t* keepers = out.table_keepers.data();
  size_t k = 0;
  for (; k < n; ++k) {  // (8.21), the competition in the same pass while all points lie in the table
    const Eigen::Vector3i i = lattice.nearestIndexOfCoordinates(to_coordinates * offset[k], &dist2[k]);
    idx[k] = i;
    assigned[k] = !i.isZero();  // the origin is the centre particle's own point
    const int32_t slot = latticeTableSlot(i);
    if (slot < 0) break;
    if (stamps[slot] != stamp) {
      stamps[slot] = stamp;
      keepers[slot] = int32_t(k);
    } else {
      compete(keepers[slot], k);
    }
  }
  if (k == n) return;
  // A point outside the table: the rest of the indices, then the competition anew in the hash table.
  for (++k; k < n; ++k) {
    idx[k] = lattice.nearestIndexOfCoordinates(to_coordinates * offset[k], &dist2[k]);
  }
  for (k = 0; k < n; ++k) assigned[k] = !idx[k].isZero();
  size_t hash_slots = 64;
  while (hash_slots < 4 * n) hash_slots *= 2;
  std::vector<int32_t>& keeper = out.keepers;
  keeper.assign(hash_slots, -1);
  for (k = 0; k < n; ++k) {
    const Eigen::Vector3i& i = idx[k];
    const uint64_t key = uint64_t(uint32_t(i.x())) * 0x9E3779B97F4A7C15ull ^
                         uint64_t(uint32_t(i.y())) * 0xC2B2AE3D27D4EB4Full ^
                         uint64_t(uint32_t(i.z())) * 0x165667B19E3779F9ull;
    for (size_t slot = size_t(key >> 32) & (hash_slots - 1);; slot = (slot + 1) & (hash_slots - 1)) {
      const int32_t other = keeper[slot];
      if (other < 0) {
        keeper[slot] = int32_t(k);
        break;
      }
      if (idx[size_t(other)] != i) continue;
      compete(keeper[slot], k);
      break;
    }
  }
}

// GCC 12 reports Eigen's JacobiSVD internals as maybe-uninitialized once inlined here (a false positive).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
void rotationSvd(const Mat3& a, int dimension, Mat3& u, Vec3& sigma, Mat3& v) {
  if (dimension == 2) {
    Eigen::JacobiSVD<Eigen::Matrix2d> svd(a.topLeftCorner<2, 2>(), Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix2d u2 = svd.matrixU(), v2 = svd.matrixV();
    Eigen::Vector2d s2 = svd.singularValues();
    if ((u2 * v2.transpose()).determinant() < 0.0) {  // reflection: flip the smallest singular value
      u2.col(1) = -u2.col(1);
      s2(1) = -s2(1);
    }
    u.setIdentity();
    v.setIdentity();
    u.topLeftCorner<2, 2>() = u2;
    v.topLeftCorner<2, 2>() = v2;
    sigma = Vec3(s2(0), s2(1), 1.0);
    return;
  }
  Eigen::JacobiSVD<Mat3> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
  u = svd.matrixU();
  v = svd.matrixV();
  sigma = svd.singularValues();
  if ((u * v.transpose()).determinant() < 0.0) {  // (8.24) must be a rotation
    u.col(2) = -u.col(2);
    sigma(2) = -sigma(2);
  }
}
#pragma GCC diagnostic pop

SphElasticSolid::SphElasticSolid(const SphElasticConfig& config, const SphKernels& kernels, uint8_t phase,
                                 const Mat3& lattice_orientation)
    : config_(config),
      kernels_(kernels),
      lattice_(kernels.dimension, config.lattice_spacing > 0.0 ? config.lattice_spacing : 1.0),
      phase_(phase),
      orientation_(lattice_orientation),
      step_dt_(config.time_step) {
  config_.validate();
  if (phase == 0) throw std::invalid_argument("SphElasticSolid: phase 0 is the fluid phase");
  if (!isRotation(lattice_orientation))
    throw std::invalid_argument("SphElasticSolid: lattice_orientation must be a rotation");
  if (kernels.dimension == 2 && (lattice_orientation.col(2) - Vec3::UnitZ()).norm() > 1e-12)
    throw std::invalid_argument("SphElasticSolid: in 2D lattice_orientation must be a rotation about z");
  if (!(kernels.h > 1.01 * config.lattice_spacing))
    throw std::invalid_argument("SphElasticSolid: the smoothing length " + std::to_string(kernels.h) +
                                " must exceed the lattice spacing " + std::to_string(config.lattice_spacing) +
                                " (no neighbours otherwise)");
  if (config_.min_neighbors < kernels.dimension)
    throw std::invalid_argument("SphElasticConfig.min_neighbors: must be >= the dimension");
  const double y = config_.youngs_modulus, nu = config_.poisson_ratio;
  lame_mu_ = y / (2.0 * (1.0 + nu));
  lame_lambda_ = y * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  // Stiffness bound of the strain model on a full lattice neighbourhood (Gershgorin-like): a neighbour's
  // force coefficient a_j = W_j |D^-1 l_j| for the stress part and W_j / tr D for the hourglass part.
  const int r = static_cast<int>(std::ceil(kernels.h / config.lattice_spacing)) + 1;
  const int rz = kernels.dimension == 3 ? r : 0;
  std::vector<Vec3> ls;
  Mat3 d = Mat3::Zero();
  double sum_w = 0.0;
  for (int k = -rz; k <= rz; ++k)
    for (int j = -r; j <= r; ++j)
      for (int i = -r; i <= r; ++i) {
        const Vec3 l = lattice_.point(Eigen::Vector3i(i, j, k));
        const double w = kernels.poly6(l.squaredNorm());
        if (l.squaredNorm() == 0.0 || w <= 0.0) continue;
        ls.push_back(l);
        d += w * l * l.transpose();
        sum_w += w;
      }
  if (kernels.dimension == 2) d(2, 2) = 1.0;
  const Mat3 d_inv = d.inverse();
  double sum_a = 0.0;
  for (const Vec3& l : ls) sum_a += kernels.poly6(l.squaredNorm()) * (d_inv * l).norm();
  const double trace = kernels.dimension == 3 ? d.trace() : d.trace() - 1.0;
  strain_omega2_mass_ =
      4.0 * lattice_.cellVolume() *
      ((lame_lambda_ + 2.0 * lame_mu_) * sum_a * sum_a + config_.hourglass_control * y * sum_w / trace);
  // The nearest lattice neighbours (|B step| = d) lie in [-1, 1]^3.
  const double d2 = lattice_.spacing() * lattice_.spacing(), eps = 1e-9 * d2;
  const int kz = lattice_.dimension() == 3 ? 1 : 0;
  for (int sz = -kz; sz <= kz; ++sz)
    for (int sy = -1; sy <= 1; ++sy)
      for (int sx = -1; sx <= 1; ++sx) {
        const Eigen::Vector3i step(sx, sy, sz);
        if (std::abs(lattice_.point(step).squaredNorm() - d2) <= eps) nearest_steps_.push_back(step);
      }
}

size_t SphElasticSolid::addParticles(SphParticles& particles, const std::vector<Vec3>& positions, double mass,
                                     const Vec3& velocity) const {
  if (!(mass > 0.0) || !std::isfinite(mass))
    throw std::invalid_argument("SphElasticSolid::addParticles: mass must be finite and > 0, got " +
                                std::to_string(mass));
  const size_t first = particles.size();
  for (const Vec3& x : positions) {
    particles.add(x, velocity, mass, SphParticleKind::kFluid);
    particles.phases.back() = phase_;
  }
  return first;
}

void SphElasticSolid::prepare(const SphParticles& particles, const std::vector<Vec3>& velocities) {
  const size_t n = particles.size();
  if (transform_.size() != n) {
    transform_.resize(n, orientation_);
    rotation_.resize(n, orientation_);
    quaternion_.resize(n, Eigen::Quaterniond(orientation_));
    strain_.resize(n, Mat3::Zero());
    has_transform_.resize(n, 0);
    unassigned_count_.resize(n, 0);
  }
  if (config_.docking && dock_.size() != n) {
    dock_.resize(n);
    dock_initialized_.resize(n, 0);
    docked_count_.resize(n, 0);
  }
  if (config_.plasticity() && plastic_.size() != n) {
    plastic_.resize(n, Mat3::Identity());
    plastic_strain_.resize(n, 0.0);
  }
  const bool global_implicit = config_.global_implicit_goal;
  // Appended particles (fluid sources) start without history; the others keep their warm start.
  if (global_implicit && history_.size() != n) history_.resize(n, ImplicitHistory{});
  std::vector<Vec3>& points = member_points_;
  std::vector<uint32_t>& members = members_;
  points.clear();
  members.clear();
  // The solver's neighbour rows replace the search when they are of the same radius (setNeighborSource).
  const SphFluidSolver* source = neighbor_source_;
  if (source && (source->config().smoothing_length != kernels_.h || source->neighborGrid().size() != n))
    source = nullptr;
  if (reset_done_.size() != n) reset_done_.resize(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const bool solid = particles.phases[i] == phase_ &&
                       (particles.kinds[i] == SphParticleKind::kFluid || config_.anchor_boundary_particles);
    if (!solid) {
      if (reset_done_[i]) continue;  // reset at an earlier evaluation and untouched since
      reset_done_[i] = 1;
      has_transform_[i] = 0;  // a particle that (re)joins starts from the lattice orientation
      transform_[i] = rotation_[i] = orientation_;
      quaternion_[i] = Eigen::Quaterniond(orientation_);
      strain_[i].setZero();
      unassigned_count_[i] = 0;
      if (config_.docking && dock_initialized_[i]) {  // it docks anew when it (re)joins
        dock_[i].clear();
        dock_initialized_[i] = 0;
        docked_count_[i] = 0;
      }
      if (config_.plasticity()) {
        plastic_[i].setIdentity();
        plastic_strain_[i] = 0.0;
      }
      if (global_implicit) history_[i] = ImplicitHistory{};  // it starts anew when it (re)joins
      continue;
    }
    reset_done_[i] = 0;
    members.push_back(static_cast<uint32_t>(i));
    if (!source) points.push_back(particles.positions[i]);
  }
  const size_t m = members.size();
  solid_.resize(m);
  if (source) {
    // Sorted order: the solver's cell order restricted to the members; row_to_solid_ maps its sorted
    // positions to this order (kNoSolid for other particles).
    const std::vector<uint32_t>& order = source->neighborGrid().order();
    row_to_solid_.resize(n);
    solid_row_.resize(m);
    size_t next = 0;
    for (size_t r = 0; r < n; ++r) {
      const uint32_t i = order[r];
      const bool member = particles.phases[i] == phase_ && (particles.kinds[i] == SphParticleKind::kFluid ||
                                                            config_.anchor_boundary_particles);
      row_to_solid_[r] = member ? uint32_t(next) : kNoSolid;
      if (member) {
        solid_row_[next] = uint32_t(r);
        solid_[next++] = i;
      }
    }
  } else {
    solid_row_.clear();
    grid_.build(points, kernels_.h, 1);
    for (size_t s = 0; s < m; ++s) solid_[s] = members[grid_.order()[s]];
  }
  s_pos_.resize(m);
  s_vel_.resize(m);
  s_mass_.resize(m);
  for (size_t s = 0; s < m; ++s) {
    const uint32_t i = solid_[s];
    s_pos_[s] = particles.positions[i];
    s_vel_[s] = velocities[i];
    s_mass_[s] = particles.masses[i];
  }
  lost_.resize(m);
  if (global_implicit) springs_.resize(m);
  net_force_.resize(m);
  net_torque_.resize(m);
  energy_.assign(m, 0.0);
  max_strain_.assign(m, 0.0);
  assigned_.assign(m, 0);
  unassigned_.assign(m, 0);
  matched_.assign(m, 0);
  if (config_.docking) {
    detached_.assign(m, 0);
    separated_.assign(m, 0);
    redocked_.assign(m, 0);
  }
}

size_t SphElasticSolid::gatherNeighbors(size_t s, Scratch& sc) const {
  // Current neighbours of the same solid: from the solver's row or from a search of the solid's grid.
  const Vec3 xi = s_pos_[s];
  SphSortedGrid::Run runs[9];
  int num_runs = 0;
  size_t candidates = 0;
  const uint32_t* row = nullptr;
  if (!solid_row_.empty()) {
    uint32_t count = 0;
    row = neighbor_source_->neighborRow(solid_row_[s], count);
    candidates = count;
  } else {
    num_runs = grid_.neighborRuns(grid_.cellOfSorted(s), runs);
    for (int r = 0; r < num_runs; ++r) candidates += runs[r].end - runs[r].begin;
  }
  // Fixed scratch of the candidate count (only grows), filled by index and cut to the neighbours.
  if (sc.offsets.size() < candidates) {
    sc.offsets.resize(candidates);
    sc.neighbors.resize(candidates);
    sc.weights.resize(candidates);
  }
  Vec3* offsets = sc.offsets.data();
  uint32_t* neighbors = sc.neighbors.data();
  double* weights = sc.weights.data();
  size_t nn = 0;
  const double h2 = kernels_.h2;
  const Vec3* pos = s_pos_.data();
  // Branch-free: every candidate is written, the count advances only for neighbours (in ascending order).
  for (size_t e = 0; e < (row ? candidates : 0); ++e) {  // the row holds those within h: keep the members
    const uint32_t j = row_to_solid_[row[e]];
    const bool member = j != kNoSolid;
    const uint32_t jj = member ? j : uint32_t(s);
    const double dx = pos[jj].x() - xi.x(), dy = pos[jj].y() - xi.y(), dz = pos[jj].z() - xi.z();
    offsets[nn] = Vec3(dx, dy, dz);
    neighbors[nn] = jj;
    weights[nn] = dx * dx + dy * dy + dz * dz;  // d < h on the row
    nn += size_t(member);
  }
  for (int r = 0; r < num_runs; ++r)
    for (uint32_t j = runs[r].begin; j < runs[r].end; ++j) {
      const double dx = pos[j].x() - xi.x(), dy = pos[j].y() - xi.y(), dz = pos[j].z() - xi.z();
      const double d2 = dx * dx + dy * dy + dz * dz;
      offsets[nn] = Vec3(dx, dy, dz);
      neighbors[nn] = j;
      weights[nn] = d2;
      nn += size_t((d2 < h2) & (j != s));
    }
  for (size_t k = 0; k < nn; ++k) weights[k] = kernels_.poly6(weights[k]);  // apart: vectorised
  sc.offsets.resize(nn);
  sc.neighbors.resize(nn);
  sc.weights.resize(nn);
  return nn;
}

void SphElasticSolid::processNeighborhood(size_t s, Scratch& sc) {
  const int dim = lattice_.dimension();
  const uint32_t i = solid_[s];
  net_force_[s].setZero();
  net_torque_[s].setZero();
  lost_[s].clear();
  if (globalImplicit()) springs_[s].clear();
  const size_t nn = gatherNeighbors(s, sc);
  // Lattice assignment from the previous transform (8.21).
  assignLatticePoints(lattice_, transform_[i], sc.offsets, sc.assignment);
  const uint8_t* assigned = sc.assignment.assigned.data();
  const Eigen::Vector3i* indices = sc.assignment.indices.data();
  const Vec3* offsets = sc.offsets.data();
  const uint32_t* neighbors = sc.neighbors.data();
  const double* weights = sc.weights.data();
  // Rest points of the (plastically deformed) lattice: P_i l_ij (B n, as SphLattice::point).
  const bool plastic = config_.plasticity();
  const Vec3 b0 = lattice_.basis().col(0), b1 = lattice_.basis().col(1), b2 = lattice_.basis().col(2);
  const bool three = dim == 3;
  const Mat3 plastic_transform = plastic ? plastic_[i] : Mat3::Identity();
  const auto restPoint = [&](size_t k) {
    const Eigen::Vector3i& n = indices[k];
    Vec3 l = b0 * n.x() + b1 * n.y();
    if (three) l += b2 * n.z();
    if (plastic) l = plastic_transform * l;
    return l;
  };
  const bool docking = config_.docking;
  if (docking) {  // 8.2.5: only docked lattice points count
    sc.rest.resize(nn);
    for (size_t k = 0; k < nn; ++k) {
      sc.rest[k] = restPoint(k);
      if (!assigned[k]) {
        ++unassigned_[s];
        lost_[s].push_back(solid_[neighbors[k]]);
      }
    }
    updateDocking(s, sc);
  }
  // One pass: the neighbours left without a point, the assigned ones gathered in order, and the sums of the
  // fit (8.23), the weighted centre of the momentum correction (8.32) and the implicit springs (separate
  // accumulators, each in neighbour order).
  if (sc.a_offset.size() < nn) {
    sc.a_offset.resize(nn);
    sc.a_rest.resize(nn);
    sc.a_velocity.resize(nn);
    sc.a_force.resize(nn);
    sc.a_weight.resize(nn);
    sc.a_neighbor.resize(nn);
  }
  Vec3 *a_offset = sc.a_offset.data(), *a_rest = sc.a_rest.data(), *a_velocity = sc.a_velocity.data();
  double* a_weight = sc.a_weight.data();
  uint32_t* a_neighbor = sc.a_neighbor.data();
  FitSums sums;
  sums.w_sum = kernels_.poly6(0.0);
  Mat3 rl = Mat3::Zero(), ll = Mat3::Zero();
  Vec3 c = Vec3::Zero(), weighted_v = Vec3::Zero();
  double w_sum = sums.w_sum, w_neighbors = 0.0;
  size_t count = 0;
  const Vec3* vel = s_vel_.data();
  for (size_t k = 0; k < nn; ++k) {
    if (!assigned[k]) {
      if (!docking) {
        ++unassigned_[s];
        lost_[s].push_back(solid_[neighbors[k]]);
      }
      continue;
    }
    const Vec3 l = docking ? sc.rest[k] : restPoint(k);
    const Vec3 r = offsets[k];
    const double w = weights[k];
    const uint32_t j = neighbors[k];
    const Vec3 v = vel[j];
    a_offset[count] = r;
    a_rest[count] = l;
    a_weight[count] = w;
    a_neighbor[count] = j;
    a_velocity[count] = v;
    ++count;
    addOuter(rl, w, r, l);
    addOuter(ll, w, l, l);
    w_sum += w;
    addScaled(c, w, r);
    w_neighbors += w;
    addScaled(weighted_v, w, v);
  }
  sums.rl = rl;
  sums.ll = ll;
  sums.w_sum = w_sum;
  sums.w_neighbors = w_neighbors;
  sums.weighted_r = c;  // sum_j W_ij r_ij, also the (unnormalised) centre of (8.32)
  sums.weighted_v = weighted_v;
  sums.count = count;
  assigned_[s] = static_cast<uint32_t>(count);
  if (dim == 2) sums.rl(2, 2) = sums.ll(2, 2) = 1.0;
  if (count < size_t(config_.min_neighbors)) return;
  ShapeFit fit;
  if (!fitShape(s, sums, fit)) return;
  const Vec3 centre_force = config_.model == SphElasticModel::kStrain ? strainForces(s, sums, fit, sc)
                                                                      : goalForces(s, sums, fit, sc);
  correctAndScatter(s, sums, centre_force, sc);
}

bool SphElasticSolid::fitShape(size_t s, const FitSums& sums, ShapeFit& fit) {
  const int dim = lattice_.dimension();
  const uint32_t i = solid_[s];
  const bool plastic = config_.plasticity();
  const Mat3& ll = sums.ll;
  const double scale = ll.trace() / dim;
  const double det = dim == 3 ? ll.determinant() : ll.topLeftCorner<2, 2>().determinant();
  const double scale_dim = dim == 3 ? scale * scale * scale : scale * scale;
  if (!(det > 1e-6 * scale_dim)) return false;  // (near) planar neighbourhood: no fit
  // (8.23) fitted to the rest points: with plasticity the elastic part A_i P_i^-1.
  fit.ll_inverse = ll.inverse();
  fit.a = sums.rl * fit.ll_inverse;
  const Mat3& a = fit.a;
  if (!a.allFinite()) return false;
  // Rotation (8.24) by the warm-started quaternion iteration; the stretch S = R^T A (symmetric at the
  // optimum) has the singular values as eigenvalues. The SVD is kept where its factors are needed: plastic
  // flow, a stretch outside the clamp [0.25, 4] of the next assignment's transform (or inverted), a goal
  // stretch (8.30) at its clamp, or no convergence.
  const double s_allow = config_.deformation_allowance;
  const bool goal_model = config_.model == SphElasticModel::kGoalPosition;
  Mat3& rot = fit.rot;
  Mat3& goal = fit.goal;
  bool polar = false;
  double max_strain = -1.0;  // from the stretch's eigenvalues where the polar path has them
  if (!plastic) {
    Eigen::Quaterniond q = quaternion_[i];
    if (extractRotation(a, q)) {
      rot = q.toRotationMatrix();
      Mat3 stretch = rot.transpose() * a;
      stretch = 0.5 * (stretch + stretch.transpose());
      Eigen::SelfAdjointEigenSolver<Mat3> eigen;
      eigen.computeDirect(stretch, Eigen::EigenvaluesOnly);
      const Vec3 sigma = eigen.eigenvalues();  // ascending
      // sv_k = s sigma_k + 1 - s >= 0.05 holds for sigma >= 0.25 whenever s <= 1.
      if (sigma.allFinite() && sigma(0) >= 0.25 && sigma(2) <= 4.0) {
        polar = true;
        // sym(A R^T) = R S R^T: the strain (8.26) has the eigenvalues sigma - 1.
        max_strain = std::max(std::abs(sigma(0) - 1.0), std::abs(sigma(2) - 1.0));
        quaternion_[i] = q;
        transform_[i] = a;  // A_i for the next assignment (no clamp active)
        if (goal_model) {
          // U diag(sv) V^T of (8.29)-(8.30) = R (s S + (1 - s) I) / det^(1/dim).
          Mat3 sv = s_allow * stretch;
          sv.diagonal().array() += 1.0 - s_allow;
          if (dim == 3) {
            sv /= std::cbrt((s_allow * sigma.array() + (1.0 - s_allow)).prod());
          } else {
            sv.topLeftCorner<2, 2>() /= std::sqrt(sv.topLeftCorner<2, 2>().determinant());
            sv(2, 2) = 1.0;
          }
          goal = rot * sv;
        }
      }
    }
  }
  if (!polar) {
    Mat3 u, v;
    Vec3 sigma;
    rotationSvd(a, dim, u, sigma, v);
    rot = u * v.transpose();  // (8.24)
    const Vec3 clamped = sigma.cwiseMax(0.25).cwiseMin(4.0);
    transform_[i] = u * clamped.asDiagonal() * v.transpose();  // A_i for the next assignment
    if (plastic) {
      transform_[i] = transform_[i] * plastic_[i];
      updatePlasticity(i, v, sigma);  // takes effect at the next evaluation
    }
    if (goal_model) {
      // Goal positions g'_ij = U S V^T l_ij (8.29) with the volume-preserving S (8.30).
      Vec3 sv = (s_allow * sigma.array() + (1.0 - s_allow)).matrix().cwiseMax(0.05);
      if (dim == 2) sv.z() = 1.0;
      const double volume_factor = dim == 3 ? sv.prod() : sv.x() * sv.y();
      sv /= std::pow(volume_factor, 1.0 / dim);
      if (dim == 2) sv.z() = 1.0;
      goal = u * sv.asDiagonal() * v.transpose();
    }
    Eigen::Quaterniond q(rot);
    quaternion_[i] = q.normalized();
  }
  rotation_[i] = rot;
  has_transform_[i] = 1;
  matched_[s] = 1;

  // Strain (8.26) from the rest positions g_ij = R_i l_ij (8.25): the displacement gradient fits
  // sum_j W_ij |(r_ij - g_ij) - G g_ij|^2: (8.27) weighted by W_ij (g_ij.e_beta)^2 and solved with the full
  // normal matrix. As printed, (8.28)'s denominator sum_j W_ij g_ij.e_beta vanishes on a symmetric
  // neighbourhood, and its diagonal form is not exact for linear displacements on the rotated fcc lattice.
  // With D = sum_j W_ij g_ij g_ij^T = R ll R^T and sum_j W_ij (r_ij - g_ij) g_ij^T = (rl - R ll) R^T the fit
  // is G = A R^T - I (no second pass over the neighbours).
  Mat3 strain = a * rot.transpose();
  strain = 0.5 * (strain + strain.transpose()) - Mat3::Identity();
  if (dim == 2) {
    strain.row(2).setZero();
    strain.col(2).setZero();
  }
  strain_[i] = strain;
  if (max_strain >= 0.0) {
    max_strain_[s] = max_strain;
  } else {
    Eigen::SelfAdjointEigenSolver<Mat3> eigen;
    eigen.computeDirect(strain, Eigen::EigenvaluesOnly);
    max_strain_[s] = eigen.eigenvalues().cwiseAbs().maxCoeff();
  }
  return true;
}

Vec3 SphElasticSolid::strainForces(size_t s, const FitSums& sums, const ShapeFit& fit, Scratch& sc) {
  // Linear elasticity: sigma = lambda tr(eps) I + 2 mu eps. Forces are the negative gradient of the
  // neighbourhood's energy V_i sigma:eps / 2 through the strain fit (R_i held fixed, corotational):
  // F_j = -V_i W_ij sigma_i D_i^-1 g_ij with D_i = sum_j W_ij g_ij g_ij^T, F_i = -sum_j F_j. This is the
  // SPH stress divergence with the kernel gradient corrected to match the strain estimate; the plain V_i
  // V_j sigma_i grad W form showed the tensile instability (a 10% stretched block blew up at any dt).
  const int dim = lattice_.dimension();
  const double volume = lattice_.cellVolume();
  const Mat3& strain = strain_[solid_[s]];
  const Mat3& rot = fit.rot;
  const Mat3& a = fit.a;
  const Mat3 den_inverse = rot * fit.ll_inverse * rot.transpose();
  Mat3 identity = Mat3::Identity();
  if (dim == 2) identity(2, 2) = 0.0;
  const Mat3 stress = lame_lambda_ * strain.trace() * identity + 2.0 * lame_mu_ * strain;
  energy_[s] = 0.5 * volume * (stress.cwiseProduct(strain)).sum();
  const Mat3 stress_den = stress * den_inverse;
  // Hourglass control: the strain fit does not see non-affine (zero-energy) modes; they are penalised
  // by pulling each neighbour towards the fitted affine position A_i l_ij, with energy
  // gamma Y V / (2 tr D_i) sum_j W_ij |A_i l_ij - r_ij|^2 (zero for any affine deformation; A_i minimises
  // the sum, so the force is its exact gradient).
  const double hourglass = config_.hourglass_control * config_.youngs_modulus * volume / sums.ll.trace();
  const Vec3* offsets = sc.a_offset.data();
  const Vec3* rest = sc.a_rest.data();
  const double* weights = sc.a_weight.data();
  Vec3* forces = sc.a_force.data();
  Vec3 centre_force = Vec3::Zero();
  for (size_t k = 0; k < sums.count; ++k) {
    const Vec3& l = rest[k];
    const Vec3 g = rot * l;
    const Vec3 residual = a * l - offsets[k];
    energy_[s] += 0.5 * hourglass * weights[k] * residual.squaredNorm();
    const Vec3 f = (-volume * weights[k]) * (stress_den * g) + (hourglass * weights[k]) * residual;
    forces[k] = f;
    centre_force -= f;
  }
  return centre_force;
}

Vec3 SphElasticSolid::goalForces(size_t s, const FitSums& sums, const ShapeFit& fit, Scratch& sc) {
  // F_ij (8.31) towards the goal positions, half to j and minus half to i.
  const int dim = lattice_.dimension();
  const double volume = lattice_.cellVolume();
  const double k_e = config_.goal_stiffness * s_mass_[s] * volume;
  const Mat3& goal = fit.goal;
  const size_t count = sums.count;
  const Vec3* offsets = sc.a_offset.data();
  const Vec3* rest = sc.a_rest.data();
  const Vec3* velocities = sc.a_velocity.data();
  const double* weights = sc.a_weight.data();
  Vec3* forces = sc.a_force.data();
  Vec3 centre_force = Vec3::Zero();
  double energy = 0.0;
  if (config_.implicit_goal && !config_.global_implicit_goal && step_dt_ > 0.0) {
    // Locally implicit springs (see SphElasticConfig::implicit_goal): the forces scaled by
    // 1 / (1 + dt^2 k), and the damping -dt k u / (4 (1 + dt^2 k)) of the members' velocities u relative
    // to the neighbourhood's rigid motion (weights W_j, the centre weighted sum_j W_j: its velocity is half
    // the neighbourhood's mean, which keeps the damping stable for any dt). The damping forces have no net
    // force or torque.
    const double w_neighbors = sums.w_neighbors;
    const double w_all = 2.0 * w_neighbors;
    const Vec3 vi = s_vel_[s];
    const Vec3 mean_v = (w_neighbors * vi + sums.weighted_v) / w_all;
    const Vec3 centre = sums.weighted_r / w_all;  // relative to x_i
    // Angular velocity of the neighbourhood: I omega = sum_k W_k p_k x (v_k - mean_v).
    Mat3 inertia = pointInertia(w_neighbors, centre);
    const Vec3 centre_momentum = crossOf(-centre, vi - mean_v);
    Vec3 momentum(w_neighbors * centre_momentum.x(), w_neighbors * centre_momentum.y(),
                  w_neighbors * centre_momentum.z());
    for (size_t k = 0; k < count; ++k) {
      const Vec3 p = offsets[k] - centre;
      addInertia(inertia, weights[k], p);
      addScaled(momentum, weights[k], crossOf(p, velocities[k] - mean_v));
    }
    Vec3 spin = Vec3::Zero();
    if (dim == 3) {
      const double det = inertia.determinant(), size = inertia.trace();
      if (det > 1e-9 * size * size * size) spin = inertia.inverse() * momentum;
    } else if (inertia(2, 2) > 0.0) {
      spin.z() = momentum.z() / inertia(2, 2);
    }
    const double dt = step_dt_;
    const double scale = 1.0 / (1.0 + dt * dt * config_.goal_stiffness * volume * w_neighbors);
    const double damping = 0.25 * scale * dt * k_e;
    for (size_t k = 0; k < count; ++k) {
      const Vec3 delta = goal * rest[k] - offsets[k];
      const Vec3 u = velocities[k] - mean_v - crossOf(spin, offsets[k] - centre);
      const Vec3 f = (0.5 * scale * k_e * weights[k]) * delta - (damping * weights[k]) * u;
      energy += 0.5 * k_e * weights[k] * delta.squaredNorm();
      forces[k] = f;
      centre_force -= f;
    }
    // The centre's damping -damping w_neighbors u_i equals minus the neighbours' sum (sum_k W_k u_k = 0),
    // so centre_force = -sum_j f_j holds it exactly.
  } else {
    for (size_t k = 0; k < count; ++k) {
      const Vec3 delta = goal * rest[k] - offsets[k];
      const Vec3 f = (0.5 * k_e * weights[k]) * delta;
      energy += 0.5 * k_e * weights[k] * delta.squaredNorm();
      forces[k] = f;
      centre_force -= f;
    }
    if (globalImplicit())  // the stiffness of these forces in x_j - x_i, goal held fixed
      for (size_t k = 0; k < count; ++k) springs_[s].push_back({sc.a_neighbor[k], 0.5 * k_e * weights[k]});
  }
  energy_[s] = energy;
  return centre_force;
}

void SphElasticSolid::correctAndScatter(size_t s, const FitSums& sums, Vec3 centre_force, Scratch& sc) {
  // Angular momentum (8.32)-(8.33): the torque of the neighbourhood's forces about the weighted centre c_i
  // is removed by forces w_k omega x (x_k - c_i), which sum to zero; omega solves I omega = -tau with the
  // weighted inertia tensor I, so the correction is exact (8.33 spreads tau with weights W/|x - c|).
  const int dim = lattice_.dimension();
  const size_t count = sums.count;
  const Vec3* offsets = sc.a_offset.data();
  const double* weights = sc.a_weight.data();
  const uint32_t* neighbors = sc.a_neighbor.data();
  Vec3* forces = sc.a_force.data();
  const double w_centre = kernels_.poly6(0.0);
  const Vec3 c = sums.weighted_r / sums.w_sum;  // relative to x_i
  Vec3 torque = (-c).cross(centre_force);
  Mat3 inertia = pointInertia(w_centre, c);
  for (size_t k = 0; k < count; ++k) {
    const Vec3 p = offsets[k] - c;
    torque += crossOf(p, forces[k]);
    addInertia(inertia, weights[k], p);
  }
  if (dim == 2) {
    torque.x() = torque.y() = 0.0;  // in-plane forces
    inertia(2, 2) = std::max(inertia(2, 2), std::numeric_limits<double>::min());
    inertia.topLeftCorner<2, 2>().setIdentity();
    inertia(0, 2) = inertia(1, 2) = inertia(2, 0) = inertia(2, 1) = 0.0;
  }
  const Vec3 omega = -inertia.inverse() * torque;
  const bool correct = omega.allFinite();  // else the forces stay uncorrected
  if (correct) centre_force += w_centre * omega.cross(-c);
  // Scatter: the centre first, then the neighbours in order; the net force and torque (diagnostics) in the
  // same order.
  Vec3* target = force_target_;
  const uint32_t* scatter = scatter_.data();
  const uint32_t thread = sc.thread;
  Vec3 net_force = Vec3::Zero(), net_torque = Vec3::Zero();
  const auto emit = [&](uint32_t j, const Vec3& f) {
    net_force += f;
    net_torque += crossOf(s_pos_[j], f);
    const uint32_t info = scatter[j];
    if (info == ((thread << 1) | 1u)) {
      target[solid_[j]] += f;  // owned by this thread, no lower thread contributes
    } else {
      sc.deferred[info >> 1].push_back({j, f});
    }
  };
  emit(uint32_t(s), centre_force);
  for (size_t k = 0; k < count; ++k) {
    Vec3 f = forces[k];
    if (correct) addScaled(f, weights[k], crossOf(omega, offsets[k] - c));
    emit(neighbors[k], f);
  }
  net_force_[s] = net_force;
  net_torque_[s] = net_torque;
}

void SphElasticSolid::beginStep(double dt) {
  if (!(dt >= 0.0) || !std::isfinite(dt))
    throw std::invalid_argument("SphElasticSolid::beginStep: dt must be finite and >= 0, got " +
                                std::to_string(dt));
  step_dt_ = dt;
}

void SphElasticSolid::computeForces(const SphParticles& particles, std::vector<Vec3>& forces) {
  forces.assign(particles.size(), Vec3::Zero());
  addForces(particles, particles.velocities, forces);
}

void SphElasticSolid::addForces(const SphParticles& particles, const std::vector<Vec3>& velocities,
                                std::vector<Vec3>& forces) {
  if (forces.size() != particles.size())
    throw std::invalid_argument("SphElasticSolid::addForces: forces must have one entry per particle");
  if (particles.phases.size() != particles.size() || particles.kinds.size() != particles.size())
    throw std::invalid_argument("SphElasticSolid::addForces: particle arrays differ in size");
  if (velocities.size() != particles.size())
    throw std::invalid_argument("SphElasticSolid::addForces: velocities must have one entry per particle");
  prepare(particles, velocities);
  const long m = static_cast<long>(solid_.size());
  // A neighbourhood costs 1-2 us. Threads get at least 512 of them (about a millisecond): on a loaded machine
  // a preempted or spinning worker stalls a region's barrier for far longer than a tiny region saves (the
  // nine 249-particle dice of Fig. 8.8 ran 3x slower on 2 threads than on 1 with 64 per thread).
  const int threads = static_cast<int>(std::max<long>(1, std::min<long>(threadLimit(), m / 512)));
  if (scratch_.size() < size_t(threads)) scratch_.resize(threads);
  scatter_.resize(m);
  const bool global_implicit = globalImplicit();
  // Global implicit springs: the explicit forces f0 are gathered (original order) for the solve.
  std::vector<Vec3>& target = global_implicit ? s_force_ : forces;
  if (global_implicit) s_force_.assign(particles.size(), Vec3::Zero());
  force_target_ = target.data();
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num(), nt = omp_get_num_threads();
    const uint32_t first = uint32_t(m * t / nt), last = uint32_t(m * (t + 1) / nt);
    Scratch& scratch = scratch_[t];
    scratch.thread = uint32_t(t);
    scratch.deferred.resize(nt);
    for (auto& list : scratch.deferred) list.clear();
    // A particle's forces come from its own neighbourhood and its neighbours' (neighbour rows are
    // symmetric and ascending in the sorted order; the grid's runs ascend and hold all neighbours).
    for (uint32_t j = first; j < last; ++j) {
      uint32_t lo = j;
      if (nt > 1 && !solid_row_.empty()) {
        uint32_t count = 0;
        const uint32_t* row = neighbor_source_->neighborRow(solid_row_[j], count);
        for (uint32_t e = 0; e < count; ++e)
          if (row_to_solid_[row[e]] != kNoSolid) {
            lo = std::min(lo, row_to_solid_[row[e]]);
            break;
          }
      } else if (nt > 1) {
        SphSortedGrid::Run runs[9];
        if (grid_.neighborRuns(grid_.cellOfSorted(j), runs) > 0) lo = std::min(lo, runs[0].begin);
      }
      scatter_[j] = (uint32_t(t) << 1) | uint32_t(lo >= first);
    }
#pragma omp barrier
    for (uint32_t s = first; s < last; ++s) processNeighborhood(s, scratch);
#pragma omp barrier
    // The deferred contributions to this thread's particles (after the barrier), in neighbourhood order:
    // the threads' lists in thread order, each in the order of its neighbourhoods.
    for (int u = 0; u < nt; ++u)
      for (const Scratch::Contribution& c : scratch_[u].deferred[t]) target[solid_[c.target]] += c.force;
  }
  force_target_ = nullptr;
  SphElasticStats st;
  st.solid_particles = solid_.size();
  st.solver_neighbor_rows = !solid_row_.empty();
  for (size_t s = 0; s < solid_.size(); ++s) unassigned_count_[solid_[s]] = 0;
  for (size_t s = 0; s < solid_.size(); ++s) {
    st.net_force += net_force_[s];
    st.net_torque += net_torque_[s];
    for (uint32_t j : lost_[s]) ++unassigned_count_[j];
    st.matched_neighborhoods += matched_[s];
    st.skipped_neighborhoods += 1 - matched_[s];
    st.assigned_pairs += assigned_[s];
    st.unassigned_pairs += unassigned_[s];
    st.energy += energy_[s];
    st.max_strain = std::max(st.max_strain, max_strain_[s]);
    if (!matched_[s]) strain_[solid_[s]].setZero();
    if (config_.docking) {
      st.docked_points += docked_count_[solid_[s]];
      st.detached += detached_[s];
      st.separated += separated_[s];
      st.redocked += redocked_[s];
    }
    if (config_.plasticity())
      st.max_plastic_strain = std::max(st.max_plastic_strain, plastic_strain_[solid_[s]]);
  }
  if (global_implicit) solveGlobalImplicit(particles, velocities, forces, st);
  total_detached_ += st.detached;
  total_redocked_ += st.redocked;
  ++evaluations_;
  stats_ = st;
}

void SphElasticSolid::solveGlobalImplicit(const SphParticles& particles, const std::vector<Vec3>& velocities,
                                          std::vector<Vec3>& forces, SphElasticStats& st) {
  const size_t m = solid_.size();
  const double dt = step_dt_;
  f0_.resize(m);
  v_mid_.resize(m);
  dv_.resize(m);
  constraints_.clear();
  for (size_t s = 0; s < m; ++s) {
    const uint32_t i = solid_[s];
    f0_[s] = s_force_[i];
    ImplicitHistory& h = history_[i];
    dv_[s] = h.dv;
    SphVelocityConstraint c;
    c.particle = uint32_t(s);
    if (particles.kinds[i] != SphParticleKind::kFluid) {  // anchors: prescribed motion
      v_mid_[s] = velocities[i];
      c.count = 3;
      c.fixed = true;
      for (int k = 0; k < 3; ++k) c.normals[k] = Vec3::Unit(k);
      constraints_.push_back(c);
      continue;
    }
    // The velocity the springs resist, the coming step's without this term's velocity change (the solver's
    // kick-drift-kick): the given (predicted) velocity less the half kick of this term's previous force,
    // plus the other half kick of gravity; the same again when the state is evaluated again.
    const Vec3& x = s_pos_[s];
    if (h.known && x == h.x) {
      v_mid_[s] = h.velocity;
    } else {
      v_mid_[s] = velocities[i] + (0.5 * dt) * (gravity_ - h.force / s_mass_[s]);
    }
    h.x = x;
    h.velocity = v_mid_[s];
    h.known = true;
    // Planes that would stop the particle in the step: its normal velocity change brings it onto the plane.
    for (const SphPlane& plane : planes_) {
      const double gap = plane.normal.dot(x) - plane.offset, vn = plane.normal.dot(v_mid_[s]);
      if (gap + dt * vn >= 0.0 || c.count == 3) continue;
      bool orthogonal = true;
      for (int k = 0; k < c.count; ++k)
        orthogonal = orthogonal && std::abs(c.normals[k].dot(plane.normal)) < 1e-9;
      if (!orthogonal) continue;
      c.normals[c.count] = plane.normal;
      c.values[c.count++] = -std::max(gap, 0.0) / dt - vn;
    }
    if (c.count > 0) constraints_.push_back(c);
  }
  implicit_solver_.setThreads(threadLimit());
  implicit_solver_.setSystem(s_pos_, s_mass_, springs_);
  implicit_solver_.setConstraints(constraints_);
  // Solved with the other coupled solids and their contact springs by the coupling's term after this one,
  // or here alone (released plane constraints, force M dv / dt, see SphImplicitGoalCoupling).
  SphImplicitGoalBlock block;
  block.solver = &implicit_solver_;
  block.particles = &solid_;
  block.f0 = &f0_;
  block.velocity = &v_mid_;
  block.dv = &dv_;
  block.force = &implicit_force_;
  block.dt = dt;
  block.tolerance = config_.implicit_tolerance;
  block.max_iterations = config_.implicit_max_iterations;
  if (implicit_coupling_) {
    block.finish = [this](const SphImplicitGoalResult& result) { finishGlobalImplicit(result, stats_); };
    implicit_coupling_->submit(std::move(block));
    return;
  }
  block.finish = [this, &st](const SphImplicitGoalResult& result) { finishGlobalImplicit(result, st); };
  own_coupling_.submit(std::move(block));
  own_coupling_.solve({}, forces);
}

void SphElasticSolid::finishGlobalImplicit(const SphImplicitGoalResult& result, SphElasticStats& st) {
  st.implicit_iterations = result.iterations;
  st.implicit_residual = result.relative_residual;
  st.net_force.setZero();
  st.net_torque.setZero();
  for (size_t s = 0; s < solid_.size(); ++s) {
    const uint32_t i = solid_[s];
    history_[i].force = implicit_force_[s];
    history_[i].dv = dv_[s];
    st.net_force += implicit_force_[s];
    st.net_torque += crossOf(s_pos_[s], implicit_force_[s]);
  }
}

void SphElasticSolid::setLatticeTransform(size_t i, const Mat3& transform) {
  if (i >= transform_.size())
    throw std::out_of_range("SphElasticSolid::setLatticeTransform: particle " + std::to_string(i) +
                            " has no lattice transform (" + std::to_string(transform_.size()) + " known)");
  const double det =
      lattice_.dimension() == 3 ? transform.determinant() : transform.topLeftCorner<2, 2>().determinant();
  if (!transform.allFinite() || !(std::abs(det) > 0.0))
    throw std::invalid_argument("SphElasticSolid::setLatticeTransform: transform must be finite and regular");
  transform_[i] = transform;
  if (i < reset_done_.size()) reset_done_[i] = 0;  // prepare() resets it if it is no member
  Mat3 u, v;
  Vec3 sigma;
  rotationSvd(transform, lattice_.dimension(), u, sigma, v);
  quaternion_[i] = Eigen::Quaterniond(Mat3(u * v.transpose())).normalized();  // warm start of (8.24)
}

double SphElasticSolid::stableTimeStep(const SphParticles& particles, double cfl) const {
  if (config_.model == SphElasticModel::kGoalPosition) {
    const double explicit_limit = cfl * std::sqrt(2.0 / config_.goal_stiffness);
    if (!config_.implicit_goal) return explicit_limit;
    return config_.implicit_step_factor > 0.0 ? config_.implicit_step_factor * explicit_limit
                                              : std::numeric_limits<double>::infinity();
  }
  double min_mass = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < particles.size(); ++i)
    if (particles.phases[i] == phase_ && particles.kinds[i] == SphParticleKind::kFluid)
      min_mass = std::min(min_mass, particles.masses[i]);
  if (!std::isfinite(min_mass)) return std::numeric_limits<double>::infinity();
  // Verlet is stable for omega dt < 2; omega_max^2 <= strain_omega2_mass_ / m.
  return cfl * 2.0 / std::sqrt(strain_omega2_mass_ / min_mass);
}

}  // namespace rc
