// Held degrees of freedom of WarpedDynamics (Dirichlet conditions with prescribed targets; header of
// warped_dynamics.h): the mask, the targets, their elimination from the step's system and the reactions.
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace rc {

void WarpedDynamics::setHeld(std::vector<char> dof_mask) {
  if (!dof_mask.empty() && dof_mask.size() != static_cast<size_t>(numDofs()))
    throw std::invalid_argument("WarpedDynamics::setHeld: " + std::to_string(dof_mask.size()) +
                                " mask entries for " + std::to_string(numDofs()) + " dofs");
  num_held_dofs_ = 0;
  for (char& held : dof_mask) {
    held = held != 0;
    num_held_dofs_ += held;
  }
  if (num_held_dofs_ == 0) dof_mask.clear();
  if (dof_mask != held_dofs_) held_changed_ = true;
  held_dofs_ = std::move(dof_mask);
  held_nodes_.assign(held_dofs_.empty() ? 0 : static_cast<size_t>(numNodes()), 0);
  for (size_t d = 0; d < held_dofs_.size(); ++d)
    if (held_dofs_[d]) held_nodes_[d / 3] = 1;
  held_targets_ = positions_;
  held_reactions_ = Eigen::VectorXd::Zero(numDofs());
}

void WarpedDynamics::setHeldTargets(const Eigen::VectorXd& targets) {
  if (targets.size() != numDofs())
    throw std::invalid_argument("WarpedDynamics::setHeldTargets: " + std::to_string(targets.size()) +
                                " entries for " + std::to_string(numDofs()) + " dofs");
  for (size_t d = 0; d < held_dofs_.size(); ++d)
    if (held_dofs_[d] && !std::isfinite(targets[Eigen::Index(d)]))
      throw std::invalid_argument("WarpedDynamics::setHeldTargets: the target of dof " + std::to_string(d) +
                                  " is not finite");
  held_targets_ = targets;
}

Eigen::VectorXd WarpedDynamics::eliminateHeldDofs(Eigen::VectorXd& rhs, Eigen::VectorXd& guess) {
  const double dt = options_.time_step;
  Eigen::VectorXd held_dv = Eigen::VectorXd::Zero(numDofs());
  for (int d = 0; d < numDofs(); ++d)
    if (held_dofs_[size_t(d)]) held_dv[d] = (held_targets_[d] - positions_[d]) / dt - velocities_[d];
  rhs.noalias() -= system_matrix_ * held_dv;
  // S A S + (I - S): the held rows and columns become those of the identity (the pattern stays).
  for (int column = 0; column < numDofs(); ++column) {
    const bool held_column = held_dofs_[size_t(column)] != 0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(system_matrix_, column); it; ++it)
      if (held_column || held_dofs_[size_t(it.row())]) it.valueRef() = it.row() == column ? 1.0 : 0.0;
  }
  for (int d = 0; d < numDofs(); ++d)
    if (held_dofs_[size_t(d)]) rhs[d] = guess[d] = 0.0;
  return held_dv;
}

void WarpedDynamics::computeHeldReactions(const Eigen::VectorXd& dv, const Eigen::VectorXd& rhs) {
  // A dv - b with A = (1 + dt alpha) M + (dt^2 + dt beta) K_w (unfiltered), per held dof; J / dt.
  const double dt = options_.time_step;
  const Eigen::VectorXd kdv = warped_stiffness_ * dv;
  held_reactions_.setZero();
  for (int d = 0; d < numDofs(); ++d)
    if (held_dofs_[size_t(d)])
      held_reactions_[d] = ((1.0 + dt * options_.mass_damping) * masses3_[d] * dv[d] +
                            (dt * dt + dt * options_.stiffness_damping) * kdv[d] - rhs[d]) /
                           dt;
}

}  // namespace rc
