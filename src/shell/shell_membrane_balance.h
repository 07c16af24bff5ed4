// Membrane patch-test calibration of fiber stiffness (thesis 7.2.1, 7.3.4 per-fiber stiffness).
//
// The fiber membrane energy (7.5-7.7) of an irregular node sampling is not in tangential equilibrium under a
// uniform stretch: on the balloon of Fig. 7.10 the net tangential force on a node is as large as the normal
// one, so a uniformly pressurised sphere settles with fiber strains from 0.1x to 3x the mean and tears where
// the sampling is irregular, at a third of the pressure the material can bear. A consistent membrane carries
// a uniform stretch with no force on interior nodes of a flat sheet and a purely normal force on a curved
// one.
//
// Under a uniform stretch x = sigma X every fiber term of (7.7) pulls along the arc-length gradient with a
// tension linear in the fiber stretch factors s_k (Fiber::stretch_scale); with c the factors relative to the
// current ones, the tangential forces on interior nodes are F c = 0 for the balanced membrane. The
// calibration seeks the least change of c from 1 with F c = 0 by proximal steps
// c += F^T (F F^T + mu I)^-1 (-F c) (sparse LDLT), keeps c within [min_factor, max_factor] by fixing the
// clamped factors, scales c so a uniform stretch stores the same energy as before (sum a_i w_k s_k kept),
// and multiplies the stretch factors by c. Bending and masses do not change.
#pragma once

#include <cstddef>

#include "relaxed_connectivity/shell/shell_fibers.h"
#include "relaxed_connectivity/shell/shell_nodes.h"

namespace rc {

struct ShellMembraneBalanceOptions {
  double min_factor = 0.1;  ///< bounds of the per-fiber correction c_k
  double max_factor = 10.0;
  /// Nodes whose neighbour directions leave a tangent-plane gap wider than this (radians) are boundary
  /// nodes: a uniform stretch legitimately pulls them outward, so they are not constrained.
  double boundary_gap = 2.0 * 3.14159265358979323846 / 3.0;
  int iterations = 50;         ///< proximal steps (each one solve; a refactorisation after new clamps)
  double step_penalty = 1e-3;  ///< mu relative to the mean diagonal of F F^T
};

struct ShellMembraneBalanceReport {
  size_t constrained_nodes = 0;  ///< interior nodes whose tangential force was balanced
  size_t clamped_fibers = 0;     ///< factors held at a bound
  /// RMS tangential force on the constrained nodes under a uniform stretch, relative to the RMS fiber force
  /// (tension times arc-length gradient) there, before and after.
  double residual_before = 0.0, residual_after = 0.0;
  double min_factor = 1.0, max_factor = 1.0;  ///< range of the applied corrections
};

/// Multiplies Fiber::stretch_scale of `fibers` (built for `nodes`, at their rest state) by the patch-test
/// corrections. Throws std::invalid_argument for fibers of another node set or bad options.
ShellMembraneBalanceReport balanceMembraneStiffness(const ShellNodes& nodes, ShellFibers& fibers,
                                                    const ShellMembraneBalanceOptions& options = {});

/// The relative RMS tangential force of the current stretch factors (residual_before of the above), without
/// changing anything.
double membraneImbalance(const ShellNodes& nodes, const ShellFibers& fibers,
                         const ShellMembraneBalanceOptions& options = {});

}  // namespace rc
