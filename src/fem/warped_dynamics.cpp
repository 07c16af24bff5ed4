#include "relaxed_connectivity/fem/warped_dynamics.h"

#include <Eigen/Geometry>
#include <Eigen/OrderingMethods>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "relaxed_connectivity/fem/horn_registration.h"

namespace rc {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Below this many elements the per-step loops run serially (thread start-up dominates).
constexpr int kParallelElements = 512;

// to = from; only the values when the pattern is the same (it is per body).
void copyValues(const Eigen::SparseMatrix<double>& from, Eigen::SparseMatrix<double>& to) {
  if (to.rows() != from.rows() || to.nonZeros() != from.nonZeros() || !to.isCompressed()) {
    to = from;
    return;
  }
  std::copy(from.valuePtr(), from.valuePtr() + from.nonZeros(), to.valuePtr());
}

void checkVector(const Eigen::VectorXd& v, Eigen::Index size, const char* name) {
  if (v.size() != size)
    throw std::invalid_argument(std::string("WarpedDynamics: ") + name + " has " + std::to_string(v.size()) +
                                " entries for " + std::to_string(size) + " dofs");
  if (!v.allFinite()) throw std::invalid_argument(std::string("WarpedDynamics: ") + name + " is not finite");
}

}  // namespace

WarpedDynamics::WarpedDynamics(LinearElasticModel model, const WarpedDynamicsOptions& options)
    : model_(std::move(model)), options_(options) {
  if (!(options_.time_step > 0.0) || !std::isfinite(options_.time_step))
    throw std::invalid_argument("WarpedDynamics: time_step must be positive and finite, got " +
                                std::to_string(options_.time_step));
  if (!(options_.mass_damping >= 0.0) || !(options_.stiffness_damping >= 0.0))
    throw std::invalid_argument("WarpedDynamics: Rayleigh damping coefficients must be non-negative");
  if (!options_.gravity.allFinite()) throw std::invalid_argument("WarpedDynamics: gravity is not finite");
  if (options_.ground.enabled) {
    if (!(options_.ground.normal.norm() > 0.0) || !options_.ground.normal.allFinite())
      throw std::invalid_argument("WarpedDynamics: ground normal must be non-zero and finite");
    options_.ground.normal.normalize();
    if (!(options_.ground.friction >= 0.0))
      throw std::invalid_argument("WarpedDynamics: ground friction must be non-negative");
  }
  if (!(options_.cg_tolerance > 0.0) || options_.cg_max_iterations <= 0 ||
      options_.pcg_refactor_iterations <= 0)
    throw std::invalid_argument(
        "WarpedDynamics: cg_tolerance, cg_max_iterations and pcg_refactor_iterations must be positive");
  if (options_.pcg_contact_updates < 0 || options_.pcg_extension_iterations < 0)
    throw std::invalid_argument(
        "WarpedDynamics: pcg_contact_updates and pcg_extension_iterations must be non-negative");

  const PolyhedralMesh& mesh = model_.mesh();
  const int dofs = numDofs(), num_elements = mesh.numElements();
  rest_.resize(dofs);
  masses3_.resize(dofs);
  gravity_forces_.resize(dofs);
  for (int i = 0; i < mesh.numNodes(); ++i) {
    rest_.segment<3>(3 * i) = mesh.node(i);
    masses3_.segment<3>(3 * i).setConstant(model_.lumpedMasses()[i]);  // (9.21)
    gravity_forces_.segment<3>(3 * i) = model_.lumpedMasses()[i] * options_.gravity;
  }
  positions_ = rest_;
  velocities_ = Eigen::VectorXd::Zero(dofs);
  user_forces_ = Eigen::VectorXd::Zero(dofs);
  elastic_forces_ = Eigen::VectorXd::Zero(dofs);
  previous_dv_ = Eigen::VectorXd::Zero(dofs);

  warped_stiffness_ = model_.stiffness();
  warped_stiffness_.makeCompressed();
  rotations_.assign(num_elements, Eigen::Matrix3d::Identity());
  rotation_weights_.resize(num_elements);
  element_force_offset_.resize(num_elements + 1);
  element_force_offset_[0] = 0;
  diagonal_index_.resize(dofs);
  for (int e = 0; e < num_elements; ++e) {
    const auto& ids = mesh.element(e).globalNodeIds();
    const int n = static_cast<int>(ids.size());
    max_element_nodes_ = std::max(max_element_nodes_, n);
    element_force_offset_[e + 1] = element_force_offset_[e] + 3 * n;
    Eigen::VectorXd& w = rotation_weights_[e];
    w.resize(n);
    for (int a = 0; a < n; ++a) {
      w[a] = options_.rotation_weights == WarpedDynamicsOptions::RotationWeights::kLumpedMasses
                 ? model_.lumpedMasses()[ids[a]]
                 : model_.quadrature(e).node_volume_fractions[a];
      const int diagonal = model_.blockValueIndices(e)[a * n + a];
      for (int r = 0; r < 3; ++r)
        diagonal_index_[3 * ids[a] + r] = diagonal + r * model_.columnLength(ids[a]) + r;
    }
  }
  element_forces_ = Eigen::VectorXd::Zero(element_force_offset_[num_elements]);
  rotated_block_offset_.resize(num_elements + 1);
  rotated_block_offset_[0] = 0;
  for (int e = 0; e < num_elements; ++e) {
    const int n = mesh.element(e).numNodes();
    rotated_block_offset_[e + 1] = rotated_block_offset_[e] + 9 * n * n;
  }
  rotated_blocks_ = Eigen::VectorXd::Zero(rotated_block_offset_[num_elements]);
  system_matrix_ = warped_stiffness_;
  if (options_.solver == WarpedDynamicsOptions::Solver::kCholmod ||
      options_.solver == WarpedDynamicsOptions::Solver::kCholmodPcg)
    cholmod_ = std::make_unique<CholmodSolver>();
}

