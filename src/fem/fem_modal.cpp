#include "relaxed_connectivity/fem/fem_modal.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/lowest_modes.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"

namespace rc {

bool femModalAvailable() {
  return lowestModesAvailable();
}

FemModalResult solveFemModal(const FemScene& scene) {
  if (scene.analysis != FemAnalysis::kModal)
    throw std::invalid_argument("solveFemModal: the scene's analysis is not modal");
  if (!lowestModesAvailable())
    throw std::runtime_error("solveFemModal: this build has no Spectra (libspectra-dev)");
  const auto start = std::chrono::steady_clock::now();
  const LinearElasticModel model(*scene.mesh, scene.youngs_modulus, scene.poisson_ratio, scene.density,
                                 scene.quadrature);
  const int dofs = model.numDofs();
  std::vector<char> held(size_t(dofs), 0);
  for (const FemHeldRegion& region : scene.held)
    for (int i : region.nodes)
      for (int k = 0; k < 3; ++k)
        if (region.components[size_t(k)]) held[size_t(3 * i + k)] = 1;
  Eigen::VectorXd mass(dofs);
  for (int d = 0; d < dofs; ++d) mass[d] = model.lumpedMasses()[size_t(d / 3)];
  // Shift-invert about 0: the lowest frequencies.
  const LowestModes modes = lowestModes(model.stiffness(), mass, held, scene.modes, 0.0);
  // A rigid motion left free has omega^2 ~ 0 (round-off of the shift-invert), far below the scale E / (rho
  // d^2) of the mesh (d its diagonal).
  Vec3 lo = model.mesh().node(0), hi = lo;
  for (int i = 0; i < model.mesh().numNodes(); ++i) {
    lo = lo.cwiseMin(model.mesh().node(i));
    hi = hi.cwiseMax(model.mesh().node(i));
  }
  const double scale = scene.youngs_modulus / (scene.density * (hi - lo).squaredNorm());
  for (int m = 0; m < modes.omega2.size(); ++m)
    if (!(modes.omega2[m] > 1e-8 * scale))
      throw std::runtime_error(
          "solveFemModal: a mode of frequency ~0: the held regions leave a rigid motion free");
  FemModalResult result;
  result.frequencies = modes.omega2.cwiseMax(0.0).cwiseSqrt() / (2 * M_PI);
  result.modes = modes.modes;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace rc
