// BlockEnvelopeCholesky: solutions against Eigen's dense LLT for random symmetric positive-definite matrices
// with banded, irregular (skyline) and full block envelopes; the envelope's work; indefinite and NaN matrices
// refused with their row; bad patterns refused.
#include "relaxed_connectivity/core/block_envelope_cholesky.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace rc {
namespace {

/// A random SPD matrix (3n x 3n) with nonzero blocks only within the block envelope `first`, some blocks
/// inside it zero; diagonally dominant.
Eigen::MatrixXd randomWithin(const std::vector<int>& first, std::mt19937& rng) {
  const int n = int(first.size());
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int i = 0; i < n; ++i)
    for (int j = first[size_t(i)]; j <= i; ++j) {
      if (j < i && u(rng) < -0.5) continue;  // a hole inside the envelope
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          if (j < i || c < r) a(3 * i + r, 3 * j + c) = a(3 * j + c, 3 * i + r) = u(rng);
    }
  for (int i = 0; i < 3 * n; ++i) a(i, i) = a.row(i).cwiseAbs().sum() + 0.1 + std::abs(u(rng));
  return a;
}

void load(BlockEnvelopeCholesky& c, const Eigen::MatrixXd& a) {
  c.setZero();
  for (int i = 0; i < c.size(); ++i)
    for (int j = c.firstColumn(i); j <= i; ++j) c.block(i, j) = a.block<3, 3>(3 * i, 3 * j);
}

double solveError(const std::vector<int>& first, std::mt19937& rng) {
  BlockEnvelopeCholesky c;
  c.setPattern(first);
  const Eigen::MatrixXd a = randomWithin(first, rng);
  load(c, a);
  EXPECT_TRUE(c.factor());
  const Eigen::VectorXd b = Eigen::VectorXd::Random(a.rows());
  Eigen::VectorXd x = b;
  c.solveInPlace(x.data());
  const Eigen::VectorXd reference = a.llt().solve(b);
  return (x - reference).norm() / reference.norm();
}

TEST(BlockEnvelopeCholesky, SolvesBandedSkylineAndFullMatricesAsDenseLltDoes) {
  std::mt19937 rng(7);
  for (int n : {1, 2, 5, 12, 40}) {
    std::vector<int> banded(static_cast<size_t>(n)), skyline(banded.size()), full(banded.size(), 0);
    std::uniform_int_distribution<int> pick(0, n - 1);
    for (int i = 0; i < n; ++i) {
      banded[size_t(i)] = std::max(0, i - 4);
      skyline[size_t(i)] = std::min(i, pick(rng));  // rows start anywhere, as an arrow or a ring's closure
    }
    EXPECT_LT(solveError(banded, rng), 1e-12) << n;
    EXPECT_LT(solveError(skyline, rng), 1e-12) << n;
    EXPECT_LT(solveError(full, rng), 1e-12) << n;
  }
}

TEST(BlockEnvelopeCholesky, WorkIsTheEnvelopes) {
  BlockEnvelopeCholesky c;
  c.setPattern(std::vector<int>(12, 0));
  EXPECT_EQ(c.factorWork(), 11L * 12 * 13 / 6);  // dense: n (n - 1) (n + 1) / 6 block products
  std::vector<int> banded(12);
  for (int i = 0; i < 12; ++i) banded[size_t(i)] = std::max(0, i - 4);
  c.setPattern(banded);
  EXPECT_EQ(c.factorWork(), 0 + 1 + 3 + 6 + 10 * 8);  // rows of 1..5 blocks, then 8 full-band rows
  c.setPattern(std::vector<int>{0, 1, 2});            // block diagonal: no products
  EXPECT_EQ(c.factorWork(), 0);
}

TEST(BlockEnvelopeCholesky, RefusesIndefiniteAndNanMatricesWithTheRow) {
  BlockEnvelopeCholesky c;
  c.setPattern({0, 0});
  c.block(0, 0) = Eigen::Matrix3d::Identity();
  c.block(1, 1) = Eigen::Matrix3d::Identity();
  c.block(1, 0) = 2 * Eigen::Matrix3d::Identity();  // [[I, 2I], [2I, I]] is indefinite: pivot 1 - 4
  int row = -1;
  EXPECT_FALSE(c.factor(&row));
  EXPECT_EQ(row, 3);
  c.setZero();
  c.block(0, 0) = Eigen::Matrix3d::Identity();
  c.block(1, 1) = Eigen::Matrix3d::Identity();
  c.block(1, 1)(2, 2) = std::nan("");
  EXPECT_FALSE(c.factor(&row));
  EXPECT_EQ(row, 5);
  c.setZero();
  c.block(0, 0) = Eigen::Vector3d(4, 9, 16).asDiagonal();
  c.block(1, 1) = Eigen::Vector3d(1, 4, 25).asDiagonal();
  EXPECT_TRUE(c.factor());
  double b[6] = {4, 9, 16, 1, 4, 25};
  c.solveInPlace(b);
  for (double x : b) EXPECT_DOUBLE_EQ(x, 1);
}

TEST(BlockEnvelopeCholesky, RefusesPatternsOutsideTheLowerTriangle) {
  BlockEnvelopeCholesky c;
  EXPECT_THROW(c.setPattern({0, 2}), std::invalid_argument);
  EXPECT_THROW(c.setPattern({-1}), std::invalid_argument);
  c.setPattern({});
  EXPECT_EQ(c.size(), 0);
  EXPECT_TRUE(c.factor());
}

}  // namespace
}  // namespace rc
