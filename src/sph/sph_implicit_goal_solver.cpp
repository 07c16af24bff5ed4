#include "relaxed_connectivity/sph/sph_implicit_goal_solver.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

namespace rc {

namespace {

double dotOf(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double s = 0.0;
  for (size_t k = 0; k < a.size(); ++k) s += a[k].dot(b[k]);
  return s;
}

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}

/// Keeps the normals of the constraints that push (impulse . n >= 0); anchors stay. True if any let go.
bool releasePullingConstraints(std::vector<SphVelocityConstraint>& constraints,
                               const std::vector<Vec3>& impulses) {
  bool released = false;
  for (size_t k = 0; k < constraints.size(); ++k) {
    SphVelocityConstraint& c = constraints[k];
    if (c.fixed) continue;
    int kept = 0;
    for (int a = 0; a < c.count; ++a) {
      if (impulses[k].dot(c.normals[a]) < 0.0) continue;
      c.normals[kept] = c.normals[a];
      c.values[kept++] = c.values[a];
    }
    released = released || kept < c.count;
    c.count = kept;
  }
  return released;
}

constexpr int kReleaseRounds = 4;

}  // namespace

void SphImplicitGoalSolver::setSystem(const std::vector<Vec3>& positions, const std::vector<double>& masses,
                                      const std::vector<std::vector<SphGoalSpring>>& springs) {
  const size_t n = masses.size();
  if (positions.size() != n || springs.size() != n)
    throw std::invalid_argument("SphImplicitGoalSolver::setSystem: arrays differ in size");
  masses_ = masses;
  constraints_.clear();
  // Symmetric rows: the spring (s, j) enters row s and row j, in the order of the centres s (thread t takes
  // the centres [n t / T, n (t + 1) / T) and writes after the lower threads' entries of each row, so the
  // rows are those of one pass over s for any thread count).
  const int threads = n >= 4096 ? threads_ : 1;
  thread_counts_.resize(size_t(threads));
  thread_markers_.resize(size_t(threads));
  raw_begin_.resize(n + 1);
  merged_count_.resize(n);
  diag_.resize(n);
  row_begin_.resize(n + 1);
  bool valid = true;
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num(), nt = omp_get_num_threads();
    const size_t first = n * size_t(t) / size_t(nt), last = n * size_t(t + 1) / size_t(nt);
    std::vector<uint32_t>& count = thread_counts_[size_t(t)];
    count.assign(n, 0);
    bool thread_valid = true;
    for (size_t s = first; s < last; ++s)
      for (const SphGoalSpring& e : springs[s]) {
        const bool inside = e.other < n;
        thread_valid = thread_valid && inside;
        ++count[s];
        ++count[inside ? e.other : s];
      }
    if (!thread_valid) {
#pragma omp atomic write
      valid = false;
    }
#pragma omp barrier
    bool all_valid;
#pragma omp atomic read
    all_valid = valid;
    if (all_valid) {  // the same branch on all threads
#pragma omp single
      {
        // Row starts, and each thread's first write position per row.
        uint32_t total = 0;
        for (size_t j = 0; j < n; ++j) {
          raw_begin_[j] = total;
          for (int u = 0; u < nt; ++u) {
            const uint32_t c = thread_counts_[size_t(u)][j];
            thread_counts_[size_t(u)][j] = total;
            total += c;
          }
        }
        raw_begin_[n] = total;
        raw_cols_.resize(total);
        raw_coefs_.resize(total);
      }
      uint32_t* next = count.data();
      for (size_t s = first; s < last; ++s)
        for (const SphGoalSpring& e : springs[s]) {
          raw_cols_[next[s]] = e.other;
          raw_coefs_[next[s]++] = e.stiffness;
          raw_cols_[next[e.other]] = uint32_t(s);
          raw_coefs_[next[e.other]++] = e.stiffness;
        }
#pragma omp barrier
      // Per row: the diagonal (sum of the row's entries in order) and the entries of a pair that both
      // neighbourhoods hold merged (most pairs: half the work per product); one thread writes the rows
      // packed, several in place at each row's start and then packed.
      std::vector<uint32_t>& marker = thread_markers_[size_t(t)];
      marker.assign(n, UINT32_MAX);
      if (nt == 1) {
        cols_.resize(raw_begin_[n]);
        coefs_.resize(raw_begin_[n]);
        uint32_t out = 0;
        for (size_t s = 0; s < n; ++s) {
          const uint32_t first_out = out;
          row_begin_[s] = out;
          double diag = 0.0;
          for (uint32_t e = raw_begin_[s]; e < raw_begin_[s + 1]; ++e) {
            const uint32_t j = raw_cols_[e];
            const double c = raw_coefs_[e];
            diag += c;
            if (marker[j] != UINT32_MAX && marker[j] >= first_out) {
              coefs_[marker[j]] += c;
            } else {
              marker[j] = out;
              cols_[out] = j;
              coefs_[out++] = c;
            }
          }
          diag_[s] = diag;
        }
        row_begin_[n] = out;
        cols_.resize(out);
        coefs_.resize(out);
      } else {
#pragma omp for schedule(static)
        for (size_t s = 0; s < n; ++s) {
          const uint32_t begin = raw_begin_[s], end = raw_begin_[s + 1];
          double diag = 0.0;
          uint32_t out = begin;
          for (uint32_t e = begin; e < end; ++e) {
            const uint32_t j = raw_cols_[e];
            const double c = raw_coefs_[e];
            diag += c;
            if (marker[j] != UINT32_MAX && marker[j] >= begin) {
              raw_coefs_[marker[j]] += c;
            } else {
              marker[j] = out;
              raw_cols_[out] = j;
              raw_coefs_[out++] = c;
            }
          }
          diag_[s] = diag;
          merged_count_[s] = out - begin;
        }
#pragma omp single
        {
          uint32_t total = 0;
          for (size_t s = 0; s < n; ++s) {
            row_begin_[s] = total;
            total += merged_count_[s];
          }
          row_begin_[n] = total;
          cols_.resize(total);
          coefs_.resize(total);
        }
#pragma omp for schedule(static)
        for (size_t s = 0; s < n; ++s) {
          const uint32_t from = raw_begin_[s], to = row_begin_[s];
          std::copy(raw_cols_.begin() + from, raw_cols_.begin() + from + merged_count_[s],
                    cols_.begin() + to);
          std::copy(raw_coefs_.begin() + from, raw_coefs_.begin() + from + merged_count_[s],
                    coefs_.begin() + to);
        }
      }
    }
  }
  if (!valid) throw std::invalid_argument("SphImplicitGoalSolver::setSystem: spring to no particle");
  // Rigid motions of the whole solid, about its centre of mass.
  rigid_projection_ = n > 0;
  total_mass_ = 0.0;
  Vec3 centre = Vec3::Zero();
  for (size_t s = 0; s < n; ++s) {
    total_mass_ += masses[s];
    centre += masses[s] * positions[s];
  }
  if (total_mass_ > 0.0) centre /= total_mass_;
  arms_.resize(n);
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (size_t s = 0; s < n; ++s) {
    const Vec3 a = positions[s] - centre;
    arms_[s] = a;
    inertia += masses[s] * (a.squaredNorm() * Eigen::Matrix3d::Identity() - a * a.transpose());
  }
  // In 2D (all z = 0) the inertia is regular too (I_xx = sum m y^2, I_yy = sum m x^2); a collinear or
  // single-particle solid has no rotation to remove.
  const double size = inertia.trace();
  rotation_ = size > 0.0 && inertia.determinant() > 1e-12 * size * size * size;
  inertia_inverse_ = rotation_ ? Eigen::Matrix3d(inertia.inverse()) : Eigen::Matrix3d::Zero();
}

