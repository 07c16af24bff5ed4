// The lowest natural modes of a lumped-mass structure, K phi = omega^2 M phi over its free degrees of freedom
// (M diagonal), by shift-invert Lanczos (Spectra, libspectra-dev) on M^-1/2 K M^-1/2. Shared by the modal
// analyses of FEM and shell scenes.
#pragma once

#include <Eigen/Core>
#include <Eigen/Sparse>
#include <vector>

namespace rc {

struct LowestModes {
  Eigen::VectorXd omega2;  ///< omega^2, ascending
  Eigen::MatrixXd modes;  ///< one column per mode over all dofs, mass-normalised (phi^T M phi = 1), 0 on held
};

/// True when this build has Spectra; lowestModes throws std::runtime_error otherwise.
bool lowestModesAvailable();

/// The `wanted` modes with omega^2 nearest `shift` (below the lowest: the lowest modes). K: symmetric
/// stiffness over all dofs; mass: per dof, > 0; held: per dof, nonzero = fixed at 0. shift 0 needs K regular
/// on the free dofs (no free rigid motion); a slightly negative shift admits rigid modes (omega^2 ~ 0).
/// Throws std::invalid_argument for sizes that do not match or wanted outside [1, free dofs),
/// std::runtime_error when the eigensolver does not converge.
LowestModes lowestModes(const Eigen::SparseMatrix<double>& K, const Eigen::VectorXd& mass,
                        const std::vector<char>& held, int wanted, double shift = 0.0);

}  // namespace rc
