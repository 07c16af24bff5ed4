#include "relaxed_connectivity/fem/fem_corotational_static.h"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace rc {
namespace {

// Relative accuracy of each Newton step's linear solve (inexact Newton).
constexpr double kNewtonForcing = 1e-3;

// GMRES on A x = b from x = 0 with right preconditioning (A M^-1 y = b, x = M^-1 y), at most `iterations`
// (no restart), until |b - A x| <= tolerance |b|.
template <class Apply, class Precondition>
Eigen::VectorXd preconditionedGmres(Apply&& apply, Precondition&& precondition, const Eigen::VectorXd& b,
                                    double tolerance, int iterations) {
  const double beta = b.norm();
  if (beta == 0.0) return Eigen::VectorXd::Zero(b.size());
  std::vector<Eigen::VectorXd> basis = {b / beta}, preconditioned;
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(iterations + 1, iterations);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(iterations + 1), cs(iterations), sn(iterations);
  g[0] = beta;
  int k = 0;
  for (;; ++k) {
    preconditioned.push_back(precondition(basis[size_t(k)]));
    Eigen::VectorXd w = apply(preconditioned.back());
    for (int i = 0; i <= k; ++i) {  // modified Gram-Schmidt
      h(i, k) = w.dot(basis[size_t(i)]);
      w -= h(i, k) * basis[size_t(i)];
    }
    const double w_norm = w.norm();
    h(k + 1, k) = w_norm;
    for (int i = 0; i < k; ++i) {  // earlier Givens rotations
      const double t = cs[i] * h(i, k) + sn[i] * h(i + 1, k);
      h(i + 1, k) = -sn[i] * h(i, k) + cs[i] * h(i + 1, k);
      h(i, k) = t;
    }
    const double r = std::hypot(h(k, k), h(k + 1, k));
    cs[k] = h(k, k) / r;
    sn[k] = h(k + 1, k) / r;
    h(k, k) = r;
    h(k + 1, k) = 0.0;
    g[k + 1] = -sn[k] * g[k];
    g[k] = cs[k] * g[k];
    if (std::abs(g[k + 1]) <= tolerance * beta || w_norm == 0.0 || k + 1 == iterations) {
      ++k;
      break;
    }
    basis.push_back(w / w_norm);
  }
  // y from the triangular system, x = sum_i y_i M^-1 v_i.
  const Eigen::VectorXd y = h.topLeftCorner(k, k).triangularView<Eigen::Upper>().solve(g.head(k));
  Eigen::VectorXd x = Eigen::VectorXd::Zero(b.size());
  for (int i = 0; i < k; ++i) x += y[i] * preconditioned[size_t(i)];
  return x;
}

}  // namespace

