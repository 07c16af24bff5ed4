#include "relaxed_connectivity/core/lowest_modes.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#if defined(RC_HAVE_SPECTRA)
#include <Spectra/MatOp/SparseSymShiftSolve.h>
#include <Spectra/SymEigsShiftSolver.h>
#endif

namespace rc {

bool lowestModesAvailable() {
#if defined(RC_HAVE_SPECTRA)
  return true;
#else
  return false;
#endif
}

LowestModes lowestModes(const Eigen::SparseMatrix<double>& K, const Eigen::VectorXd& mass,
                        const std::vector<char>& held, int wanted, double shift) {
  const int dofs = int(K.rows());
  if (K.cols() != dofs || mass.size() != dofs || int(held.size()) != dofs)
    throw std::invalid_argument("lowestModes: K, masses and held flags of different sizes");
  std::vector<int> free_index(size_t(dofs), -1), free_dofs;
  for (int d = 0; d < dofs; ++d) {
    if (held[size_t(d)]) continue;
    if (!(mass[d] > 0.0))
      throw std::invalid_argument("lowestModes: dof " + std::to_string(d) + " has no mass");
    free_index[size_t(d)] = int(free_dofs.size());
    free_dofs.push_back(d);
  }
  const int n = int(free_dofs.size());
  if (wanted < 1 || wanted >= n)
    throw std::invalid_argument("lowestModes: " + std::to_string(wanted) + " modes of " + std::to_string(n) +
                                " free dofs (need 1 <= modes < free dofs)");
#if defined(RC_HAVE_SPECTRA)
  // M^-1/2 K M^-1/2 over the free dofs (M diagonal): a standard symmetric problem with the same eigenvalues.
  Eigen::VectorXd inv_sqrt_mass(n);
  for (int f = 0; f < n; ++f) inv_sqrt_mass[f] = 1.0 / std::sqrt(mass[free_dofs[size_t(f)]]);
  std::vector<Eigen::Triplet<double>> triplets;
  for (int col = 0; col < K.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, col); it; ++it) {
      const int r = free_index[size_t(it.row())], c = free_index[size_t(it.col())];
      if (r >= 0 && c >= 0) triplets.emplace_back(r, c, inv_sqrt_mass[r] * it.value() * inv_sqrt_mass[c]);
    }
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(triplets.begin(), triplets.end());
  Spectra::SparseSymShiftSolve<double> op(a);
  const int ncv = std::min(n, std::max(2 * wanted + 1, wanted + 20));
  Spectra::SymEigsShiftSolver<Spectra::SparseSymShiftSolve<double>> eigs(op, wanted, ncv, shift);
  eigs.init();
  eigs.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10);
  if (eigs.info() != Spectra::CompInfo::Successful)
    throw std::runtime_error(
        "lowestModes: the eigensolver did not converge (are all rigid motions held? a free body has zero "
        "frequencies)");
  const Eigen::VectorXd lambda = eigs.eigenvalues();
  const Eigen::MatrixXd psi = eigs.eigenvectors();
  std::vector<int> order(static_cast<size_t>(wanted));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int x, int y) { return lambda[x] < lambda[y]; });
  LowestModes result;
  result.omega2.resize(wanted);
  result.modes = Eigen::MatrixXd::Zero(dofs, wanted);
  for (int m = 0; m < wanted; ++m) {
    const int j = order[size_t(m)];
    result.omega2[m] = lambda[j];
    for (int f = 0; f < n; ++f) result.modes(free_dofs[size_t(f)], m) = inv_sqrt_mass[f] * psi(f, j);  // phi
  }
  return result;
#else
  (void)shift;
  throw std::runtime_error("lowestModes: this build has no Spectra (libspectra-dev)");
#endif
}

}  // namespace rc