void WarpedDynamics::setPositions(const Eigen::VectorXd& positions) {
  checkVector(positions, numDofs(), "positions");
  positions_ = positions;
}

void WarpedDynamics::setVelocities(const Eigen::VectorXd& velocities) {
  checkVector(velocities, numDofs(), "velocities");
  velocities_ = velocities;
}

void WarpedDynamics::setExternalForces(const Eigen::VectorXd& forces) {
  checkVector(forces, numDofs(), "external forces");
  user_forces_ = forces;
}

void WarpedDynamics::setRotations(const std::vector<Eigen::Matrix3d>& rotations) {
  if (rotations.size() != rotations_.size())
    throw std::invalid_argument("WarpedDynamics: " + std::to_string(rotations.size()) + " rotations for " +
                                std::to_string(rotations_.size()) + " elements");
  for (size_t e = 0; e < rotations.size(); ++e)
    if (!rotations[e].allFinite())
      throw std::invalid_argument("WarpedDynamics: rotation of element " + std::to_string(e) +
                                  " is not finite");
  rotations_ = rotations;
}

void WarpedDynamics::setPreviousVelocityIncrement(const Eigen::VectorXd& dv) {
  checkVector(dv, numDofs(), "previous velocity increment");
  previous_dv_ = dv;
}

void WarpedDynamics::gatherElement(int e, const Eigen::VectorXd& global, Eigen::VectorXd& local) const {
  const auto& ids = model_.mesh().element(e).globalNodeIds();
  local.resize(3 * ids.size());
  for (size_t a = 0; a < ids.size(); ++a) local.segment<3>(3 * a) = global.segment<3>(3 * ids[a]);
}

// Stiffness warping (9.1.4): R_e by Horn's registration [103] of the rest onto the current nodes.
WarpedDynamics::ElementFrame WarpedDynamics::elementFrame(int e, const Eigen::VectorXd& positions,
                                                          const Eigen::Matrix3d& previous) const {
  Eigen::VectorXd rest_local, current_local;
  gatherElement(e, rest_, rest_local);
  gatherElement(e, positions, current_local);
  const HornRegistration reg =
      warmStartedRegistration(rest_local, current_local, rotation_weights_[e], previous);
  ElementFrame frame{reg.rotation, reg.rest_centroid, reg.current_centroid, false};
  if (!options_.stiffness_warping) {
    frame.rotation.setIdentity();
  } else if (!(reg.eigenvalue_gap > options_.min_eigenvalue_gap)) {
    frame.rotation = previous;
    frame.degenerate = true;
  }
  return frame;
}

Eigen::VectorXd WarpedDynamics::elementDisplacement(int e, const ElementFrame& frame) const {
  // u_e = R^T (x_e - c) - (X_e - C): the rotated-back displacement the linear strain (9.14) is evaluated on
  const auto& ids = model_.mesh().element(e).globalNodeIds();
  Eigen::VectorXd u(3 * ids.size());
  for (size_t a = 0; a < ids.size(); ++a)
    u.segment<3>(3 * a) =
        frame.rotation.transpose() * (positions_.segment<3>(3 * ids[a]) - frame.current_centroid) -
        (rest_.segment<3>(3 * ids[a]) - frame.rest_centroid);
  return u;
}

