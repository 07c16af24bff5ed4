// Modal analysis of an FEM scene (key analysis: modal): the lowest natural frequencies and mode shapes of the
// placed rest mesh, K phi = omega^2 M phi with the lumped masses (9.21) and the scene's held regions (held
// components fixed at zero), by shift-invert Lanczos (Spectra).
#pragma once

#include <Eigen/Core>

#include "relaxed_connectivity/fem/fem_scene.h"

namespace rc {

struct FemModalResult {
  Eigen::VectorXd frequencies;  ///< [Hz], ascending
  Eigen::MatrixXd modes;        ///< one column per frequency, 3 per node, mass-normalised (phi^T M phi = 1)
  double seconds = 0.0;
};

/// True when this build has Spectra (libspectra-dev); solveFemModal throws std::runtime_error otherwise.
bool femModalAvailable();

/// The scene's `modes` lowest modes. Throws std::invalid_argument for a scene that is not modal or asks for
/// more modes than it has free dofs, std::runtime_error if the eigensolver does not converge (or a held
/// region leaves a rigid motion free) or without Spectra.
FemModalResult solveFemModal(const FemScene& scene);

}  // namespace rc
