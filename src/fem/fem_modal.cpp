#include "relaxed_connectivity/fem/fem_modal.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/fem/linear_elasticity.h"

#if defined(RC_HAVE_SPECTRA)
#include <Spectra/MatOp/SparseSymShiftSolve.h>
#include <Spectra/SymEigsShiftSolver.h>
#endif

namespace rc {

bool femModalAvailable() {
#if defined(RC_HAVE_SPECTRA)
  return true;
#else
  return false;
#endif
}

FemModalResult solveFemModal(const FemScene& scene) {
  if (scene.analysis != FemAnalysis::kModal)
    throw std::invalid_argument("solveFemModal: the scene's analysis is not modal");
#if defined(RC_HAVE_SPECTRA)
  const auto start = std::chrono::steady_clock::now();
  const LinearElasticModel model(*scene.mesh, scene.youngs_modulus, scene.poisson_ratio, scene.density,
                                 scene.quadrature);
  const int dofs = model.numDofs();
  std::vector<char> held(size_t(dofs), 0);
  for (const FemHeldRegion& region : scene.held)
    for (int i : region.nodes)
      for (int k = 0; k < 3; ++k)
        if (region.components[size_t(k)]) held[size_t(3 * i + k)] = 1;
  std::vector<int> free_index(size_t(dofs), -1), free_dofs;
  for (int d = 0; d < dofs; ++d)
    if (!held[size_t(d)]) free_index[size_t(d)] = int(free_dofs.size()), free_dofs.push_back(d);
  const int n = int(free_dofs.size()), wanted = scene.modes;
  if (wanted < 1 || wanted >= n)
    throw std::invalid_argument("solveFemModal: " + std::to_string(wanted) + " modes of " +
                                std::to_string(n) + " free dofs (need 1 <= modes < free dofs)");
  // M^-1/2 K M^-1/2 over the free dofs (M diagonal): a standard symmetric problem with the same eigenvalues.
  Eigen::VectorXd inv_sqrt_mass(n);
  for (int f = 0; f < n; ++f)
    inv_sqrt_mass[f] = 1.0 / std::sqrt(model.lumpedMasses()[free_dofs[size_t(f)] / 3]);
  std::vector<Eigen::Triplet<double>> triplets;
  const Eigen::SparseMatrix<double>& k = model.stiffness();
  for (int col = 0; col < k.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(k, col); it; ++it) {
      const int r = free_index[size_t(it.row())], c = free_index[size_t(it.col())];
      if (r >= 0 && c >= 0) triplets.emplace_back(r, c, inv_sqrt_mass[r] * it.value() * inv_sqrt_mass[c]);
    }
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(triplets.begin(), triplets.end());
  // Shift-invert about 0: the eigenvalues of A nearest 0, i.e. the lowest frequencies.
  Spectra::SparseSymShiftSolve<double> op(a);
  const int ncv = std::min(n, std::max(2 * wanted + 1, wanted + 20));
  Spectra::SymEigsShiftSolver<Spectra::SparseSymShiftSolve<double>> eigs(op, wanted, ncv, 0.0);
  eigs.init();
  eigs.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10);
  if (eigs.info() != Spectra::CompInfo::Successful)
    throw std::runtime_error(
        "solveFemModal: the eigensolver did not converge (are all rigid motions held? a free body has zero "
        "frequencies)");
  const Eigen::VectorXd lambda = eigs.eigenvalues();
  // A rigid motion left free has omega^2 ~ 0 (round-off of the shift-invert), far below the scale E / (rho
  // d^2) of the mesh (d its diagonal).
  Vec3 lo = model.mesh().node(0), hi = lo;
  for (int i = 0; i < model.mesh().numNodes(); ++i) {
    lo = lo.cwiseMin(model.mesh().node(i));
    hi = hi.cwiseMax(model.mesh().node(i));
  }
  const double scale = scene.youngs_modulus / (scene.density * (hi - lo).squaredNorm());
  for (int m = 0; m < wanted; ++m)
    if (!(lambda[m] > 1e-8 * scale))
      throw std::runtime_error(
          "solveFemModal: a mode of frequency ~0: the held regions leave a rigid motion free");
  const Eigen::MatrixXd psi = eigs.eigenvectors();
  std::vector<int> order(static_cast<size_t>(wanted));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int x, int y) { return lambda[x] < lambda[y]; });
  FemModalResult result;
  result.frequencies.resize(wanted);
  result.modes = Eigen::MatrixXd::Zero(dofs, wanted);
  for (int m = 0; m < wanted; ++m) {
    const int j = order[size_t(m)];
    result.frequencies[m] = std::sqrt(std::max(lambda[j], 0.0)) / (2 * M_PI);
    for (int f = 0; f < n; ++f) result.modes(free_dofs[size_t(f)], m) = inv_sqrt_mass[f] * psi(f, j);  // phi
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
#else
  throw std::runtime_error("solveFemModal: this build has no Spectra (libspectra-dev)");
#endif
}

}  // namespace rc
