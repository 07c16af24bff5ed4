#include "relaxed_connectivity/fem/cholmod_solver.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include <dlfcn.h>
#include <omp.h>

#if RC_HAVE_CHOLMOD
#include <cholmod.h>
#endif

namespace rc {

namespace {

// OpenBLAS's pool functions, when the process has OpenBLAS (CHOLMOD's BLAS).
struct OpenBlasThreads {
  using SetThreads = void (*)(int);
  using Shutdown = int (*)();
  SetThreads set_threads = nullptr;
  Shutdown shutdown = nullptr;
  bool enabled = false;
  OpenBlasThreads() {
    set_threads = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    shutdown = reinterpret_cast<Shutdown>(dlsym(RTLD_DEFAULT, "blas_thread_shutdown_"));
  }
  bool active() const { return enabled && set_threads && shutdown; }
  static OpenBlasThreads& instance() {
    static OpenBlasThreads threads;
    return threads;
  }
};

// BLAS threads for a numeric factorisation; one thread and no spinning pool afterwards.
class FactorizationBlasThreads {
 public:
  FactorizationBlasThreads() : threads_(OpenBlasThreads::instance()), active_(threads_.active()) {
    if (active_) threads_.set_threads(omp_get_max_threads());
  }
  ~FactorizationBlasThreads() {
    if (!active_) return;
    threads_.set_threads(1);
    threads_.shutdown();
  }
  FactorizationBlasThreads(const FactorizationBlasThreads&) = delete;
  FactorizationBlasThreads& operator=(const FactorizationBlasThreads&) = delete;

 private:
  OpenBlasThreads& threads_;
  bool active_;
};

}  // namespace

void setCholmodBlasThreadControl(bool enabled) {
  OpenBlasThreads& threads = OpenBlasThreads::instance();
  threads.enabled = enabled;
  if (!enabled && threads.set_threads) threads.set_threads(omp_get_max_threads());
}

bool cholmodBlasThreadControl() {
  return OpenBlasThreads::instance().enabled;
}

bool openBlasThreadControlAvailable() {
  const OpenBlasThreads& threads = OpenBlasThreads::instance();
  return threads.set_threads && threads.shutdown;
}

bool cholmodAvailable() {
#if RC_HAVE_CHOLMOD
  return true;
#else
  return false;
#endif
}

#if RC_HAVE_CHOLMOD

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}
}  // namespace

struct CholmodSolver::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  cholmod_dense *x = nullptr, *y = nullptr, *e = nullptr;  // solve2 result and workspace, reused
  Eigen::SparseMatrix<double> compressed;                  // copy of a non-compressed input

  Impl() {
    cholmod_start(&common);
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.print = 0;  // failures become exceptions
    common.error_handler = nullptr;
  }
  ~Impl() {
    cholmod_free_dense(&x, &common);
    cholmod_free_dense(&y, &common);
    cholmod_free_dense(&e, &common);
    cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }

  // A view (no copy) of the lower triangle of a compressed column-major matrix.
  static cholmod_sparse view(const Eigen::SparseMatrix<double>& a) {
    cholmod_sparse s;
    std::memset(&s, 0, sizeof(s));
    s.nrow = static_cast<size_t>(a.rows());
    s.ncol = static_cast<size_t>(a.cols());
    s.nzmax = static_cast<size_t>(a.nonZeros());
    s.p = const_cast<int*>(a.outerIndexPtr());
    s.i = const_cast<int*>(a.innerIndexPtr());
    s.x = const_cast<double*>(a.valuePtr());
    s.stype = -1;  // symmetric, lower triangle used, upper ignored
    s.itype = CHOLMOD_INT;
    s.xtype = CHOLMOD_REAL;
    s.dtype = CHOLMOD_DOUBLE;
    s.sorted = 1;
    s.packed = 1;
    return s;
  }

  const Eigen::SparseMatrix<double>& compressedView(const Eigen::SparseMatrix<double>& a) {
    if (a.isCompressed()) return a;
    compressed = a;
    compressed.makeCompressed();
    return compressed;
  }
};

CholmodSolver::CholmodSolver() : impl_(std::make_unique<Impl>()) {}

CholmodSolver::~CholmodSolver() = default;
CholmodSolver::CholmodSolver(CholmodSolver&&) noexcept = default;
CholmodSolver& CholmodSolver::operator=(CholmodSolver&&) noexcept = default;

bool CholmodSolver::patternMatches(const Eigen::SparseMatrix<double>& a) const {
  if (num_analyses_ == 0 || a.cols() + 1 != static_cast<Eigen::Index>(outer_.size()) ||
      a.rows() != a.cols() || !a.isCompressed() || a.nonZeros() != static_cast<Eigen::Index>(inner_.size()))
    return false;
  return std::equal(outer_.begin(), outer_.end(), a.outerIndexPtr()) &&
         std::equal(inner_.begin(), inner_.end(), a.innerIndexPtr());
}

void CholmodSolver::analyzePattern(const Eigen::SparseMatrix<double>& input) {
  if (input.rows() != input.cols() || input.rows() == 0)
    throw std::invalid_argument("CholmodSolver: the matrix must be square and non-empty, got " +
                                std::to_string(input.rows()) + " x " + std::to_string(input.cols()));
  const Clock::time_point start = Clock::now();
  const Eigen::SparseMatrix<double>& a = impl_->compressedView(input);
  cholmod_sparse view = Impl::view(a);
  cholmod_free_factor(&impl_->factor, &impl_->common);
  factorized_ = false;
  impl_->factor = cholmod_analyze(&view, &impl_->common);
  if (!impl_->factor || impl_->common.status < CHOLMOD_OK)
    throw std::runtime_error("CholmodSolver: symbolic analysis failed (CHOLMOD status " +
                             std::to_string(impl_->common.status) + ")");
  outer_.assign(a.outerIndexPtr(), a.outerIndexPtr() + a.cols() + 1);
  inner_.assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
  ++num_analyses_;
  analysis_seconds_ += secondsSince(start);
}