void WarpedDynamics::updateWarping() {
  const Clock::time_point warping_start = Clock::now();
  const PolyhedralMesh& mesh = model_.mesh();
  const int num_elements = mesh.numElements();
  int degenerate = 0;
#pragma omp parallel reduction(+ : degenerate) if (num_elements >= kParallelElements)
  {
    // Per-thread scratch (no allocation per element).
    Eigen::VectorXd rest_buffer(3 * max_element_nodes_), current_buffer(3 * max_element_nodes_),
        u_buffer(3 * max_element_nodes_), ku_buffer(3 * max_element_nodes_);
#pragma omp for schedule(dynamic, 64)
    for (int e = 0; e < num_elements; ++e) {
      const auto& ids = mesh.element(e).globalNodeIds();
      const int n = static_cast<int>(ids.size());
      Eigen::Map<Eigen::VectorXd> rest_local(rest_buffer.data(), 3 * n),
          current_local(current_buffer.data(), 3 * n), u(u_buffer.data(), 3 * n), ku(ku_buffer.data(), 3 * n);
      for (int a = 0; a < n; ++a) {
        rest_local.segment<3>(3 * a) = rest_.segment<3>(3 * ids[a]);
        current_local.segment<3>(3 * a) = positions_.segment<3>(3 * ids[a]);
      }
      // Newton iterations from the previous R_e; Horn's eigen-solve for flat or far-rotated elements.
      const HornRegistration reg =
          warmStartedRegistration(rest_local, current_local, rotation_weights_[e], rotations_[e]);
      if (!options_.stiffness_warping) {
        rotations_[e].setIdentity();
      } else if (reg.eigenvalue_gap > options_.min_eigenvalue_gap) {
        rotations_[e] = reg.rotation;
      } else {
        ++degenerate;  // keep the previous R_e
      }
      const Eigen::Matrix3d& r = rotations_[e];
      // u_e = R^T (x_e - c) - (X_e - C), f_e = -R K_e u_e
      for (int a = 0; a < n; ++a)
        u.segment<3>(3 * a) = r.transpose() * (current_local.segment<3>(3 * a) - reg.current_centroid) -
                              (rest_local.segment<3>(3 * a) - reg.rest_centroid);
      ku.noalias() = model_.elementStiffness(e) * u;
      double* f = element_forces_.data() + element_force_offset_[e];
      for (int a = 0; a < n; ++a) Eigen::Map<Vec3>(f + 3 * a) = -(r * ku.segment<3>(3 * a));
      // R_e K_e R_e^T block by block (block (a, b) column-major at 9 (b n + a)); K_e is symmetric, so
      // block (b, a) is the transpose of block (a, b).
      const Eigen::MatrixXd& k = model_.elementStiffness(e);
      double* rk = rotated_blocks_.data() + rotated_block_offset_[e];
      for (int b = 0; b < n; ++b)
        for (int a = 0; a <= b; ++a) {
          Eigen::Map<Eigen::Matrix3d> block(rk + 9 * (b * n + a));
          block.noalias() = r * (k.block<3, 3>(3 * a, 3 * b) * r.transpose());
          if (a != b) Eigen::Map<Eigen::Matrix3d>(rk + 9 * (a * n + b)) = block.transpose();
        }
    }
  }
  degenerate_rotations_ = degenerate;
  last_warping_ms_ = millisecondsSince(warping_start);

  // K_w = sum_e R_e K_e R_e^T (the thesis' K'_e, 9.1.4) and f_int: a serial pass adding each element's
  // rotated 3 x 3 blocks in place (block value indices of the model's pattern). Serial on purpose:
  // node-range-parallel variants (no atomics, same sums) measured slower on 2 shared, loaded cores (bunny
  // scene: assembly 35 -> 65-96 ms/frame).
  const Clock::time_point scatter_start = Clock::now();
  double* values = warped_stiffness_.valuePtr();
  std::fill(values, values + warped_stiffness_.nonZeros(), 0.0);
  elastic_forces_.setZero();
  for (int e = 0; e < num_elements; ++e) {
    const auto& ids = mesh.element(e).globalNodeIds();
    const int n = static_cast<int>(ids.size());
    const double* f = element_forces_.data() + element_force_offset_[e];
    const double* rk = rotated_blocks_.data() + rotated_block_offset_[e];
    const int* index = model_.blockValueIndices(e);
    for (int b = 0; b < n; ++b) {
      elastic_forces_.segment<3>(3 * ids[b]) += Eigen::Map<const Vec3>(f + 3 * b);
      const int length = model_.columnLength(ids[b]);
      for (int a = 0; a < n; ++a) {
        const double* block = rk + 9 * (b * n + a);
        double* column = values + index[b * n + a];
        for (int c = 0; c < 3; ++c)
          for (int row = 0; row < 3; ++row) column[c * length + row] += block[3 * c + row];
      }
    }
  }
  last_scatter_ms_ = millisecondsSince(scatter_start);
}

