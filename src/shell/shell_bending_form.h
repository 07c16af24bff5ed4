// Per-node bending energy as a quadratic form of the fiber curvature changes (thesis 7.2.2, (7.3), (7.9)):
// U_b,i = K_b / 2 a_i^0 d^T Q_i d, d_k = theta_k / (3/4 l_k) - theta_k^0 / (3/4 l_k^0) over node i's fibers.
//
// The isotropic formula U_b = K_b/2 [4 sum_k w_k d_k^2 - 2 (sum_k w_k d_k)^2] (shell_energy.h) equals
// K_b/2 |dS|_F^2 only where the fibers' directions are isotropic. At an open boundary they are not (a node at
// a straight edge has one straight fiber along the edge and kinked ones into the sheet): measured on a square
// grid, an edge node stored 1.4-1.6 x the bending energy of a cylinder along the edge and 0.03 x across it.
// Q_i instead fits the curvature change tensor dS to the fibers' measured responses and charges its Frobenius
// norm, plus the isotropic formula's penalty on what no tensor explains:
//   a_k = d d_k / d(S_uu, S_uv, S_vv)   (calibrated per fiber: central differences of the quadratic height
//                                        fields over the node's stencil flattened onto its tangent plane,
//                                        through the energy's own measurement; on a curved rest shape the
//                                        fibers' response to more curvature is lower by O(kappa^2 h^2) than
//                                        in the plane, which the isotropic formula also leaves alone),
//   s = (A^T W A)^-1 A^T W d,   r = d - A s,   d^T Q d = s_uu^2 + 2 s_uv^2 + s_vv^2 + 4 sum_k w_k r_k^2.
// Exact for every constant curvature change at every node whose fibers span the three components; for
// isotropic fiber directions it reduces to the isotropic formula. A component the fibers barely see (at an
// edge node, the curvature across the edge) is left out of the fit, its response charged as residual; nodes
// with fewer than 3 fibers or none seen keep the isotropic formula.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/shell/shell_fibers.h"
#include "relaxed_connectivity/shell/shell_nodes.h"

namespace rc {

struct ShellBendingForms {
  std::vector<size_t> offsets;  ///< node i's m x m form (row-major) at values[offsets[i]], m its fiber count
  std::vector<double> values;
  /// Largest eigenvalue of W^-1/2 Q W^-1/2 per node (W = diag(fiber weights)): Q <= bound W, for the
  /// stable-step estimate. 4 for the isotropic formula.
  std::vector<double> bound;
  std::vector<uint8_t> fitted;  ///< per node: 1 if it uses the fitted form (0: the isotropic one)
  size_t fitted_nodes = 0;      ///< their count
  double min_response = 0.0;    ///< the setting they were built with
  size_t reused_nodes = 0;      ///< forms copied from an earlier build (ShellBendingFormsReuse)
};

/// An earlier build and the topology it was built for: a node that kept its neighbours and its fibers (ends
/// and weights; rest positions never change) keeps its form (re-neighbouring after cracks changes few nodes).
struct ShellBendingFormsReuse {
  const ShellBendingForms* forms = nullptr;
  const ShellNodes* nodes = nullptr;
  const ShellFibers* fibers = nullptr;
};

/// The forms of every node from the rest positions and the fibers' weights, rest lengths and rest angles.
/// Components with an eigenvalue of D^-1/2 (A^T W A) D^-1/2 (D = diag(1, 2, 1); 1/2, 1/4, 1/4 for isotropic
/// directions) at or below `min_response` are left out of the fit; a kept one with eigenvalue lambda makes
/// the form up to 1/lambda x stiffer than the fibers' weights, which shrinks the stable step with its root.
ShellBendingForms buildShellBendingForms(const ShellNodes& nodes, const ShellFibers& fibers,
                                         double min_response = 0.15,
                                         const ShellBendingFormsReuse* previous = nullptr);

}  // namespace rc
