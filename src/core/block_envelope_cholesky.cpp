#include "relaxed_connectivity/core/block_envelope_cholesky.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

/// Lower-triangular Cholesky factor of the lower triangle of d and its inverse; false when a pivot is not
/// positive and finite (*row: which of the three).
bool factorDiagonal(const Eigen::Matrix3d& d, Eigen::Matrix3d* l, Eigen::Matrix3d* inverse, int* row) {
  const auto fail = [&](int r) { return *row = r, false; };
  const double p0 = d(0, 0);
  if (!(p0 > 0) || !std::isfinite(p0)) return fail(0);
  const double l00 = std::sqrt(p0), l10 = d(1, 0) / l00, l20 = d(2, 0) / l00;
  const double p1 = d(1, 1) - l10 * l10;
  if (!(p1 > 0) || !std::isfinite(p1)) return fail(1);
  const double l11 = std::sqrt(p1), l21 = (d(2, 1) - l20 * l10) / l11;
  const double p2 = d(2, 2) - l20 * l20 - l21 * l21;
  if (!(p2 > 0) || !std::isfinite(p2)) return fail(2);
  const double l22 = std::sqrt(p2);
  *l << l00, 0, 0, l10, l11, 0, l20, l21, l22;
  const double i00 = 1 / l00, i11 = 1 / l11, i22 = 1 / l22;
  const double i10 = -l10 * i00 * i11, i21 = -l21 * i11 * i22, i20 = -(l20 * i00 + l21 * i10) * i22;
  *inverse << i00, 0, 0, i10, i11, 0, i20, i21, i22;
  return true;
}

}  // namespace

void BlockEnvelopeCholesky::setPattern(std::vector<int> first) {
  for (size_t i = 0; i < first.size(); ++i)
    if (first[i] < 0 || first[i] > int(i))
      throw std::invalid_argument("BlockEnvelopeCholesky: block row " + std::to_string(i) +
                                  " starts at block column " + std::to_string(first[i]) + " (must be 0.." +
                                  std::to_string(i) + ")");
  first_ = std::move(first);
  blocks_.assign(first_.size() * first_.size(), Eigen::Matrix3d::Zero());
  inverse_.assign(first_.size(), Eigen::Matrix3d::Zero());
}

long BlockEnvelopeCholesky::factorWork() const {
  long work = 0;
  for (int i = 0; i < size(); ++i)
    for (int j = first_[size_t(i)]; j <= i; ++j) work += j - std::max(first_[size_t(i)], first_[size_t(j)]);
  return work;
}

void BlockEnvelopeCholesky::setZero() {
  std::fill(blocks_.begin(), blocks_.end(), Eigen::Matrix3d::Zero());
}

bool BlockEnvelopeCholesky::factor(int* failed_row) {
  // Block row by block row ("up-looking"): L(i, j) = (A(i, j) - sum_k L(i, k) L(j, k)^T) L(j, j)^-T over the
  // block columns both rows hold, then the diagonal block's own Cholesky factor.
  const int n = size();
  for (int i = 0; i < n; ++i) {
    const int fi = first_[size_t(i)];
    for (int j = fi; j < i; ++j) {
      Eigen::Matrix3d s = block(i, j);
      for (int k = std::max(fi, first_[size_t(j)]); k < j; ++k)
        s.noalias() -= block(i, k) * block(j, k).transpose();
      block(i, j).noalias() = s * inverse_[size_t(j)].transpose();
    }
    Eigen::Matrix3d d = block(i, i);
    for (int k = fi; k < i; ++k) d.noalias() -= block(i, k) * block(i, k).transpose();
    int row = 0;
    if (!factorDiagonal(d, &block(i, i), &inverse_[size_t(i)], &row)) {
      if (failed_row) *failed_row = 3 * i + row;
      return false;
    }
  }
  return true;
}

void BlockEnvelopeCholesky::solveInPlace(double* b) const {
  const int n = size();
  using Segment = Eigen::Map<Eigen::Vector3d>;
  for (int i = 0; i < n; ++i) {  // L y = b
    Eigen::Vector3d s = Segment(b + 3 * i);
    for (int k = first_[size_t(i)]; k < i; ++k) s.noalias() -= block(i, k) * Segment(b + 3 * k);
    Segment(b + 3 * i).noalias() = inverse_[size_t(i)] * s;
  }
  for (int i = n - 1; i >= 0; --i) {  // L^T x = y, by block rows of L (columns of L^T)
    const Eigen::Vector3d x = inverse_[size_t(i)].transpose() * Segment(b + 3 * i);
    Segment(b + 3 * i) = x;
    for (int k = first_[size_t(i)]; k < i; ++k) Segment(b + 3 * k).noalias() -= block(i, k).transpose() * x;
  }
}

}  // namespace rc
