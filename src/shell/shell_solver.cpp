#include "relaxed_connectivity/shell/shell_solver.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace rc {
namespace {
// Below this node count a parallel loop costs more than it saves.
constexpr size_t kParallelNodes = 2048;
}  // namespace

ShellSolver::ShellSolver(ShellNodes nodes, const ShellMaterial& material, const ShellSolverOptions& options)
    : nodes_(std::move(nodes)),
      fibers_(buildShellFibers(nodes_)),
      energy_(nodes_, fibers_, material),
      options_(options),
      x_(nodes_.rest_positions),
      v_(nodes_.size(), Vec3::Zero()),
      held_(nodes_.size(), 0) {
  if (!(options.time_step >= 0.0) || !(options.step_safety > 0.0 && options.step_safety <= 1.0) ||
      options.step_update_interval < 1 || !(options.blowup_factor > 1.0) || !options.gravity.allFinite()) {
    throw std::invalid_argument(
        "ShellSolverOptions: need time_step >= 0, step_safety in (0, 1], step_update_interval >= 1, "
        "blowup_factor > 1 and finite gravity");
  }
  if (options.ground && !(options.ground_normal.norm() > 0.0)) {
    throw std::invalid_argument("ShellSolverOptions: ground_normal must be non-zero");
  }
  options_.ground_normal.normalize();
  double area = 0.0;
  for (double a : nodes_.rest_areas) area += a;
  energy_floor_ = 1e-9 * (material.stretch_stiffness * area + material.bending_stiffness);
  resetReference();
}

void ShellSolver::pin(size_t node) {
  hold(node, 7);
}

void ShellSolver::hold(size_t node, uint8_t mask) {
  if (mask > 7) throw std::invalid_argument("ShellSolver::hold: mask must be 0..7 (bits x, y, z)");
  held_.at(node) |= mask;
  for (int d = 0; d < 3; ++d)
    if (held_[node] >> d & 1) v_[node][d] = 0.0;
  partly_held_ = partly_held_ || (held_[node] != 0 && held_[node] != 7);
}

void ShellSolver::setPinVelocity(size_t node, const Vec3& velocity) {
  if (!velocity.allFinite()) throw std::invalid_argument("ShellSolver::setPinVelocity: non-finite velocity");
  pin(node);
  for (auto& [i, v] : moving_pins_) {
    if (i == node) {
      v = velocity;
      return;
    }
  }
  moving_pins_.emplace_back(node, velocity);
}

void ShellSolver::evaluateForces() {
  elastic_ = energy_.evaluate(x_, &gradient_, &fiber_length_, &fiber_angle_);
}

void ShellSolver::setPositions(const std::vector<Vec3>& x) {
  if (x.size() != x_.size())
    throw std::invalid_argument("ShellSolver::setPositions: wrong number of positions");
  x_ = x;
  resetReference();
}

void ShellSolver::setVelocities(const std::vector<Vec3>& v) {
  if (v.size() != v_.size())
    throw std::invalid_argument("ShellSolver::setVelocities: wrong number of velocities");
  v_ = v;
  for (size_t i = 0; i < v_.size(); ++i)
    for (int d = 0; d < 3; ++d)
      if (held_[i] >> d & 1) v_[i][d] = 0.0;
  resetReference();
}

void ShellSolver::setExternalForce(ShellExternalForce force) {
  external_force_ = std::move(force);
  resetReference();
}

void ShellSolver::refreshForces() {
  const double before = elastic_.total();
  evaluateForces();
  reference_energy_ += std::max(0.0, elastic_.total() - before);
}

void ShellSolver::setTopology(ShellNodes nodes, ShellFibers fibers) {
  if (nodes.size() != nodes_.size() || fibers.node_offsets.size() != nodes.size() + 1) {
    throw std::invalid_argument("ShellSolver::setTopology: node count changed or fibers do not match nodes");
  }
  const ShellMaterial material = energy_.material();
  // The old topology stays alive until the new energy has copied the bending forms of unchanged nodes.
  const ShellNodes old_nodes = std::exchange(nodes_, std::move(nodes));
  const ShellFibers old_fibers = std::exchange(fibers_, std::move(fibers));
  const ShellBendingFormsReuse previous{&energy_.bendingForms(), &old_nodes, &old_fibers};
  ShellEnergy next(nodes_, fibers_, material, &previous);
  energy_ = std::move(next);
  refreshForces();
}

void ShellSolver::resetReference() {
  evaluateForces();
  external_.assign(x_.size(), Vec3::Zero());
  if (external_force_) external_force_(x_, external_);
  external_work_ = 0.0;
  pin_work_ = 0.0;
  reference_energy_ = kineticEnergy() + elastic_.total();
  reference_gravity_ = gravityPotential();
}

double ShellSolver::kineticEnergy() const {
  double k = 0.0;
  for (size_t i = 0; i < v_.size(); ++i) k += 0.5 * energy_.masses()[i] * v_[i].squaredNorm();
  return k;
}