void SphImplicitGoalSolver::setConstraints(const std::vector<SphVelocityConstraint>& constraints) {
  for (const SphVelocityConstraint& c : constraints)
    if (c.particle >= masses_.size() || c.count < 0 || c.count > 3)
      throw std::invalid_argument("SphImplicitGoalSolver::setConstraints: bad constraint");
  constraints_ = constraints;
}

void SphImplicitGoalSolver::filter(std::vector<Vec3>& a) const {
  for (const SphVelocityConstraint& c : constraints_) {
    Vec3& x = a[c.particle];
    for (int k = 0; k < c.count; ++k) x -= c.normals[k].dot(x) * c.normals[k];
  }
}

void SphImplicitGoalSolver::rightHandSide(const std::vector<Vec3>& f0, const std::vector<Vec3>& v, double dt,
                                          std::vector<Vec3>& b) const {
  applyStiffness(v, b);
  for (size_t s = 0; s < b.size(); ++s) b[s] = dt * (f0[s] - dt * b[s]);
}

void SphImplicitGoalSolver::constraintImpulses(const std::vector<Vec3>& f0, const std::vector<Vec3>& v,
                                               double dt, const std::vector<Vec3>& dv,
                                               std::vector<Vec3>& impulses) const {
  std::vector<Vec3>& b = z_;
  rightHandSide(f0, v, dt, b);
  std::vector<Vec3>& a = q_;
  applyStiffness(dv, a);
  impulses.clear();
  for (const SphVelocityConstraint& c : constraints_) {
    const size_t s = c.particle;
    impulses.push_back(masses_[s] * dv[s] + dt * dt * a[s] - b[s]);
  }
}