Eigen::VectorXd WarpedDynamics::solveSystem(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& b,
                                            const Eigen::VectorXd& guess, const std::vector<char>& active,
                                            StepStatistics& stats) {
  Eigen::VectorXd x;
  if (options_.solver == WarpedDynamicsOptions::Solver::kSimplicialLDLT) {
    if (!ldlt_analyzed_) {
      ldlt_.analyzePattern(a);
      ldlt_analyzed_ = true;
    }
    ldlt_.factorize(a);
    ++stats.factorizations;
    if (ldlt_.info() != Eigen::Success)
      throw std::runtime_error("WarpedDynamics::step: LDLT factorisation of M + dt C + dt^2 K failed");
    x = ldlt_.solve(b);
    stats.solver_iterations += 1;
  } else if (options_.solver == WarpedDynamicsOptions::Solver::kCholmod) {
    factorizeCholmod(a, stats);
    cholmod_->solve(b, x);
    stats.solver_iterations += 1;
  } else if (options_.solver == WarpedDynamicsOptions::Solver::kCholmodPcg) {
    // The system and contact-filtered matrices share one pattern for the life of the body.
    const bool fresh = held_changed_ || !cholmod_->factorized() || !prepareContactCorrection(active, stats);
    held_changed_ = false;
    if (fresh) {
      factorizeCholmod(a, stats);
      recordFactoredContact(active);
    }
    x = guess;
    if (!factorPreconditionedCg(a, b, x,
                                fresh ? options_.cg_max_iterations : options_.pcg_refactor_iterations,
                                fresh ? 0 : options_.pcg_extension_iterations, stats)) {
      if (fresh) {
        stats.converged = false;
      } else {  // the stale factor preconditions too poorly: factorise this matrix and solve directly
        factorizeCholmod(a, stats);
        recordFactoredContact(active);
        cholmod_->solve(b, x);
        stats.solver_iterations += 1;
        stats.solver_error = 0.0;
      }
    }
  } else if (options_.preconditioner == WarpedDynamicsOptions::Preconditioner::kJacobi) {
    jacobi_cg_.setTolerance(options_.cg_tolerance);
    jacobi_cg_.setMaxIterations(options_.cg_max_iterations);
    jacobi_cg_.compute(a);
    x = jacobi_cg_.solveWithGuess(b, guess);
    stats.solver_iterations += static_cast<int>(jacobi_cg_.iterations());
    stats.solver_error = jacobi_cg_.error();
    stats.converged = stats.converged && jacobi_cg_.info() == Eigen::Success;
  } else {
    ichol_cg_.setTolerance(options_.cg_tolerance);
    ichol_cg_.setMaxIterations(options_.cg_max_iterations);
    ichol_cg_.compute(a);
    if (ichol_cg_.info() != Eigen::Success)
      throw std::runtime_error("WarpedDynamics::step: incomplete Cholesky preconditioner failed");
    x = ichol_cg_.solveWithGuess(b, guess);
    stats.solver_iterations += static_cast<int>(ichol_cg_.iterations());
    stats.solver_error = ichol_cg_.error();
    stats.converged = stats.converged && ichol_cg_.info() == Eigen::Success;
  }
  if (!x.allFinite()) throw std::runtime_error("WarpedDynamics::step: the velocity update is not finite");
  return x;
}

void WarpedDynamics::factorizeCholmod(const Eigen::SparseMatrix<double>& a, StepStatistics& stats) {
  try {
    cholmod_->factorize(a);  // analyses when the pattern differs from the last one
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(std::string("WarpedDynamics::step: CHOLMOD factorisation of M + dt C + dt^2 K "
                                         "failed: ") +
                             error.what());
  }
  ++stats.factorizations;
}

bool WarpedDynamics::factorPreconditionedCg(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& b,
                                            Eigen::VectorXd& x, int max_iterations, int max_extension,
                                            StepStatistics& stats) {
  const double b_norm = b.norm();
  if (b_norm == 0.0) {
    x.setZero();
    stats.solver_error = 0.0;
    return true;
  }
  const double threshold = options_.cg_tolerance * b_norm;
  Eigen::VectorXd r = b - a * x, z, p, q;
  double r_norm = r.norm();
  const double initial_norm = r_norm;
  int iterations = 0;
  bool extended = false;
  if (r_norm > threshold) {
    applyPreconditioner(r, z);
    p = z;
    double rz = r.dot(z);
    for (;;) {
      if (iterations >= max_iterations) {
        // Out of iterations: go on when the mean residual reduction so far reaches the tolerance within
        // max_extension more (cheaper than the refactorisation it saves).
        if (extended || max_extension <= 0 || !(r_norm < initial_norm)) break;
        const double rate = std::pow(r_norm / initial_norm, 1.0 / iterations);
        const double needed = std::ceil(std::log(threshold / r_norm) / std::log(rate));
        if (!(needed <= max_extension)) break;
        max_iterations += static_cast<int>(needed);
        extended = true;
      }
      q.noalias() = a * p;
      const double alpha = rz / p.dot(q);
      x += alpha * p;
      r -= alpha * q;
      ++iterations;
      r_norm = r.norm();
      if (r_norm <= threshold) break;
      applyPreconditioner(r, z);
      const double rz_next = r.dot(z);
      p = z + (rz_next / rz) * p;
      rz = rz_next;
    }
  }
  stats.solver_iterations += iterations;
  stats.solver_error = r_norm / b_norm;
  return r_norm <= threshold;
}

