// Cholesky factorisation A = L L^T of a small symmetric positive-definite matrix of 3x3 blocks (one per node
// of a 3D mass-spring system) whose lower triangle is nonzero only within an envelope (a skyline): block row
// i from block column first(i) to the diagonal. The factor keeps that envelope (no fill outside it), so the
// work is the envelope's and not n^3 / 3, in fixed-size 3x3 products without per-call set-up: the flat
// brush's implicit step (12 nodes, rows reaching back at most 4 nodes) factors in ~1 us.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace rc {

class BlockEnvelopeCholesky {
 public:
  /// Sets the pattern: block row i may be nonzero from block column first[i] (0 <= first[i] <= i) to the
  /// diagonal. Throws std::invalid_argument for a first column out of range. The values become zero.
  void setPattern(std::vector<int> first);
  /// Block rows (nodes); the matrix is 3 size() x 3 size().
  int size() const { return int(first_.size()); }
  int firstColumn(int row) const { return first_[size_t(row)]; }
  /// 3x3 block products of one factor() (the envelope's work; a dense factor takes n (n - 1) (n + 1) / 6).
  long factorWork() const;

  /// Zeroes the values (keeps the pattern).
  void setZero();
  /// Block (i, j) of the lower triangle, first(i) <= j <= i (not checked: a block outside the envelope is
  /// ignored by factor(); of a diagonal block only the lower triangle is read).
  Eigen::Matrix3d& block(int i, int j) { return blocks_[size_t(i) * first_.size() + size_t(j)]; }
  const Eigen::Matrix3d& block(int i, int j) const { return blocks_[size_t(i) * first_.size() + size_t(j)]; }

  /// Factors in place (the blocks become L's). False, and the values are undefined, when a pivot is not
  /// positive and finite: the matrix is not positive definite (or holds a NaN); *failed_row is its scalar
  /// row.
  bool factor(int* failed_row = nullptr);
  /// Solves A x = b with the factor; b (3 size() values) becomes x.
  void solveInPlace(double* b) const;

 private:
  std::vector<int> first_;
  std::vector<Eigen::Matrix3d> blocks_;   // row-major size() x size(), only the envelope is read
  std::vector<Eigen::Matrix3d> inverse_;  // L(i, i)^-1 (lower triangular)
};

}  // namespace rc