void SphImplicitGoalSolver::applyLaplacian(const std::vector<Vec3>& u, std::vector<Vec3>& y) const {
  const size_t n = masses_.size();
  y.resize(n);
  const auto row = [&](size_t s) {
    double x = diag_[s] * u[s].x(), yy = diag_[s] * u[s].y(), z = diag_[s] * u[s].z();
    for (uint32_t e = row_begin_[s]; e < row_begin_[s + 1]; ++e) {
      const Vec3& o = u[cols_[e]];
      const double c = coefs_[e];
      x -= c * o.x();
      yy -= c * o.y();
      z -= c * o.z();
    }
    y[s] = Vec3(x, yy, z);
  };
  const int threads = n >= 4096 ? threads_ : 1;
  if (threads == 1) {
    for (size_t s = 0; s < n; ++s) row(s);
    return;
  }
#pragma omp parallel for num_threads(threads) schedule(static)
  for (size_t s = 0; s < n; ++s) row(s);
}

void SphImplicitGoalSolver::removeRigidMotion(std::vector<Vec3>& u) const {
  if (!rigid_projection_ || total_mass_ <= 0.0) return;
  Vec3 momentum = Vec3::Zero(), angular = Vec3::Zero();
  for (size_t s = 0; s < u.size(); ++s) {
    momentum += masses_[s] * u[s];
    angular += masses_[s] * arms_[s].cross(u[s]);
  }
  const Vec3 velocity = momentum / total_mass_, spin = inertia_inverse_ * angular;
  for (size_t s = 0; s < u.size(); ++s) u[s] -= velocity + spin.cross(arms_[s]);
}

void SphImplicitGoalSolver::removeNetForceAndTorque(std::vector<Vec3>& f) const {
  if (total_mass_ <= 0.0) return;
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  for (size_t s = 0; s < f.size(); ++s) {
    force += f[s];
    torque += arms_[s].cross(f[s]);
  }
  const Vec3 acceleration = force / total_mass_, angular = inertia_inverse_ * torque;
  for (size_t s = 0; s < f.size(); ++s) f[s] -= masses_[s] * (acceleration + angular.cross(arms_[s]));
}

void SphImplicitGoalSolver::applyStiffness(const std::vector<Vec3>& u, std::vector<Vec3>& y) const {
  t_ = u;
  removeRigidMotion(t_);
  applyLaplacian(t_, y);
  removeNetForceAndTorque(y);
}