void WarpedDynamics::recordFactoredContact(const std::vector<char>& active) {
  factored_active_ = active;
  released_nodes_.clear();
  added_nodes_.clear();
  if (options_.pcg_contact_updates > 0) copyValues(system_matrix_, factored_system_);
}

bool WarpedDynamics::prepareContactCorrection(const std::vector<char>& active, StepStatistics& stats) {
  if (options_.pcg_contact_updates == 0 || factored_active_.empty()) return true;  // plain stale factor
  std::vector<int> released, added;
  for (int i = 0; i < numNodes(); ++i) {
    if (factored_active_[i] && !active[i]) released.push_back(i);
    if (!factored_active_[i] && active[i]) added.push_back(i);
  }
  if (static_cast<int>(released.size() + added.size()) > options_.pcg_contact_updates) return false;
  if (released == released_nodes_ && added == added_nodes_) return true;  // prepared in an earlier round
  released_nodes_.clear();
  added_nodes_.clear();
  const Vec3& n = options_.ground.normal;
  const int dofs = numDofs(), r = static_cast<int>(released.size()), a = static_cast<int>(added.size());
  if (r > 0) {
    // Z = P A_f Q column by column (P: no normal component on the factor's contact nodes), Q^T A_f Q.
    Eigen::MatrixXd coupling = Eigen::MatrixXd::Zero(dofs, r), normal_block(r, r);
    for (int k = 0; k < r; ++k) {
      auto column = coupling.col(k);
      for (int c = 0; c < 3; ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(factored_system_, 3 * released[k] + c); it; ++it)
          column[it.row()] += n[c] * it.value();
      for (int l = 0; l < r; ++l) normal_block(l, k) = n.dot(column.segment<3>(3 * released[l]));
    }
    for (int i = 0; i < numNodes(); ++i)
      if (factored_active_[i])
        for (int k = 0; k < r; ++k) {
          auto block = coupling.block<3, 1>(3 * i, k);
          block -= n.dot(block) * n;
        }
    released_coupling_ = coupling.sparseView();
    cholmod_->solve(coupling, released_solves_);  // W = F^-1 Z
    released_schur_.compute(normal_block - released_coupling_.transpose() * released_solves_);
    if (released_schur_.info() != Eigen::Success) return false;
  }
  released_nodes_ = released;
  if (a > 0) {
    Eigen::MatrixXd normals = Eigen::MatrixXd::Zero(dofs, a);  // E
    for (int k = 0; k < a; ++k) normals.block<3, 1>(3 * added[k], k) = n;
    applyReleasedInverse(normals, added_solves_);  // V = B^-1 E
    Eigen::MatrixXd h(a, a);
    for (int k = 0; k < a; ++k)
      for (int l = 0; l < a; ++l) h(l, k) = n.dot(added_solves_.block<3, 1>(3 * added[l], k));
    added_schur_.compute(h);
    if (added_schur_.info() != Eigen::Success) {
      released_nodes_.clear();
      return false;
    }
  }
  added_nodes_ = added;
  stats.contact_updates = std::max(stats.contact_updates, r + a);
  return true;
}

void WarpedDynamics::applyReleasedInverse(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
  const int r = static_cast<int>(released_nodes_.size());
  if (r == 0) {
    cholmod_->solve(b, x);
    return;
  }
  // Block elimination: x_R = S^-1 (Q^T b - Z^T F^-1 b_G), x = F^-1 b_G - W x_R + Q x_R, b_G = b - Q Q^T b.
  const Vec3& n = options_.ground.normal;
  const Eigen::Index cols = b.cols();
  Eigen::MatrixXd normal_part(r, cols), free_part = b;
  for (int k = 0; k < r; ++k) {
    auto rows = free_part.middleRows<3>(3 * released_nodes_[k]);
    normal_part.row(k) = n.transpose() * rows;
    rows -= n * normal_part.row(k);
  }
  cholmod_->solve(free_part, x);
  const Eigen::MatrixXd released_values =
      released_schur_.solve(normal_part - released_coupling_.transpose() * x);
  x.noalias() -= released_solves_ * released_values;
  for (int k = 0; k < r; ++k) x.middleRows<3>(3 * released_nodes_[k]) += n * released_values.row(k);
}

