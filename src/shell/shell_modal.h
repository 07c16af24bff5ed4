// Modal analysis of a point-sampled thin shell (scene key analysis: modal): the lowest natural frequencies
// and mode shapes about given node positions (the rest shape, or a loaded equilibrium), K phi = omega^2 M phi
// with the stiffness of the shell energy (shell_hessian.h), the lumped node masses rho a_i^0 and the held
// components fixed. A shell with no held component has six rigid modes at ~0 Hz, which are reported as such.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "relaxed_connectivity/shell/shell_loads.h"

namespace rc {

struct ShellModalResult {
  Eigen::VectorXd frequencies;  ///< [Hz], ascending
  Eigen::MatrixXd modes;        ///< one column per frequency, 3 per node, mass-normalised (phi^T M phi = 1)
  int rigid_modes = 0;          ///< leading modes with omega^2 below 1e-8 of the shell's stiffness scale
  size_t hessian_colors = 0;
  double seconds = 0.0;
};

/// True when this build can solve it (Spectra).
bool shellModalAvailable();

/// The `modes` lowest modes about positions x. Throws std::invalid_argument for bad sizes, regions or counts,
/// std::runtime_error without Spectra or when the eigensolver does not converge.
ShellModalResult solveShellModal(const ShellEnergy& energy, const std::vector<Vec3>& x,
                                 const std::vector<ShellHeld>& held, int modes);

}  // namespace rc