void CholmodSolver::factorize(const Eigen::SparseMatrix<double>& input) {
  const Eigen::SparseMatrix<double>& a = impl_->compressedView(input);
  if (!patternMatches(a)) analyzePattern(a);
  const Clock::time_point start = Clock::now();
  cholmod_sparse view = Impl::view(a);
  factorized_ = false;
  int ok = 0;
  {
    FactorizationBlasThreads blas_threads;
    ok = cholmod_factorize(&view, impl_->factor, &impl_->common);
  }
  if (!ok || impl_->common.status < CHOLMOD_OK)
    throw std::runtime_error("CholmodSolver: numeric factorisation failed (CHOLMOD status " +
                             std::to_string(impl_->common.status) + ")");
  if (impl_->common.status == CHOLMOD_NOT_POSDEF || impl_->factor->minor < impl_->factor->n)
    throw std::runtime_error("CholmodSolver: the matrix is not positive definite (leading minor of order " +
                             std::to_string(impl_->factor->minor + 1) + " of " +
                             std::to_string(impl_->factor->n) + ")");
  factorized_ = true;
  ++num_factorizations_;
  factorization_seconds_ += secondsSince(start);
}

void CholmodSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  Eigen::Map<const Eigen::MatrixXd> b_columns(b.data(), b.size(), 1);
  x.resize(b.size());
  Eigen::Map<Eigen::MatrixXd> x_columns(x.data(), x.size(), 1);
  solveColumns(b_columns.data(), b.size(), 1, x_columns.data());
}

void CholmodSolver::solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
  x.resize(b.rows(), b.cols());
  if (b.cols() > 0) solveColumns(b.data(), b.rows(), b.cols(), x.data());
}

void CholmodSolver::solveColumns(const double* b, Eigen::Index rows, Eigen::Index cols, double* x) {
  if (!factorized_) throw std::logic_error("CholmodSolver::solve: no successful factorisation");
  if (rows != static_cast<Eigen::Index>(impl_->factor->n))
    throw std::invalid_argument("CholmodSolver::solve: right-hand side has " + std::to_string(rows) +
                                " entries for " + std::to_string(impl_->factor->n) + " unknowns");
  cholmod_dense rhs;
  std::memset(&rhs, 0, sizeof(rhs));
  rhs.nrow = rhs.d = static_cast<size_t>(rows);
  rhs.ncol = static_cast<size_t>(cols);
  rhs.nzmax = rhs.nrow * rhs.ncol;
  rhs.x = const_cast<double*>(b);
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  if (!cholmod_solve2(CHOLMOD_A, impl_->factor, &rhs, nullptr, &impl_->x, nullptr, &impl_->y, &impl_->e,
                      &impl_->common))
    throw std::runtime_error("CholmodSolver::solve: CHOLMOD status " + std::to_string(impl_->common.status));
  std::memcpy(x, impl_->x->x, sizeof(double) * static_cast<size_t>(rows * cols));
}

double CholmodSolver::factorNonZeros() const {
  if (!impl_->factor || !factorized_) return 0.0;
  // Supernodal: entries of the dense supernode blocks (common.lnz is set by the analysis).
  return impl_->common.lnz;
}

bool CholmodSolver::supernodal() const {
  return impl_->factor && impl_->factor->is_super;
}

#else  // !RC_HAVE_CHOLMOD

struct CholmodSolver::Impl {};

namespace {
[[noreturn]] void lacksCholmod() {
  throw std::runtime_error(
      "CholmodSolver: this build lacks CHOLMOD (install libsuitesparse-dev and reconfigure)");
}
}  // namespace

CholmodSolver::CholmodSolver() {
  lacksCholmod();
}
CholmodSolver::~CholmodSolver() = default;
CholmodSolver::CholmodSolver(CholmodSolver&&) noexcept = default;
CholmodSolver& CholmodSolver::operator=(CholmodSolver&&) noexcept = default;
void CholmodSolver::analyzePattern(const Eigen::SparseMatrix<double>&) {
  lacksCholmod();
}
void CholmodSolver::factorize(const Eigen::SparseMatrix<double>&) {
  lacksCholmod();
}
void CholmodSolver::solve(const Eigen::VectorXd&, Eigen::VectorXd&) {
  lacksCholmod();
}
void CholmodSolver::solve(const Eigen::MatrixXd&, Eigen::MatrixXd&) {
  lacksCholmod();
}
void CholmodSolver::solveColumns(const double*, Eigen::Index, Eigen::Index, double*) {
  lacksCholmod();
}
bool CholmodSolver::patternMatches(const Eigen::SparseMatrix<double>&) const {
  return false;
}
double CholmodSolver::factorNonZeros() const {
  return 0.0;
}
bool CholmodSolver::supernodal() const {
  return false;
}

#endif

Eigen::VectorXd CholmodSolver::solve(const Eigen::VectorXd& b) {
  Eigen::VectorXd x;
  solve(b, x);
  return x;
}

}  // namespace rc