double ShellSolver::gravityPotential() const {
  double u = 0.0;
  for (size_t i = 0; i < x_.size(); ++i) u -= energy_.masses()[i] * options_.gravity.dot(x_[i]);
  return u;
}

void ShellSolver::applyGround() {
  if (!options_.ground) return;
  const Vec3& n = options_.ground_normal;
  for (size_t i = 0; i < x_.size(); ++i) {
    const double depth = (x_[i] - options_.ground_point).dot(n);
    if (depth >= 0.0 || held_[i] == 7) continue;
    x_[i] -= depth * n;
    const double vn = v_[i].dot(n);
    if (vn < 0.0) {
      const Vec3 vt = v_[i] - vn * n;
      v_[i] = (1.0 - options_.ground_friction) * vt - options_.ground_restitution * vn * n;
    }
  }
}

ShellStepReport ShellSolver::step() {
  const size_t n = x_.size();
  const size_t index = step_count_ + 1;
  if (step_count_ % options_.step_update_interval == 0) stable_ = energy_.stableStep(x_);
  const double dt = options_.time_step > 0.0 ? options_.time_step : options_.step_safety * stable_.combined;
  if (!std::isfinite(dt) || dt <= 0.0) {
    throw ShellInstabilityError(index, "no finite stable time step (zero stiffness?); set time_step");
  }
  const double damping = energy_.material().damping;
  const std::vector<double>& m = energy_.masses();
  if (external_force_) x_before_ = x_;
#pragma omp parallel for schedule(static) if (n >= kParallelNodes)
  for (size_t i = 0; i < n; ++i) {  // (7.18): first half kick, drift
    if (held_[i] == 7) continue;
    Vec3 a = (external_[i] - gradient_[i]) / m[i] + options_.gravity - damping * v_[i];
    if (partly_held_ && held_[i])
      for (int d = 0; d < 3; ++d)
        if (held_[i] >> d & 1) a[d] = 0.0;  // its velocity component stays 0
    v_[i] += 0.5 * dt * a;
    x_[i] += dt * v_[i];
  }
  pin_force_before_.resize(moving_pins_.size());
  for (size_t p = 0; p < moving_pins_.size(); ++p) {  // prescribed motion of pulled pins
    pin_force_before_[p] = gradient_[moving_pins_[p].first];
    x_[moving_pins_[p].first] += dt * moving_pins_[p].second;
  }
  applyGround();
  evaluateForces();
  for (size_t p = 0; p < moving_pins_.size(); ++p) {  // work of the pins on the shell, trapezoidal
    const auto& [i, v] = moving_pins_[p];
    pin_work_ += 0.5 * (pin_force_before_[p] + gradient_[i]).dot(dt * v);
  }
  if (external_force_) {  // trapezoidal work of the external force over the drift
    external_next_.assign(n, Vec3::Zero());
    external_force_(x_, external_next_);
    for (size_t i = 0; i < n; ++i)
      external_work_ += 0.5 * (external_[i] + external_next_[i]).dot(x_[i] - x_before_[i]);
    external_.swap(external_next_);
  }
#pragma omp parallel for schedule(static) if (n >= kParallelNodes)
  for (size_t i = 0; i < n; ++i) {  // second half kick, damping implicit
    if (held_[i] == 7) continue;
    v_[i] = (v_[i] + 0.5 * dt * ((external_[i] - gradient_[i]) / m[i] + options_.gravity)) /
            (1.0 + 0.5 * dt * damping);
    if (partly_held_ && held_[i])
      for (int d = 0; d < 3; ++d)
        if (held_[i] >> d & 1) v_[i][d] = 0.0;
  }
  applyGround();
  ++step_count_;
  time_ += dt;

  ShellStepReport report;
  report.step = index;
  report.time = time_;
  report.dt = dt;
  report.stable = stable_;
  report.elastic = elastic_;
  report.kinetic = kineticEnergy();
  report.gravity_potential = gravityPotential();
  report.external_work = external_work_;
  for (size_t i = 0; i < n; ++i) {
    if (!x_[i].allFinite() || !v_[i].allFinite()) {
      std::ostringstream os;
      os << "non-finite position or velocity at node " << i << " (dt " << dt << ", stable bound "
         << stable_.combined << ")";
      throw ShellInstabilityError(index, os.str());
    }
  }
  const double available = reference_energy_ + std::max(0.0, reference_gravity_ - report.gravity_potential) +
                           std::max(0.0, external_work_) + std::max(0.0, pin_work_) + energy_floor_;
  const double held = report.kinetic + elastic_.total();
  if (!std::isfinite(held) || held > options_.blowup_factor * available) {
    std::ostringstream os;
    os << "energy blow-up: kinetic + elastic energy " << held << " exceeds " << options_.blowup_factor
       << " x the available " << available << " (dt " << dt << ", stable bound " << stable_.combined
       << ": membrane " << stable_.membrane << ", bending " << stable_.bending << ")";
    throw ShellInstabilityError(index, os.str());
  }
  return report;
}

}  // namespace rc