void WarpedDynamics::applyPreconditioner(const Eigen::VectorXd& r, Eigen::VectorXd& z) {
  if (released_nodes_.empty() && added_nodes_.empty()) {
    cholmod_->solve(r, z);
    return;
  }
  const Vec3& n = options_.ground.normal;
  Eigen::MatrixXd filtered = r, t;
  for (int i : added_nodes_) filtered.block<3, 1>(3 * i, 0) -= n.dot(r.segment<3>(3 * i)) * n;
  applyReleasedInverse(filtered, t);
  z = t.col(0);
  if (added_nodes_.empty()) return;
  Eigen::VectorXd normal_values(added_nodes_.size());
  for (size_t k = 0; k < added_nodes_.size(); ++k)
    normal_values[k] = n.dot(z.segment<3>(3 * added_nodes_[k]));
  z.noalias() -= added_solves_ * added_schur_.solve(normal_values);
  for (int i : added_nodes_) z.segment<3>(3 * i) += n.dot(r.segment<3>(3 * i)) * n;
}

void WarpedDynamics::buildConstrainedMatrix(const std::vector<char>& active) {
  // A' = S A S + (I - S), S_i = I - n n^T on contact nodes, I elsewhere; blocks of A are full 3 x 3.
  copyValues(system_matrix_, constrained_matrix_);
  const Vec3& n = options_.ground.normal;
  const Eigen::Matrix3d s = Eigen::Matrix3d::Identity() - n * n.transpose();
  const int* outer = constrained_matrix_.outerIndexPtr();
  const int* inner = constrained_matrix_.innerIndexPtr();
  double* values = constrained_matrix_.valuePtr();
  for (int j = 0; j < numNodes(); ++j) {
    const int count = outer[3 * j + 1] - outer[3 * j];
    for (int k = 0; k < count; k += 3) {
      const int i = inner[outer[3 * j] + k] / 3;
      if (!active[i] && !active[j]) continue;
      Eigen::Matrix3d block;
      for (int q = 0; q < 3; ++q)
        for (int p = 0; p < 3; ++p) block(p, q) = values[outer[3 * j + q] + k + p];
      if (active[i]) block = s * block;
      if (active[j]) block = block * s;
      if (i == j && active[i]) block += n * n.transpose();
      for (int q = 0; q < 3; ++q)
        for (int p = 0; p < 3; ++p) values[outer[3 * j + q] + k + p] = block(p, q);
    }
  }
}

