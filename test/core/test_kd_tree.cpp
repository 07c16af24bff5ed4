#include "relaxed_connectivity/core/kd_tree.h"

#include <gtest/gtest.h>

#include "spatial_test_points.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace rc {
namespace {

using test::Layout;
using test::makePoints;
std::vector<double> bruteKnnDists(const std::vector<Vec3>& pts, const Vec3& q, size_t k) {
  std::vector<double> d;
  for (const Vec3& p : pts) d.push_back((p - q).squaredNorm());
  std::sort(d.begin(), d.end());
  d.resize(std::min(k, d.size()));
  return d;
}

std::vector<double> bruteRadiusDists(const std::vector<Vec3>& pts, const Vec3& q, double r) {
  std::vector<double> d;
  for (const Vec3& p : pts)
    if ((p - q).squaredNorm() <= r * r) d.push_back((p - q).squaredNorm());
  std::sort(d.begin(), d.end());
  return d;
}

void expectSameDists(const std::vector<double>& expected, const std::vector<Neighbor>& got,
                     const std::vector<Vec3>& pts, const Vec3& q) {
  ASSERT_EQ(expected.size(), got.size());
  std::vector<double> d;
  for (const Neighbor& nb : got) {
    ASSERT_LT(nb.index, pts.size());
    // The reported distance belongs to the reported index.
    EXPECT_DOUBLE_EQ(nb.sq_dist, (pts[nb.index] - q).squaredNorm());
    d.push_back(nb.sq_dist);
  }
  std::sort(d.begin(), d.end());
  for (size_t i = 0; i < d.size(); ++i) EXPECT_NEAR(d[i], expected[i], 1e-12 * (1.0 + expected[i]));
}

void checkAgainstBruteForce(const std::vector<Vec3>& pts, double scale, const Vec3& offset, uint32_t seed) {
  KdTree tree(pts);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.2, 1.2);
  std::vector<Neighbor> out;
  std::vector<Neighbor> knn(16);
  for (int q = 0; q < 60; ++q) {
    // Half the queries are data points (exact hits), half are free points.
    const Vec3 query =
        q % 2 == 0 ? pts[(q * 37) % pts.size()] : offset + scale * Vec3(uni(rng), uni(rng), uni(rng));
    const size_t found = tree.knn(query, 16, knn.data());
    ASSERT_EQ(found, std::min<size_t>(16, pts.size()));
    const std::vector<Neighbor> got(knn.begin(), knn.begin() + found);
    for (size_t i = 1; i < got.size(); ++i) EXPECT_LE(got[i - 1].sq_dist, got[i].sq_dist);
    expectSameDists(bruteKnnDists(pts, query, 16), got, pts, query);
    const double r = 0.15 * scale;
    tree.radius(query, r, out, true);
    for (size_t i = 1; i < out.size(); ++i) EXPECT_LE(out[i - 1].sq_dist, out[i].sq_dist);
    expectSameDists(bruteRadiusDists(pts, query, r), out, pts, query);
  }
}

TEST(KdTree, MatchesBruteForceOnUniformClusteredAndSurfacePoints) {
  for (Layout layout : {Layout::kUniform, Layout::kClustered, Layout::kSphere})
    checkAgainstBruteForce(makePoints(layout, 3000, 7 + int(layout)), 1.0, Vec3::Zero(), 11);
}

TEST(KdTree, NegativeHugeAndTinyCoordinates) {
  const Vec3 negative(-5.5, -3.25, -9.0), huge(1e6, -1e6, 1e6);
  checkAgainstBruteForce(makePoints(Layout::kUniform, 1500, 3, 1.0, negative), 1.0, negative, 5);
  checkAgainstBruteForce(makePoints(Layout::kSphere, 1500, 4, 1.0, huge), 1.0, huge, 6);
  checkAgainstBruteForce(makePoints(Layout::kClustered, 1500, 5, 1e-6), 1e-6, Vec3::Zero(), 7);
}

TEST(KdTree, IncludesPointsExactlyOnTheRadius) {
  std::vector<Vec3> grid;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int k = -2; k <= 2; ++k) grid.emplace_back(i, j, k);
  KdTree tree(grid);
  std::vector<Neighbor> out;
  EXPECT_EQ(tree.radius(Vec3::Zero(), 1.0, out), 7u);  // itself + 6 face neighbours at distance exactly 1
  EXPECT_EQ(tree.radius(Vec3::Zero(), std::sqrt(2.0), out), 19u);
}

TEST(KdTree, BoundaryCases) {
  std::vector<Vec3> pts = makePoints(Layout::kUniform, 200, 9);
  pts.push_back(pts[10]);  // duplicates
  pts.push_back(pts[10]);
  KdTree tree(pts);
  std::vector<Neighbor> out, knn(500);

  // Query far outside: the nearest points are still found, the radius query is empty.
  const Vec3 far(1e9, -1e9, 3e9);
  EXPECT_EQ(tree.knn(far, 5, knn.data()), 5u);
  expectSameDists(bruteKnnDists(pts, far, 5), std::vector<Neighbor>(knn.begin(), knn.begin() + 5), pts, far);
  EXPECT_EQ(tree.radius(far, 10.0, out), 0u);

  // Radius 0 finds exactly the coincident points.
  EXPECT_EQ(tree.radius(pts[10], 0.0, out), 3u);
  for (const Neighbor& nb : out) EXPECT_EQ(nb.sq_dist, 0.0);
  EXPECT_EQ(tree.radius(Vec3(5, 5, 5), 0.0, out), 0u);

  // k > n returns all points, sorted.
  EXPECT_EQ(tree.knn(Vec3::Zero(), 500, knn.data()), pts.size());
  expectSameDists(bruteKnnDists(pts, Vec3::Zero(), 500),
                  std::vector<Neighbor>(knn.begin(), knn.begin() + pts.size()), pts, Vec3::Zero());

  // Nearest neighbour of a duplicated point: three zeros.
  ASSERT_EQ(tree.knn(pts[10], 4, knn.data()), 4u);
  EXPECT_EQ(knn[2].sq_dist, 0.0);
  EXPECT_GT(knn[3].sq_dist, 0.0);

  EXPECT_THROW(tree.radius(Vec3::Zero(), -1.0, out), std::invalid_argument);
  EXPECT_THROW(KdTree(pts, 0), std::invalid_argument);
}