SphImplicitGoalResult SphImplicitGoalSolver::solve(const std::vector<Vec3>& f0, const std::vector<Vec3>& v,
                                                   double dt, double tolerance, int max_iterations,
                                                   std::vector<Vec3>& dv) const {
  const size_t n = masses_.size();
  if (f0.size() != n || v.size() != n)
    throw std::invalid_argument("SphImplicitGoalSolver::solve: arrays differ in size");
  if (dv.size() != n) dv.assign(n, Vec3::Zero());
  const double dt2 = dt * dt;
  // Prescribed components set, free ones kept (filtered CG: the iterates change only free components).
  for (const SphVelocityConstraint& c : constraints_) {
    Vec3& x = dv[c.particle];
    for (int k = 0; k < c.count; ++k) x += (c.values[k] - c.normals[k].dot(x)) * c.normals[k];
  }
  // A x = M x + dt^2 K x, filtered.
  const auto apply = [&](const std::vector<Vec3>& x, std::vector<Vec3>& ax) {
    applyStiffness(x, ax);
    for (size_t s = 0; s < n; ++s) ax[s] = masses_[s] * x[s] + dt2 * ax[s];
    filter(ax);
  };
  std::vector<Vec3>& r = r_;
  rightHandSide(f0, v, dt, r);
  filter(r);
  std::vector<Vec3>& z = z_;
  z.resize(n);
  double b_norm2 = 0.0;
  for (size_t s = 0; s < n; ++s) b_norm2 += r[s].squaredNorm() / (masses_[s] + dt2 * diag_[s]);
  std::vector<Vec3>& q = q_;
  apply(dv, q);
  for (size_t s = 0; s < n; ++s) r[s] -= q[s];
  double rz = 0.0;
  for (size_t s = 0; s < n; ++s) {
    z[s] = r[s] / (masses_[s] + dt2 * diag_[s]);
    rz += r[s].dot(z[s]);
  }
  SphImplicitGoalResult result;
  // Scale of the residual: the right-hand side, or (no free forcing, e.g. only prescribed components) the
  // initial residual.
  const double scale2 = b_norm2 > 0.0 ? b_norm2 : rz;
  if (!(scale2 > 0.0)) {
    result.converged = true;
    return result;
  }
  const double target2 = tolerance * tolerance * scale2;
  std::vector<Vec3>& p = p_;
  p = z;
  int it = 0;
  while (rz > target2 && it < max_iterations) {
    apply(p, q);
    const double pq = dotOf(p, q);
    if (!(pq > 0.0)) break;
    const double alpha = rz / pq;
    double rz_next = 0.0;
    for (size_t s = 0; s < n; ++s) {
      dv[s] += alpha * p[s];
      r[s] -= alpha * q[s];
      z[s] = r[s] / (masses_[s] + dt2 * diag_[s]);
      rz_next += r[s].dot(z[s]);
    }
    const double beta = rz_next / rz;
    rz = rz_next;
    for (size_t s = 0; s < n; ++s) p[s] = z[s] + beta * p[s];
    ++it;
  }
  result.iterations = it;
  result.relative_residual = std::sqrt(std::max(rz, 0.0) / scale2);
  result.converged = rz <= target2;
  return result;
}

// --- SphImplicitGoalCoupling ---

void SphImplicitGoalCoupling::submit(SphImplicitGoalBlock block) {
  if (!block.solver || !block.particles || !block.f0 || !block.velocity || !block.dv || !block.force)
    throw std::invalid_argument("SphImplicitGoalCoupling::submit: block with a missing array");
  const size_t n = block.solver->size();
  if (block.particles->size() != n || block.f0->size() != n || block.velocity->size() != n)
    throw std::invalid_argument(
        "SphImplicitGoalCoupling::submit: block arrays differ in size from its system");
  if (!(block.dt > 0.0) || !std::isfinite(block.dt))
    throw std::invalid_argument("SphImplicitGoalCoupling::submit: dt must be finite and > 0, got " +
                                std::to_string(block.dt));
  if (block.dv->size() != n) block.dv->assign(n, Vec3::Zero());
  block.force->resize(n);
  const int32_t index = static_cast<int32_t>(blocks_.size());
  for (size_t s = 0; s < n; ++s) {
    const uint32_t i = (*block.particles)[s];
    if (i >= owner_.size()) {
      owner_.resize(size_t(i) + 1, -1);
      local_.resize(size_t(i) + 1, 0);
    }
    if (owner_[i] >= 0)
      throw std::logic_error("SphImplicitGoalCoupling::submit: particle " + std::to_string(i) +
                             " is in a block that was not solved yet (the contact term must evaluate after "
                             "the solids it couples, once per evaluation)");
    owner_[i] = index;
    local_[i] = uint32_t(s);
  }
  blocks_.push_back(std::move(block));
}

