// The stiffness matrix of a point-sampled thin shell: the Hessian of its elastic energy (thesis 7.2.1) at
// given node positions, from the analytic gradient (7.14-7.17) by central differences. Nodes that share no
// energy term are perturbed together (a colouring of the energy stencils), so the whole matrix costs 6
// gradients per colour, not per node. Used by the static and modal analyses of shell scenes.
#pragma once

#include <Eigen/Sparse>
#include <vector>

#include "relaxed_connectivity/shell/shell_energy.h"

namespace rc {

struct ShellHessianStats {
  size_t colors = 0;       ///< groups of nodes perturbed together
  size_t gradients = 0;    ///< gradient evaluations (6 per colour)
  double asymmetry = 0.0;  ///< max |H - H^T| / max |H| before symmetrising (the differences' error)
  double step = 0.0;       ///< the perturbation used
};

/// d^2 E / dx^2 at x (3 rows and columns per node, node-major), symmetrised. `step`: the central-difference
/// perturbation (0: 1e-6 of the node spacing). Throws std::invalid_argument if x does not hold one finite
/// position per node or step < 0.
Eigen::SparseMatrix<double> shellEnergyHessian(const ShellEnergy& energy, const std::vector<Vec3>& x,
                                               double step = 0.0, ShellHessianStats* stats = nullptr);

}  // namespace rc