CorotationalStaticResult solveCorotationalStatic(LinearElasticModel model, const Eigen::VectorXd& forces,
                                                 const std::vector<DisplacementConstraint>& constraints,
                                                 const FemStaticOptions& options) {
  if (options.load_steps < 1 || options.max_iterations < 1 || !(options.tolerance > 0.0))
    throw std::invalid_argument(
        "solveCorotationalStatic: load_steps, max_iterations and tolerance must be positive");
  const int dofs = model.numDofs();
  if (forces.size() != dofs) throw std::invalid_argument("solveCorotationalStatic: wrong force vector size");
  std::vector<char> held(size_t(dofs), 0);
  Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(dofs);
  for (const DisplacementConstraint& c : constraints)
    for (int k = 0; k < 3; ++k)
      if (c.held[size_t(k)]) held[size_t(3 * c.node + k)] = 1, prescribed[3 * c.node + k] = c.displacement[k];

  WarpedDynamics body(std::move(model));  // its warping: R_e, f(x) and K_w at given positions
  const Eigen::VectorXd rest = body.restPositions();
  Eigen::VectorXd x = rest, r(dofs), trial, trial_r(dofs);
  // f(x) + lambda F on the free dofs; returns its norm and the scale of the convergence test.
  double scale = 0.0, lambda = 0.0;
  auto residual = [&](const Eigen::VectorXd& at, Eigen::VectorXd& out) {
    body.setPositions(at);
    body.updateWarping();
    out = body.elasticForces() + lambda * forces;
    double held_force = 0.0;
    for (int d = 0; d < dofs; ++d)
      if (held[size_t(d)]) held_force += body.elasticForces()[d] * body.elasticForces()[d], out[d] = 0.0;
    scale = std::max({lambda * forces.norm(), std::sqrt(held_force), 1e-300});
    return out.norm();
  };
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  bool analysed = false;
  CorotationalStaticResult result;
  for (int step = 1; step <= options.load_steps; ++step) {
    lambda = double(step) / options.load_steps;
    for (int d = 0; d < dofs; ++d)
      if (held[size_t(d)]) x[d] = rest[d] + lambda * prescribed[d];
    double norm = residual(x, r);
    for (int iteration = 0; norm > options.tolerance * scale; ++iteration) {
      if (iteration == options.max_iterations || !std::isfinite(norm))
        throw std::runtime_error("static (corotational): load step " + std::to_string(step) + " of " +
                                 std::to_string(options.load_steps) + " not in equilibrium after " +
                                 std::to_string(iteration) + " iterations (residual " +
                                 std::to_string(norm / scale) +
                                 " of the load); raise static.load_steps or static.max_iterations");
      // K_w with the held dofs' rows and columns those of the identity.
      Eigen::SparseMatrix<double> k = body.warpedStiffness();
      for (int column = 0; column < dofs; ++column)
        for (Eigen::SparseMatrix<double>::InnerIterator it(k, column); it; ++it)
          if (held[size_t(column)] || held[size_t(it.row())]) it.valueRef() = it.row() == column ? 1.0 : 0.0;
      if (!analysed) ldlt.analyzePattern(k), analysed = true;
      ldlt.factorize(k);
      if (ldlt.info() != Eigen::Success)
        throw std::runtime_error("static (corotational): the warped stiffness is singular at load step " +
                                 std::to_string(step) + " (do the held regions fix every rigid motion?)");
      // Newton: J dx = -r with J = d(f(x) + lambda F)/dx (rotations included) by finite differences inside
      // GMRES, preconditioned by -K_w^-1 (the Jacobian without the rotations' derivatives).
      const Eigen::VectorXd base = x, base_r = r;
      auto jacobianTimes = [&](const Eigen::VectorXd& v) {
        const double v_norm = v.norm();
        if (v_norm == 0.0) return Eigen::VectorXd(Eigen::VectorXd::Zero(dofs));
        const double epsilon = 1e-7 * (1.0 + base.norm() / std::sqrt(double(dofs))) / v_norm;
        Eigen::VectorXd shifted_r(dofs);
        residual(base + epsilon * v, shifted_r);
        return Eigen::VectorXd((shifted_r - base_r) / epsilon);
      };
      auto precondition = [&](const Eigen::VectorXd& v) { return Eigen::VectorXd(-ldlt.solve(v)); };
      const Eigen::VectorXd dx =
          preconditionedGmres(jacobianTimes, precondition, -base_r, kNewtonForcing, 40);
      // Merit: the potential 1/2 sum_e u_e^T K_e u_e - lambda F . (x - X) (the residual's norm is dominated
      // by the stiff stretching of slender parts and would reject good Newton steps). A step is taken when
      // it lowers the potential or the residual, else halved.
      residual(base, r);  // back at x (scale and rotations)
      const double potential = body.elasticEnergy() - lambda * forces.dot(base - rest);
      double a = 1.0, trial_norm = 0.0;
      for (int halving = 0; halving <= 8; ++halving, a *= 0.5) {
        trial = base + a * dx;
        trial_norm = residual(trial, trial_r);
        const double trial_potential = body.elasticEnergy() - lambda * forces.dot(trial - rest);
        if (trial_norm < norm || trial_potential <= potential + 1e-12 * std::abs(potential)) break;
      }
      x = trial;
      r = trial_r;
      norm = trial_norm;
      ++result.iterations;
    }
    result.residual = norm / scale;
  }
  result.displacements = x - rest;
  residual(x, r);  // the holders balance f(x) + F at the held dofs
  result.reactions = Eigen::VectorXd::Zero(dofs);
  for (int d = 0; d < dofs; ++d)
    if (held[size_t(d)]) result.reactions[d] = -(body.elasticForces()[d] + forces[d]);
  return result;
}

}  // namespace rc
