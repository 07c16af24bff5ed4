#include "relaxed_connectivity/shell/shell_modal.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "relaxed_connectivity/core/lowest_modes.h"
#include "relaxed_connectivity/shell/shell_hessian.h"

namespace rc {

bool shellModalAvailable() {
  return lowestModesAvailable();
}

ShellModalResult solveShellModal(const ShellEnergy& energy, const std::vector<Vec3>& x,
                                 const std::vector<ShellHeld>& held, int modes) {
  const auto t0 = std::chrono::steady_clock::now();
  const ShellNodes& nodes = energy.nodes();
  const size_t n = nodes.size();
  const std::vector<uint8_t> mask = shellHeldMask(n, held);
  std::vector<char> held_dof(3 * n, 0);
  Eigen::VectorXd mass(3 * n);
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      held_dof[3 * i + d] = char(mask[i] >> d & 1), mass[3 * i + d] = energy.masses()[i];
  ShellHessianStats stats;
  const Eigen::SparseMatrix<double> K = shellEnergyHessian(energy, x, 0.0, &stats);
  // The stiffness scale: omega^2 of a bending wave of the shell's size L (K_b / (rho L^4)) or a membrane one
  // (K_s / (rho L^2)), whichever is larger. A shift just below 0 keeps the shift-invert regular when rigid
  // motions are free.
  Vec3 lo = nodes.rest_positions[0], hi = lo;
  for (const Vec3& p : nodes.rest_positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double size = std::max((hi - lo).norm(), nodes.spacing);
  const ShellMaterial& m = energy.material();
  const double scale =
      std::max(m.bending_stiffness / std::pow(size, 4), m.stretch_stiffness / (size * size)) /
      m.areal_density;
  const LowestModes solved = lowestModes(K, mass, held_dof, modes, -1e-6 * scale);
  ShellModalResult result;
  result.frequencies = solved.omega2.cwiseMax(0.0).cwiseSqrt() / (2 * M_PI);
  result.modes = solved.modes;
  while (result.rigid_modes < modes && solved.omega2[result.rigid_modes] < 1e-8 * scale) ++result.rigid_modes;
  result.hessian_colors = stats.colors;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace rc
