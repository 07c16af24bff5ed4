// Static equilibrium of a point-sampled thin shell (scene key analysis: static): the node positions where the
// elastic forces (7.14-7.17) balance the loads and gravity, with held components fixed. Geometrically
// nonlinear (the shell energy itself): Newton's method on the stiffness (shell_hessian.h) with a line search
// on the total potential, the loads applied in increments.
#pragma once

#include <vector>

#include "relaxed_connectivity/shell/shell_loads.h"

namespace rc {

struct ShellStaticOptions {
  int load_steps = 1;  ///< the loads and held displacements reach their full value in this many increments
  int max_iterations = 50;  ///< Newton iterations per increment
  double tolerance = 1e-9;  ///< converged when |free residual| <= tolerance * |loads| (or an absolute floor)
};

struct ShellStaticResult {
  std::vector<Vec3> positions;
  double max_displacement = 0.0;         ///< max |x - x_rest| over the nodes
  std::vector<Vec3> held_reactions;      ///< per held region: the sum over its held components of grad E - f
  std::vector<Vec3> load_displacements;  ///< per load: the mean displacement of its nodes
  int iterations = 0;                    ///< Newton iterations, all increments
  double residual = 0.0;                 ///< |free residual| / |loads| at the end
  size_t hessian_colors = 0;             ///< of the stiffness matrices (shell_hessian.h)
  double seconds = 0.0;
};

/// Solves from the rest positions. Throws std::invalid_argument for no held component, bad options or bad
/// regions (shellLoadForces, shellHeldMask), std::runtime_error when an increment does not converge or a load
/// moves a free rigid motion (a displacement beyond 1000 x the shell's size), naming the increment.
ShellStaticResult solveShellStatic(const ShellEnergy& energy, const std::vector<ShellHeld>& held,
                                   const std::vector<ShellLoad>& loads, const Vec3& gravity,
                                   const ShellStaticOptions& options = {});

}  // namespace rc
