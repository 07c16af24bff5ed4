// The corotational static equilibrium (key static.corotational of an FEM scene, FemStaticOptions): the warped
// internal forces f(x) = -sum_e R_e K_e u_e of the stiffness-warped dynamics (9.1.4) balance the loads F, so
// large rotations with small strains (a cantilever bent far, a column turned) are in equilibrium where the
// linear K U = F (9.16) stretches the rotated parts.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "relaxed_connectivity/fem/fem_scene.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"

namespace rc {

struct CorotationalStaticResult {
  Eigen::VectorXd displacements;  ///< 3 N
  Eigen::VectorXd reactions;      ///< 3 N: -(f(x) + F) at held dofs (the holders' forces), 0 elsewhere
  int iterations = 0;             ///< over all load steps
  double residual = 0.0;          ///< final |f(x) + F| over the free dofs relative to the load scale
};

/// Load steps lambda = s / load_steps (loads and prescribed displacements scaled together); per step Newton
/// iterations on the free dofs: J dx = -(f(x) + lambda F), J the derivative of f with the rotations' (finite
/// differences inside GMRES, preconditioned by the warped stiffness K_w = sum_e R_e K_e R_e^T), x += a dx (a
/// halved until the residual drops, at most 8 times), until |f(x) + lambda F| <= tolerance * max(lambda |F|,
/// |f(x)| at the held dofs). Throws std::runtime_error naming the load step when max_iterations do not reach
/// it or the state is not finite.
CorotationalStaticResult solveCorotationalStatic(LinearElasticModel model, const Eigen::VectorXd& forces,
                                                 const std::vector<DisplacementConstraint>& constraints,
                                                 const FemStaticOptions& options);

}  // namespace rc