StepStatistics WarpedDynamics::step() {
  StepStatistics stats;
  updateWarping();
  stats.warping_ms = last_warping_ms_;
  stats.assembly_ms = last_scatter_ms_;
  Clock::time_point phase_start = Clock::now();
  stats.degenerate_rotations = degenerate_rotations_;
  const double dt = options_.time_step, alpha = options_.mass_damping, beta = options_.stiffness_damping;

  // Implicit Euler on (9.20) with D = alpha M + beta K_w: A dv = b,
  // A = (1 + dt alpha) M + (dt^2 + dt beta) K_w
  const int nnz = static_cast<int>(warped_stiffness_.nonZeros());
  const double stiffness_scale = dt * dt + dt * beta;
  for (int k = 0; k < nnz; ++k)
    system_matrix_.valuePtr()[k] = stiffness_scale * warped_stiffness_.valuePtr()[k];
  for (int d = 0; d < numDofs(); ++d)
    system_matrix_.valuePtr()[diagonal_index_[d]] += (1.0 + dt * alpha) * masses3_[d];

  // b = dt (f_ext + f_int - alpha M v - (beta + dt) K_w v)
  const Eigen::VectorXd kv = warped_stiffness_ * velocities_;
  const Eigen::VectorXd rhs = dt * (gravity_forces_ + user_forces_ + elastic_forces_ -
                                    alpha * masses3_.cwiseProduct(velocities_) - (beta + dt) * kv);
  Eigen::VectorXd guess = options_.cg_warm_start ? previous_dv_ : Eigen::VectorXd::Zero(numDofs());
  Eigen::VectorXd system_rhs = rhs, held_dv;
  if (num_held_dofs_ > 0) held_dv = eliminateHeldDofs(system_rhs, guess);

  // Contact set: a node is held when it is on or below the ground or would cross it during the step. A held
  // node gets n . v+ = w_i = min(0, (offset - n . x_i) / dt) inside the solve, so a landing node stops on the
  // plane (no position jump afterwards) and its reaction J_i = n . (A dv - b)_i >= 0 only does work
  // J_i w_i <= 0. Held nodes pulling by more than the solver's error are released, free nodes that would
  // cross are added, and the step is solved again. Coulomb friction acts inside the solve as the tangential
  // impulse -c_i (I - n n^T) v+_i (c_i: groundFrictionCoefficient), implicit and dissipative.
  const GroundPlane& g = options_.ground;
  const int num_nodes = numNodes();
  if (contact_impulses_.size() != num_nodes) contact_impulses_ = Eigen::VectorXd::Zero(num_nodes);
  Eigen::VectorXd bound = Eigen::VectorXd::Zero(num_nodes), friction;
  std::vector<char> active(num_nodes, 0), released(num_nodes, 0), pinned(num_nodes, 0);
  int num_active = 0;
  if (g.enabled) {
    friction = Eigen::VectorXd::Zero(num_nodes);
    for (int i = 0; i < num_nodes; ++i) {
      if (!held_nodes_.empty() && held_nodes_[size_t(i)]) continue;
      const double height = g.normal.dot(positions_.segment<3>(3 * i)) - g.offset;
      bound[i] = std::min(0.0, -height / dt);
      // Predicted n . v+: v plus the previous step's dv.
      const double predicted = g.normal.dot(velocities_.segment<3>(3 * i) + previous_dv_.segment<3>(3 * i));
      // Friction bound: the previous step's normal impulse, for a new contact m_i (w_i - predicted n . v+).
      friction[i] = groundFrictionCoefficient(i, contact_impulses_[i] > 0.0
                                                     ? contact_impulses_[i]
                                                     : masses3_[3 * i] * std::max(0.0, bound[i] - predicted));
      const double round_off = 1e-12 * (1.0 + positions_.segment<3>(3 * i).norm());  // on the plane
      if (std::min(height, height + dt * predicted) <= round_off) {
        active[i] = 1;
        ++num_active;
        addGroundFriction(i, friction[i], system_rhs);
      }
    }
  }
  // Decisions tolerate the solver's error (relative residual cg_tolerance for every solver, so that CG and
  // a direct solver decide alike): release when the pull exceeds kGroundDecisionMargin tol |b|, add when
  // the predicted depth exceeds kGroundDecisionMargin tol dt |v+|. A released node added again stays held.
  constexpr int kMaxGroundRounds = 8;
  constexpr double kGroundDecisionMargin = 100.0;
  const double rhs_norm = rhs.norm();
  Eigen::VectorXd dv, reaction, z(numDofs()), b, y0;
  for (int round = 0;; ++round) {
    ++stats.contact_rounds;
    double b_norm = rhs_norm;
    if (num_active == 0) {  // the held dofs (if any) are filtered in system_matrix_ already
      stats.assembly_ms += millisecondsSince(phase_start);
      phase_start = Clock::now();
      dv = solveSystem(system_matrix_, system_rhs, round == 0 ? guess : dv, active, stats);
      stats.solve_ms += millisecondsSince(phase_start);
      phase_start = Clock::now();
    } else {
      z.setZero();  // prescribed part: dv . n = w - v . n
      for (int i = 0; i < num_nodes; ++i)
        if (active[i])
          z.segment<3>(3 * i) = (bound[i] - g.normal.dot(velocities_.segment<3>(3 * i))) * g.normal;
      // Later rounds start from the previous round's solution (only the changed nodes' rows differ).
      b = system_rhs - system_matrix_ * z;
      y0 = round == 0 ? guess : Eigen::VectorXd(dv - z);
      for (int i = 0; i < num_nodes; ++i)
        if (active[i]) {
          b.segment<3>(3 * i) -= g.normal.dot(b.segment<3>(3 * i)) * g.normal;
          y0.segment<3>(3 * i) -= g.normal.dot(y0.segment<3>(3 * i)) * g.normal;
        }
      b_norm = std::max(b_norm, b.norm());
      buildConstrainedMatrix(active);
      stats.assembly_ms += millisecondsSince(phase_start);
      phase_start = Clock::now();
      dv = solveSystem(constrained_matrix_, b, y0, active, stats) + z;
      stats.solve_ms += millisecondsSince(phase_start);
      phase_start = Clock::now();
      reaction = system_matrix_ * dv - system_rhs;  // ground impulse on each node (M dv = dt f + J)
    }
    if (!g.enabled || round + 1 >= kMaxGroundRounds) break;  // keep the last solve's contact set
    const double pull_limit = kGroundDecisionMargin * options_.cg_tolerance * b_norm;
    const double depth_limit = kGroundDecisionMargin * options_.cg_tolerance * dt * (velocities_ + dv).norm();
    int changed = 0;
    for (int i = 0; i < num_nodes; ++i) {
      if (active[i]) {
        if (pinned[i] || g.normal.dot(reaction.segment<3>(3 * i)) >= -pull_limit) continue;
        active[i] = 0;
        released[i] = 1;
        --num_active;
        addGroundFriction(i, -friction[i], system_rhs);
        ++changed;
      } else if ((held_nodes_.empty() || !held_nodes_[size_t(i)]) &&
                 g.normal.dot(positions_.segment<3>(3 * i) +
                              dt * (velocities_.segment<3>(3 * i) + dv.segment<3>(3 * i))) -
                         g.offset <
                     -depth_limit) {
        active[i] = 1;
        pinned[i] = released[i];
        ++num_active;
        addGroundFriction(i, friction[i], system_rhs);
        ++changed;
      }
    }
    if (changed == 0) break;
  }
  if (num_held_dofs_ > 0) {
    dv += held_dv;
    computeHeldReactions(dv, rhs);
  }
  previous_dv_ = dv;
  velocities_ += dv;
  contact_impulses_.setZero();
  for (int i = 0; i < num_nodes; ++i)
    if (active[i]) {
      ++stats.contact_nodes;
      contact_impulses_[i] = std::max(0.0, g.normal.dot(reaction.segment<3>(3 * i)));
    }
  positions_ += dt * velocities_;
  applyGroundContact(stats);
  return stats;
}

