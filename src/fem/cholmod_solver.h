// Supernodal sparse Cholesky (CHOLMOD, SuiteSparse; BLAS-3 supernodes, fast with OpenBLAS) for symmetric
// positive definite systems such as the implicit Euler matrix M + dt C + dt^2 K_w (9.20): the symbolic
// analysis (fill-reducing ordering, supernodes) is done once per sparsity pattern, the numeric factorisation
// per matrix, then solves. Only the lower triangle is read (a full symmetric matrix or its lower half).
// CHOLMOD is optional (RC_HAVE_CHOLMOD); without it the constructor throws std::runtime_error.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>
#include <vector>

namespace rc {

/// Whether this build links CHOLMOD (RC_HAVE_CHOLMOD).
bool cholmodAvailable();

class CholmodSolver {
 public:
  /// Starts a cholmod_common (supernodal, silent). Throws std::runtime_error when the build lacks CHOLMOD.
  CholmodSolver();
  ~CholmodSolver();
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;
  CholmodSolver(CholmodSolver&&) noexcept;
  CholmodSolver& operator=(CholmodSolver&&) noexcept;

  /// Symbolic analysis of the pattern of a's lower triangle. Throws std::invalid_argument for a non-square
  /// matrix, std::runtime_error when CHOLMOD fails.
  void analyzePattern(const Eigen::SparseMatrix<double>& a);
  /// Numeric factorisation L L^T = P A P^T; analyses first when a's pattern differs from the analysed one.
  /// Throws std::runtime_error naming the column when A is not positive definite.
  void factorize(const Eigen::SparseMatrix<double>& a);
  /// x = A^-1 b with the last factorisation. Throws std::logic_error before factorize(),
  /// std::invalid_argument for a wrong size.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  Eigen::VectorXd solve(const Eigen::VectorXd& b);
  /// X = A^-1 B for several right-hand sides at once (blocked supernodal solve, cheaper than column by
  /// column).
  void solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x);

  bool patternMatches(const Eigen::SparseMatrix<double>& a) const;
  int numAnalyses() const { return num_analyses_; }
  int numFactorizations() const { return num_factorizations_; }
  /// Entries of L (0 before the first factorisation); supernodal() tells whether CHOLMOD chose supernodes.
  double factorNonZeros() const;
  bool supernodal() const;

 private:
  void solveColumns(const double* b, Eigen::Index rows, Eigen::Index cols, double* x);  // column-major
  struct Impl;  // cholmod_common, the factor and solve workspace
  std::unique_ptr<Impl> impl_;
  std::vector<int> outer_, inner_;  // analysed pattern (compressed column, lower triangle)
  int num_analyses_ = 0, num_factorizations_ = 0;
  bool factorized_ = false;
};

}  // namespace rc