TEST(KdTree, NearestWithinABoundEqualsTheNearest) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  std::vector<Vec3> pts;
  for (int i = 0; i < 5000; ++i) pts.push_back(Vec3(u(rng), u(rng), u(rng)));
  const KdTree tree(pts);
  for (int q = 0; q < 500; ++q) {
    const Vec3 x(u(rng), u(rng), u(rng));
    Neighbor nearest, bounded;
    tree.knn(x, 1, &nearest);
    // A bound from any point (here a random one, or the nearest itself) finds the nearest ...
    const size_t other = size_t(q * 7) % pts.size();
    for (const double bound : {(pts[other] - x).squaredNorm(), nearest.sq_dist}) {
      ASSERT_TRUE(tree.nearestWithin(x, bound, &bounded));
      EXPECT_EQ(bounded.sq_dist, nearest.sq_dist);
      EXPECT_EQ((pts[bounded.index] - x).squaredNorm(), nearest.sq_dist);
    }
    // ... and a bound below it finds nothing.
    EXPECT_FALSE(tree.nearestWithin(x, 0.999 * nearest.sq_dist, &bounded));
  }
}

TEST(KdTree, EmptySetAndRebuild) {
  std::vector<Vec3> pts;
  KdTree tree(pts);
  std::vector<Neighbor> out, knn(4);
  EXPECT_EQ(tree.size(), 0u);
  EXPECT_EQ(tree.knn(Vec3::Zero(), 4, knn.data()), 0u);
  EXPECT_EQ(tree.radius(Vec3::Zero(), 1.0, out), 0u);
  pts = makePoints(Layout::kUniform, 100, 2);
  tree.rebuild();
  EXPECT_EQ(tree.size(), 100u);
  EXPECT_EQ(tree.radius(Vec3::Zero(), 10.0, out), 100u);
}

TEST(KdTree, BatchedQueriesEqualSingleQueries) {
  const std::vector<Vec3> pts = makePoints(Layout::kClustered, 4000, 21);
  const std::vector<Vec3> queries = makePoints(Layout::kUniform, 500, 22);
  KdTree tree(pts);
  std::vector<Neighbor> batch, single(8), out;
  tree.knnBatch(queries, 8, batch);
  ASSERT_EQ(batch.size(), queries.size() * 8);
  for (size_t i = 0; i < queries.size(); ++i) {
    tree.knn(queries[i], 8, single.data());
    for (size_t j = 0; j < 8; ++j) {
      EXPECT_EQ(batch[i * 8 + j].index, single[j].index);
      EXPECT_EQ(batch[i * 8 + j].sq_dist, single[j].sq_dist);
    }
  }
  // Rows of a tree smaller than k are padded.
  const std::vector<Vec3> few = makePoints(Layout::kUniform, 3, 1);
  KdTree small(few);
  small.knnBatch(queries, 5, batch);
  EXPECT_EQ(batch[3].index, std::numeric_limits<uint32_t>::max());
  EXPECT_TRUE(std::isinf(batch[4].sq_dist));

  std::vector<size_t> offsets;
  tree.radiusBatch(queries, 0.2, offsets, batch);
  ASSERT_EQ(offsets.size(), queries.size() + 1);
  EXPECT_EQ(offsets.back(), batch.size());
  size_t total = 0;
  for (size_t i = 0; i < queries.size(); ++i) {
    total += tree.radius(queries[i], 0.2, out);
    const std::vector<Neighbor> row(batch.begin() + offsets[i], batch.begin() + offsets[i + 1]);
    expectSameDists(bruteRadiusDists(pts, queries[i], 0.2), row, pts, queries[i]);
  }
  EXPECT_EQ(total, batch.size());
  EXPECT_GT(total, queries.size());  // the test is not vacuous
}

TEST(KdTree, KthNeighborDistancesAreTheBruteForceOnes) {
  const std::vector<Vec3> pts = makePoints(Layout::kClustered, 800, 11);
  const KdTree tree(pts);
  for (size_t k : {1, 8}) {
    const std::vector<double> d = tree.kthNeighborDistances(k);
    ASSERT_EQ(d.size(), pts.size());
    for (size_t i = 0; i < pts.size(); i += 37)
      EXPECT_DOUBLE_EQ(d[i], std::sqrt(bruteKnnDists(pts, pts[i], k + 1)[k])) << "point " << i << ", k " << k;
  }
  const std::vector<Vec3> two = {Vec3(0, 0, 0), Vec3(3, 4, 0)};
  const KdTree small(two);
  EXPECT_DOUBLE_EQ(small.kthNeighborDistances(1)[0], 5.0);
  EXPECT_TRUE(std::isinf(small.kthNeighborDistances(2)[1]));  // fewer than k other points
}

}  // namespace
}  // namespace rc