void WarpedDynamics::applyGroundContact(StepStatistics& stats) {
  // Safety net: nodes left below the plane (solver error, or a contact set still changing after the last
  // round) are projected onto it; their velocities stay (the next step holds them at n . v+ = 0).
  if (!options_.ground.enabled) return;
  const GroundPlane& g = options_.ground;
  for (int i = 0; i < numNodes(); ++i) {
    if (!held_nodes_.empty() && held_nodes_[size_t(i)]) continue;
    auto x = positions_.segment<3>(3 * i);
    const double depth = g.offset - g.normal.dot(x);
    if (depth <= 0.0) continue;
    x += depth * g.normal;
    if (depth > 1e-12 * (1.0 + x.norm())) ++stats.projected_nodes;  // not counted: round-off on the plane
  }
}

double WarpedDynamics::groundFrictionCoefficient(int node, double normal_impulse) const {
  // Coulomb: the impulse c |v+_t| stays below mu J when c = mu J / |v_t| (|v+_t| <= |v_t|); capped at
  // kStickingFactor m_i, which stops a body resting on its contact nodes within a few steps (a cap on the
  // stiffness-dominated diagonal of A changes the matrix more and costs the kCholmodPcg factor ~2x the
  // refactorisations in the bunny scene).
  constexpr double kStickingFactor = 10.0;
  const GroundPlane& g = options_.ground;
  const double limit = g.friction * normal_impulse;
  if (!(limit > 0.0)) return 0.0;
  const Vec3 v = velocities_.segment<3>(3 * node);
  const double speed = (v - g.normal.dot(v) * g.normal).norm();
  const double sticking = kStickingFactor * masses3_[3 * node];
  return limit < sticking * speed ? limit / speed : sticking;
}

void WarpedDynamics::addGroundFriction(int node, double coefficient, Eigen::VectorXd& rhs) {
  // (M + ... + D) dv = b - D v with D = c (I - n n^T) on the node's diagonal block: the impulse -D v+.
  if (coefficient == 0.0) return;
  const Vec3& n = options_.ground.normal;
  const Eigen::Matrix3d d = coefficient * (Eigen::Matrix3d::Identity() - n * n.transpose());
  double* values = system_matrix_.valuePtr();
  for (int q = 0; q < 3; ++q)  // the node's rows are contiguous in each of its columns (full 3 x 3 blocks)
    for (int p = 0; p < 3; ++p) values[diagonal_index_[3 * node + q] - q + p] += d(p, q);
  rhs.segment<3>(3 * node) -= d * velocities_.segment<3>(3 * node);
}

double WarpedDynamics::kineticEnergy() const {
  return 0.5 * velocities_.dot(masses3_.cwiseProduct(velocities_));
}

double WarpedDynamics::elasticEnergy() const {
  const int num_elements = model_.mesh().numElements();
  double energy = 0.0;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : energy) if (num_elements >= kParallelElements)
  for (int e = 0; e < num_elements; ++e) {
    const Eigen::VectorXd u = elementDisplacement(e, elementFrame(e, positions_, rotations_[e]));
    energy += 0.5 * u.dot(model_.elementStiffness(e) * u);
  }
  return energy;
}

double WarpedDynamics::gravityPotentialEnergy() const {
  return -gravity_forces_.dot(positions_);
}

Vec3 WarpedDynamics::linearMomentum() const {
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < numNodes(); ++i) p += masses3_[3 * i] * velocities_.segment<3>(3 * i);
  return p;
}

Vec3 WarpedDynamics::angularMomentum(const Vec3& origin) const {
  Vec3 l = Vec3::Zero();
  for (int i = 0; i < numNodes(); ++i)
    l += masses3_[3 * i] * (positions_.segment<3>(3 * i) - origin).cross(velocities_.segment<3>(3 * i));
  return l;
}

Vec3 WarpedDynamics::centerOfMass() const {
  Vec3 c = Vec3::Zero();
  double mass = 0.0;
  for (int i = 0; i < numNodes(); ++i) {
    c += masses3_[3 * i] * positions_.segment<3>(3 * i);
    mass += masses3_[3 * i];
  }
  return c / mass;
}

double WarpedDynamics::currentVolume() const {
  double volume = 0.0;
  for (const auto& t : model_.mesh().boundaryTriangles()) {
    const Vec3 a = positions_.segment<3>(3 * t[0]), b = positions_.segment<3>(3 * t[1]),
               c = positions_.segment<3>(3 * t[2]);
    volume += a.dot(b.cross(c)) / 6.0;
  }
  return volume;
}

}  // namespace rc