double SphImplicitGoalCoupling::contactForce(const Contact& c) const {
  const SphImplicitGoalBlock &a = blocks_[c.a], &b = blocks_[c.b];
  const Vec3 vi = (*a.velocity)[c.sa] + (*a.dv)[c.sa], vj = (*b.velocity)[c.sb] + (*b.dv)[c.sb];
  return c.force - c.rate * c.normal.dot(vj - vi);
}

SphImplicitGoalResult SphImplicitGoalCoupling::solveAlone(SphImplicitGoalBlock& block) {
  SphImplicitGoalSolver& solver = *block.solver;
  std::vector<SphVelocityConstraint> constraints = solver.constraints();
  SphImplicitGoalResult result;
  for (int round = 0; round < kReleaseRounds; ++round) {
    solver.setConstraints(constraints);
    const SphImplicitGoalResult r =
        solver.solve(*block.f0, *block.velocity, block.dt, block.tolerance, block.max_iterations, *block.dv);
    result.iterations += r.iterations;
    result.relative_residual = r.relative_residual;
    result.converged = r.converged;
    if (constraints.empty() || round == kReleaseRounds - 1) break;
    // Planes that would have to pull (impulse . n < 0) let go, and the step is solved again.
    solver.constraintImpulses(*block.f0, *block.velocity, block.dt, *block.dv, impulses_);
    if (!releasePullingConstraints(constraints, impulses_)) break;
  }
  // F = M dv / dt. Without constraints its net force and torque are removed (exact for the exact solution:
  // f0 has none (8.32)-(8.33), the stiffness K none by construction), so momentum does not depend on the CG
  // tolerance; plane and anchor constraints exert external impulses.
  std::vector<Vec3>& force = *block.force;
  const std::vector<double>& masses = solver.masses();
  for (size_t s = 0; s < force.size(); ++s) force[s] = (masses[s] / block.dt) * (*block.dv)[s];
  bool constrained = false;
  for (const SphVelocityConstraint& c : solver.constraints()) constrained = constrained || c.count > 0;
  if (!constrained) solver.removeNetForceAndTorque(force);
  return result;
}

void SphImplicitGoalCoupling::applyGroup(const std::vector<uint32_t>& group,
                                         const std::vector<uint32_t>& contacts, Field in, Field out,
                                         bool filter) {
  for (uint32_t b : group) {
    const SphImplicitGoalBlock& block = blocks_[b];
    Work& w = work_[b];
    const std::vector<Vec3>& x = w.*in;
    std::vector<Vec3>& y = w.*out;
    block.solver->applyStiffness(x, y);
    const std::vector<double>& masses = block.solver->masses();
    const double dt2 = block.dt * block.dt;
    for (size_t s = 0; s < y.size(); ++s) y[s] = masses[s] * x[s] + dt2 * y[s];
  }
  for (uint32_t k : contacts) {
    const Contact& c = contacts_[k];
    if (!c.active) continue;
    Work &wa = work_[c.a], &wb = work_[c.b];
    const Vec3 f = (c.coefficient * c.normal.dot((wb.*in)[c.sb] - (wa.*in)[c.sa])) * c.normal;
    (wb.*out)[c.sb] += f;
    (wa.*out)[c.sa] -= f;
  }
  if (filter)
    for (uint32_t b : group) blocks_[b].solver->filter(work_[b].*out);
}

void SphImplicitGoalCoupling::precondition(uint32_t b) {
  Work& w = work_[b];
  for (size_t s = 0; s < w.r.size(); ++s) {
    const int32_t k = w.contact_block[s];
    w.z[s] = k < 0 ? Vec3(w.scalar[s] * w.r[s]) : Vec3(w.contact_blocks[k] * w.r[s]);
  }
  blocks_[b].solver->filter(w.z);
}

