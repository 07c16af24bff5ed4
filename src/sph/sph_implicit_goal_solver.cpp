#include "sph/sph_implicit_goal_solver.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include <Eigen/Dense>

namespace rc {

namespace {

double dotOf(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double s = 0.0;
  for (size_t k = 0; k < a.size(); ++k) s += a[k].dot(b[k]);
  return s;
}

}  // namespace

void SphImplicitGoalSolver::setSystem(const std::vector<Vec3>& positions, const std::vector<double>& masses,
                                      const std::vector<std::vector<SphGoalSpring>>& springs) {
  const size_t n = masses.size();
  if (positions.size() != n || springs.size() != n)
    throw std::invalid_argument("SphImplicitGoalSolver::setSystem: arrays differ in size");
  masses_ = masses;
  constraints_.clear();
  // Symmetric rows: the spring (s, j) enters row s and row j.
  row_begin_.assign(n + 1, 0);
  for (size_t s = 0; s < n; ++s)
    for (const SphGoalSpring& e : springs[s]) {
      if (e.other >= n)
        throw std::invalid_argument("SphImplicitGoalSolver::setSystem: spring to no particle");
      ++row_begin_[s + 1];
      ++row_begin_[e.other + 1];
    }
  for (size_t s = 0; s < n; ++s) row_begin_[s + 1] += row_begin_[s];
  cols_.resize(row_begin_[n]);
  coefs_.resize(row_begin_[n]);
  std::vector<uint32_t> next(row_begin_.begin(), row_begin_.end() - 1);
  diag_.assign(n, 0.0);
  for (size_t s = 0; s < n; ++s)
    for (const SphGoalSpring& e : springs[s]) {
      cols_[next[s]] = e.other;
      coefs_[next[s]++] = e.stiffness;
      cols_[next[e.other]] = uint32_t(s);
      coefs_[next[e.other]++] = e.stiffness;
      diag_[s] += e.stiffness;
      diag_[e.other] += e.stiffness;
    }
  // Merge the entries of a pair that both neighbourhoods hold (most pairs): half the work per product.
  marker_.assign(n, UINT32_MAX);
  uint32_t out = 0;
  for (size_t s = 0; s < n; ++s) {
    const uint32_t begin = row_begin_[s], end = row_begin_[s + 1];
    row_begin_[s] = out;
    const uint32_t first = out;
    for (uint32_t e = begin; e < end; ++e) {
      const uint32_t j = cols_[e];
      if (marker_[j] != UINT32_MAX && marker_[j] >= first) {
        coefs_[marker_[j]] += coefs_[e];
      } else {
        marker_[j] = out;
        cols_[out] = j;
        coefs_[out++] = coefs_[e];
      }
    }
  }
  row_begin_[n] = out;
  cols_.resize(out);
  coefs_.resize(out);
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
  for (size_t s = 0; s < n; ++s) {
    double x = diag_[s] * u[s].x(), yy = diag_[s] * u[s].y(), z = diag_[s] * u[s].z();
    for (uint32_t e = row_begin_[s]; e < row_begin_[s + 1]; ++e) {
      const Vec3& o = u[cols_[e]];
      const double c = coefs_[e];
      x -= c * o.x();
      yy -= c * o.y();
      z -= c * o.z();
    }
    y[s] = Vec3(x, yy, z);
  }
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

}  // namespace rc
