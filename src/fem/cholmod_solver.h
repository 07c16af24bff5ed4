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

/// OpenBLAS thread pool control (process-wide, off by default: on the idle 2-core machine the bunny of
/// Fig. 9.10 measured 307-319 ms/frame off against 322-350 on, since re-creating the pool after each of the
/// 200 factorisations costs more than the spinning it saves). OpenBLAS's worker threads spin (yield) for
/// ~0.1 s after every threaded BLAS call and compete with the OpenMP threads of the next phase (rotations)
/// on few cores. On: numeric factorisations use omp_get_max_threads() BLAS threads, everything else one, and
/// the pool is shut down after each factorisation (OpenBLAS re-creates it on demand). Off: OpenBLAS as
/// configured (OPENBLAS_NUM_THREADS). No effect with another BLAS (the functions are looked up at run time).
void setCholmodBlasThreadControl(bool enabled);
bool cholmodBlasThreadControl();
/// Whether the OpenBLAS thread functions were found in the process.
bool openBlasThreadControlAvailable();

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
  /// Whether the last factorize() succeeded (solve() may be called).
  bool factorized() const { return factorized_; }
  int numAnalyses() const { return num_analyses_; }
  int numFactorizations() const { return num_factorizations_; }
  /// Wall time spent in symbolic analyses / numeric factorisations so far, seconds.
  double analysisSeconds() const { return analysis_seconds_; }
  double factorizationSeconds() const { return factorization_seconds_; }
  /// Entries of L (0 before the first factorisation); supernodal() tells whether CHOLMOD chose supernodes.
  double factorNonZeros() const;
  bool supernodal() const;

 private:
  void solveColumns(const double* b, Eigen::Index rows, Eigen::Index cols, double* x);  // column-major
  struct Impl;  // cholmod_common, the factor and solve workspace
  std::unique_ptr<Impl> impl_;
  std::vector<int> outer_, inner_;  // analysed pattern (compressed column, lower triangle)
  int num_analyses_ = 0, num_factorizations_ = 0;
  double analysis_seconds_ = 0.0, factorization_seconds_ = 0.0;
  bool factorized_ = false;
};

}  // namespace rc