void SphImplicitGoalCoupling::prepareGroup(const std::vector<uint32_t>& group,
                                           const std::vector<uint32_t>& contacts) {
  for (uint32_t b : group) {
    const SphImplicitGoalBlock& block = blocks_[b];
    Work& w = work_[b];
    const size_t n = block.solver->size();
    w.b = w.b0;
    w.r.resize(n);
    w.z.resize(n);
    w.p.resize(n);
    w.q.resize(n);
    w.t.resize(n);
    w.scalar.resize(n);
    w.contact_block.assign(n, -1);
    w.contact_blocks.clear();
    const std::vector<double>& masses = block.solver->masses();
    const std::vector<double>& diag = block.solver->laplacianDiagonal();
    const double dt2 = block.dt * block.dt;
    for (size_t s = 0; s < n; ++s) w.scalar[s] = masses[s] + dt2 * diag[s];
  }
  const auto addBlock = [&](Work& w, uint32_t s, const Eigen::Matrix3d& nn) {
    int32_t& k = w.contact_block[s];
    if (k < 0) {
      k = int32_t(w.contact_blocks.size());
      w.contact_blocks.push_back(w.scalar[s] * Eigen::Matrix3d::Identity());
    }
    w.contact_blocks[k] += nn;
  };
  for (uint32_t k : contacts) {
    const Contact& c = contacts_[k];
    if (!c.active) continue;
    const SphImplicitGoalBlock &a = blocks_[c.a], &b = blocks_[c.b];
    const double approach = c.normal.dot((*b.velocity)[c.sb] - (*a.velocity)[c.sa]);
    const Vec3 f = (a.dt * (c.force - c.rate * approach)) * c.normal;
    work_[c.b].b[c.sb] += f;
    work_[c.a].b[c.sa] -= f;
    const Eigen::Matrix3d nn = c.coefficient * c.normal * c.normal.transpose();
    addBlock(work_[c.b], c.sb, nn);
    addBlock(work_[c.a], c.sa, nn);
  }
  for (uint32_t b : group) {
    Work& w = work_[b];
    for (double& d : w.scalar) d = 1.0 / d;
    for (Eigen::Matrix3d& d : w.contact_blocks) d = d.inverse().eval();
  }
}

SphImplicitGoalResult SphImplicitGoalCoupling::conjugateGradients(const std::vector<uint32_t>& group,
                                                                  const std::vector<uint32_t>& contacts,
                                                                  double tolerance, int max_iterations) {
  // Prescribed components set, free ones kept (filtered CG: the iterates change only free components).
  for (uint32_t b : group) {
    std::vector<Vec3>& dv = *blocks_[b].dv;
    for (const SphVelocityConstraint& c : blocks_[b].solver->constraints()) {
      Vec3& x = dv[c.particle];
      for (int k = 0; k < c.count; ++k) x += (c.values[k] - c.normals[k].dot(x)) * c.normals[k];
    }
    work_[b].t = dv;
  }
  applyGroup(group, contacts, &Work::t, &Work::q, true);
  double scale2 = 0.0, rz = 0.0;
  for (uint32_t b : group) {
    Work& w = work_[b];
    w.r = w.b;
    blocks_[b].solver->filter(w.r);
    precondition(b);  // z = D^-1 b: the scale of the residual
    scale2 += dotOf(w.r, w.z);
    for (size_t s = 0; s < w.r.size(); ++s) w.r[s] -= w.q[s];
    precondition(b);
    rz += dotOf(w.r, w.z);
  }
  SphImplicitGoalResult result;
  if (!(scale2 > 0.0)) scale2 = rz;  // no free forcing: the initial residual
  if (!(scale2 > 0.0)) {
    result.converged = true;
    return result;
  }
  const double target2 = tolerance * tolerance * scale2;
  for (uint32_t b : group) work_[b].p = work_[b].z;
  int it = 0;
  while (rz > target2 && it < max_iterations) {
    applyGroup(group, contacts, &Work::p, &Work::q, true);
    double pq = 0.0;
    for (uint32_t b : group) pq += dotOf(work_[b].p, work_[b].q);
    if (!(pq > 0.0)) break;
    const double alpha = rz / pq;
    double rz_next = 0.0;
    for (uint32_t b : group) {
      Work& w = work_[b];
      std::vector<Vec3>& dv = *blocks_[b].dv;
      for (size_t s = 0; s < dv.size(); ++s) {
        dv[s] += alpha * w.p[s];
        w.r[s] -= alpha * w.q[s];
      }
      precondition(b);
      rz_next += dotOf(w.r, w.z);
    }
    const double beta = rz_next / rz;
    rz = rz_next;
    for (uint32_t b : group) {
      Work& w = work_[b];
      for (size_t s = 0; s < w.p.size(); ++s) w.p[s] = w.z[s] + beta * w.p[s];
    }
    ++it;
  }
  result.iterations = it;
  result.relative_residual = std::sqrt(std::max(rz, 0.0) / scale2);
  result.converged = rz <= target2;
  return result;
}

