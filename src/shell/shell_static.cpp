#include "relaxed_connectivity/shell/shell_static.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/shell/shell_hessian.h"

namespace rc {

namespace {

/// The total potential E(x) - f . x.
double potential(const ShellEnergy& energy, const std::vector<Vec3>& x, const std::vector<Vec3>& f) {
  double work = 0.0;
  for (size_t i = 0; i < x.size(); ++i) work += f[i].dot(x[i]);
  return energy.evaluate(x).total() - work;
}

}  // namespace

ShellStaticResult solveShellStatic(const ShellEnergy& energy, const std::vector<ShellHeld>& held,
                                   const std::vector<ShellLoad>& loads, const Vec3& gravity,
                                   const ShellStaticOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (options.load_steps < 1 || options.max_iterations < 1 || !(options.tolerance > 0.0))
    throw std::invalid_argument("solveShellStatic: need load_steps >= 1, max_iterations >= 1, tolerance > 0");
  const ShellNodes& nodes = energy.nodes();
  const size_t n = nodes.size();
  const std::vector<uint8_t> mask = shellHeldMask(n, held);
  std::vector<Vec3> target = nodes.rest_positions;  // the held components' final positions
  for (const ShellHeld& region : held)
    for (uint32_t i : region.nodes)
      for (int d = 0; d < 3; ++d)
        if (region.components[d]) target[i][d] = nodes.rest_positions[i][d] + region.displacement[d];
  std::vector<int> free_index(3 * n, -1);  // dof -> row of the free system
  int free_count = 0;
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      if (!(mask[i] >> d & 1)) free_index[3 * i + d] = free_count++;
  if (free_count == int(3 * n))
    throw std::invalid_argument("solveShellStatic: no held component (the shell could move freely)");
  const std::vector<Vec3> f_total = shellLoadForces(energy, loads, gravity);
  double load_norm = 0.0;
  for (const Vec3& f : f_total) load_norm += f.squaredNorm();
  load_norm = std::sqrt(load_norm);
  Vec3 lo = nodes.rest_positions[0], hi = lo;
  for (const Vec3& p : nodes.rest_positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double size = std::max((hi - lo).norm(), nodes.spacing);
  // An absolute floor for load-free problems (prescribed displacements only): the elastic forces of a strain
  // of 1e-12 on every node.
  const double floor =
      1e-12 * (energy.material().stretch_stiffness * size + energy.material().bending_stiffness / size);

  ShellStaticResult result;
  std::vector<Vec3> x = nodes.rest_positions, gradient, f(n), trial(n);
  Eigen::VectorXd residual(free_count), delta(free_count);
  for (int increment = 1; increment <= options.load_steps; ++increment) {
    const double s = double(increment) / options.load_steps;
    for (size_t i = 0; i < n; ++i) {
      f[i] = s * f_total[i];
      for (int d = 0; d < 3; ++d)
        if (mask[i] >> d & 1)
          x[i][d] = nodes.rest_positions[i][d] + s * (target[i][d] - nodes.rest_positions[i][d]);
    }
    const double tolerance = std::max(options.tolerance * s * load_norm, floor);
    bool converged = false;
    for (int iteration = 0; iteration <= options.max_iterations; ++iteration) {
      energy.evaluate(x, &gradient);
      for (size_t i = 0; i < n; ++i)
        for (int d = 0; d < 3; ++d)
          if (free_index[3 * i + d] >= 0) residual[free_index[3 * i + d]] = gradient[i][d] - f[i][d];
      result.residual = residual.norm() / std::max(load_norm, 1e-300);
      if (residual.norm() <= tolerance) {
        converged = true;
        break;
      }
      if (iteration == options.max_iterations) break;
      ++result.iterations;
      ShellHessianStats stats;
      const Eigen::SparseMatrix<double> K = shellEnergyHessian(energy, x, 0.0, &stats);
      result.hessian_colors = stats.colors;
      std::vector<Eigen::Triplet<double>> triplets;
      double max_diagonal = 0.0;
      for (int k = 0; k < K.outerSize(); ++k)
        for (Eigen::SparseMatrix<double>::InnerIterator it(K, k); it; ++it) {
          const int r = free_index[it.row()], c = free_index[it.col()];
          if (r < 0 || c < 0) continue;
          triplets.emplace_back(r, c, it.value());
          if (r == c) max_diagonal = std::max(max_diagonal, it.value());
        }
      Eigen::SparseMatrix<double> A(free_count, free_count);
      A.setFromTriplets(triplets.begin(), triplets.end());
      // Newton's step on K + mu I: mu starts at 1e-12 of the largest stiffness (singular directions a load
      // does not push stay put) and grows until the step descends.
      double mu = 1e-12 * std::max(max_diagonal, 1e-300);
      bool stepped = false;
      for (int attempt = 0; attempt < 40 && !stepped; ++attempt, mu *= 10.0) {
        Eigen::SparseMatrix<double> shifted = A;
        for (int r = 0; r < free_count; ++r) shifted.coeffRef(r, r) += mu;
        Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(shifted);
        if (ldlt.info() != Eigen::Success) continue;
        delta = ldlt.solve(-residual);
        if (!delta.allFinite() || delta.dot(residual) >= 0.0) continue;
        // Backtracking on the total potential (Armijo).
        const double before = potential(energy, x, f);
        for (double alpha = 1.0; alpha > 1e-6; alpha *= 0.5) {
          trial = x;
          for (size_t i = 0; i < n; ++i)
            for (int d = 0; d < 3; ++d)
              if (free_index[3 * i + d] >= 0) trial[i][d] += alpha * delta[free_index[3 * i + d]];
          if (potential(energy, trial, f) <= before + 1e-4 * alpha * delta.dot(residual)) {
            x.swap(trial);
            stepped = true;
            break;
          }
        }
      }
      if (!stepped)
        throw std::runtime_error("solveShellStatic: increment " + std::to_string(increment) + " of " +
                                 std::to_string(options.load_steps) +
                                 ": no descending Newton step (iteration " + std::to_string(iteration + 1) +
                                 ", relative residual " + std::to_string(result.residual) +
                                 "); try more load_steps");
      double moved = 0.0;
      for (size_t i = 0; i < n; ++i) moved = std::max(moved, (x[i] - nodes.rest_positions[i]).norm());
      if (moved > 1000.0 * size)
        throw std::runtime_error("solveShellStatic: increment " + std::to_string(increment) +
                                 ": a load moves a rigid motion the held regions leave free");
    }
    if (!converged)
      throw std::runtime_error("solveShellStatic: increment " + std::to_string(increment) + " of " +
                               std::to_string(options.load_steps) + " did not converge in " +
                               std::to_string(options.max_iterations) + " iterations (relative residual " +
                               std::to_string(result.residual) + "); try more load_steps");
  }
  energy.evaluate(x, &gradient);
  result.held_reactions.assign(held.size(), Vec3::Zero());
  for (size_t k = 0; k < held.size(); ++k)
    for (uint32_t i : held[k].nodes)
      for (int d = 0; d < 3; ++d)
        if (held[k].components[d]) result.held_reactions[k][d] += gradient[i][d] - f_total[i][d];
  result.load_displacements.assign(loads.size(), Vec3::Zero());
  for (size_t k = 0; k < loads.size(); ++k) {
    for (uint32_t i : loads[k].nodes) result.load_displacements[k] += x[i] - nodes.rest_positions[i];
    result.load_displacements[k] /= double(loads[k].nodes.size());
  }
  for (size_t i = 0; i < n; ++i)
    result.max_displacement = std::max(result.max_displacement, (x[i] - nodes.rest_positions[i]).norm());
  result.positions = std::move(x);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace rc