SphImplicitGoalResult SphImplicitGoalCoupling::solveGroup(const std::vector<uint32_t>& group,
                                                          const std::vector<uint32_t>& contacts,
                                                          SphImplicitCouplingStats& stats) {
  double tolerance = 1.0;
  int max_iterations = 0;
  for (uint32_t b : group) {
    const SphImplicitGoalBlock& block = blocks_[b];
    tolerance = std::min(tolerance, block.tolerance);
    max_iterations = std::max(max_iterations, block.max_iterations);
    block.solver->rightHandSide(*block.f0, *block.velocity, block.dt, work_[b].b0);
  }
  std::vector<std::vector<SphVelocityConstraint>> constraints(group.size());
  for (size_t g = 0; g < group.size(); ++g) constraints[g] = blocks_[group[g]].solver->constraints();
  SphImplicitGoalResult result;
  for (int round = 0; round < kReleaseRounds; ++round) {
    for (size_t g = 0; g < group.size(); ++g) blocks_[group[g]].solver->setConstraints(constraints[g]);
    prepareGroup(group, contacts);
    const SphImplicitGoalResult r = conjugateGradients(group, contacts, tolerance, max_iterations);
    result.iterations += r.iterations;
    result.relative_residual = r.relative_residual;
    result.converged = r.converged;
    if (round == kReleaseRounds - 1) break;
    // Contact springs that would pull (8.37) and planes that would pull let go; the group is solved again.
    bool released = false;
    for (uint32_t k : contacts) {
      Contact& c = contacts_[k];
      if (c.active && contactForce(c) < 0.0) {
        c.active = false;
        released = true;
        ++stats.released_contacts;
      }
    }
    for (uint32_t b : group) work_[b].t = *blocks_[b].dv;
    applyGroup(group, contacts, &Work::t, &Work::q, false);  // A dv - b: the constraint impulses
    for (size_t g = 0; g < group.size(); ++g) {
      if (constraints[g].empty()) continue;
      const Work& w = work_[group[g]];
      impulses_.clear();
      for (const SphVelocityConstraint& c : constraints[g])
        impulses_.push_back(w.q[c.particle] - w.b[c.particle]);
      released = releasePullingConstraints(constraints[g], impulses_) || released;
    }
    if (!released) break;
  }
  // Forces at the end of the step: f0 - dt K (v + dv) + contact forces, plus the constraints' impulses.
  for (uint32_t b : group) {
    const SphImplicitGoalBlock& block = blocks_[b];
    Work& w = work_[b];
    const std::vector<Vec3>&v = *block.velocity, &dv = *block.dv;
    w.t.resize(v.size());
    for (size_t s = 0; s < v.size(); ++s) w.t[s] = v[s] + dv[s];
    block.solver->applyStiffness(w.t, w.q);
    std::vector<Vec3>& force = *block.force;
    for (size_t s = 0; s < v.size(); ++s) force[s] = (*block.f0)[s] - block.dt * w.q[s];
  }
  for (uint32_t k : contacts) {
    const Contact& c = contacts_[k];
    if (!c.active) continue;
    const double normal = contactForce(c);
    if (!(normal > 0.0)) continue;  // (8.37): never pulls
    ++stats.active_contacts;
    const Vec3 f = normal * c.normal;
    (*blocks_[c.b].force)[c.sb] += f;
    (*blocks_[c.a].force)[c.sa] -= f;
  }
  for (uint32_t b : group) {
    const SphImplicitGoalBlock& block = blocks_[b];
    const std::vector<double>& masses = block.solver->masses();
    std::vector<Vec3>& force = *block.force;
    for (const SphVelocityConstraint& c : block.solver->constraints()) {
      const size_t s = c.particle;
      const Vec3 target = (masses[s] / block.dt) * (*block.dv)[s];
      for (int k = 0; k < c.count; ++k) force[s] += c.normals[k].dot(target - force[s]) * c.normals[k];
    }
  }
  stats.iterations += result.iterations;
  return result;
}

SphImplicitCouplingStats SphImplicitGoalCoupling::solve(const std::vector<SphContactSpring>& contacts,
                                                        std::vector<Vec3>& forces) {
  SphImplicitCouplingStats stats;
  const size_t nb = blocks_.size();
  for (const SphImplicitGoalBlock& block : blocks_) {
    if (block.dt != blocks_[0].dt)
      throw std::invalid_argument("SphImplicitGoalCoupling::solve: blocks of different dt");
    for (uint32_t i : *block.particles)
      if (i >= forces.size())
        throw std::invalid_argument("SphImplicitGoalCoupling::solve: forces has no entry for particle " +
                                    std::to_string(i));
  }
  // Contacts with local indices; groups of blocks joined by contacts (union-find).
  contacts_.clear();
  parent_.resize(nb);
  std::iota(parent_.begin(), parent_.end(), 0u);
  for (const SphContactSpring& spring : contacts) {
    const int32_t a = blockOf(spring.first), b = blockOf(spring.second);
    if (a < 0 || b < 0)
      throw std::invalid_argument("SphImplicitGoalCoupling::solve: contact between particles " +
                                  std::to_string(spring.first) + " and " + std::to_string(spring.second) +
                                  " has an end outside the pending blocks");
    if (!(std::isfinite(spring.force) && spring.stiffness >= 0.0 && spring.damping >= 0.0 &&
          std::isfinite(spring.stiffness + spring.damping) && spring.normal.allFinite()))
      throw std::invalid_argument("SphImplicitGoalCoupling::solve: contact between particles " +
                                  std::to_string(spring.first) + " and " + std::to_string(spring.second) +
                                  ": force, normal must be finite, stiffness and damping finite and >= 0");
    const double dt = blocks_[a].dt, rate = dt * spring.stiffness + spring.damping;
    contacts_.push_back({uint32_t(a), local_[spring.first], uint32_t(b), local_[spring.second], spring.normal,
                         spring.force, dt * rate, rate, true});
    parent_[findRoot(parent_, uint32_t(a))] = findRoot(parent_, uint32_t(b));
  }
  std::vector<std::vector<uint32_t>> groups(nb), group_contacts(nb);
  for (uint32_t b = 0; b < nb; ++b) groups[findRoot(parent_, b)].push_back(b);
  for (uint32_t k = 0; k < contacts_.size(); ++k)
    group_contacts[findRoot(parent_, contacts_[k].a)].push_back(k);
  work_.resize(nb);
  std::vector<SphImplicitGoalResult> results(nb);
  for (uint32_t root = 0; root < nb; ++root) {
    const std::vector<uint32_t>& group = groups[root];
    if (group.empty()) continue;
    ++stats.groups;
    if (group_contacts[root].empty()) {
      for (uint32_t b : group) {  // one block: no contacts join it
        results[b] = solveAlone(blocks_[b]);
        stats.iterations += results[b].iterations;
      }
      continue;
    }
    stats.coupled_solids += group.size();
    const SphImplicitGoalResult r = solveGroup(group, group_contacts[root], stats);
    for (uint32_t b : group) results[b] = r;
  }
  // Forces out, blocks finished and cleared.
  for (uint32_t b = 0; b < nb; ++b) {
    const SphImplicitGoalBlock& block = blocks_[b];
    const std::vector<uint32_t>& particles = *block.particles;
    for (size_t s = 0; s < particles.size(); ++s) {
      forces[particles[s]] += (*block.force)[s];
      owner_[particles[s]] = -1;
    }
  }
  std::vector<SphImplicitGoalBlock> done;
  done.swap(blocks_);
  for (uint32_t b = 0; b < nb; ++b)
    if (done[b].finish) done[b].finish(results[b]);
  return stats;
}

}  // namespace rc
