#include "relaxed_connectivity/core/hash_grid.h"

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
/// Reference: the live points of a dynamic set (NaN marks a removed id).
std::vector<double> bruteDists(const std::vector<Vec3>& pts, const Vec3& q, double r, size_t k) {
  std::vector<double> d;
  for (const Vec3& p : pts)
    if (p.allFinite() && (p - q).squaredNorm() <= r * r) d.push_back((p - q).squaredNorm());
  std::sort(d.begin(), d.end());
  if (d.size() > k) d.resize(k);
  return d;
}

void expectSameDists(const std::vector<double>& expected, const Neighbor* got, size_t count,
                     const std::vector<Vec3>& pts, const Vec3& q) {
  ASSERT_EQ(expected.size(), count);
  std::vector<double> d;
  std::vector<uint32_t> ids;
  for (size_t i = 0; i < count; ++i) {
    ASSERT_LT(got[i].index, pts.size());
    EXPECT_EQ(got[i].sq_dist, (pts[got[i].index] - q).squaredNorm());
    d.push_back(got[i].sq_dist);
    ids.push_back(got[i].index);
  }
  std::sort(ids.begin(), ids.end());
  EXPECT_TRUE(std::adjacent_find(ids.begin(), ids.end()) == ids.end()) << "a point was reported twice";
  std::sort(d.begin(), d.end());
  for (size_t i = 0; i < d.size(); ++i) EXPECT_EQ(d[i], expected[i]);
}

void checkQueries(const HashGrid& grid, const std::vector<Vec3>& pts, double scale, const Vec3& offset,
                  uint32_t seed) {
  const double inf = std::numeric_limits<double>::infinity();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.3, 1.3), frac(0.0, 1.0);
  std::vector<Neighbor> out, knn(12);
  int multi = 0;  // queries that found more than one point
  for (int q = 0; q < 80; ++q) {
    const Vec3 query =
        q % 2 == 0 ? pts[(q * 53) % pts.size()] : offset + scale * Vec3(uni(rng), uni(rng), uni(rng));
    if (!query.allFinite()) continue;
    const double r = (q % 5 == 0 ? 1.0 : frac(rng)) * grid.maxRadius();
    grid.radius(query, r, out, true);
    for (size_t i = 1; i < out.size(); ++i) EXPECT_LE(out[i - 1].sq_dist, out[i].sq_dist);
    expectSameDists(bruteDists(pts, query, r, pts.size()), out.data(), out.size(), pts, query);
    multi += out.size() > 1;
    const size_t found = grid.knn(query, 12, knn.data());
    for (size_t i = 1; i < found; ++i) EXPECT_LE(knn[i - 1].sq_dist, knn[i].sq_dist);
    expectSameDists(bruteDists(pts, query, inf, 12), knn.data(), found, pts, query);
  }
  EXPECT_GE(multi, 5);  // not vacuous
}

TEST(HashGrid, MatchesBruteForceOnUniformClusteredAndSurfacePoints) {
  for (Layout layout : {Layout::kUniform, Layout::kClustered, Layout::kSphere}) {
    const std::vector<Vec3> pts = makePoints(layout, 3000, 17 + int(layout));
    HashGrid grid(0.12);
    grid.build(pts);
    EXPECT_EQ(grid.size(), pts.size());
    EXPECT_DOUBLE_EQ(grid.cellSize(), 0.24);
    checkQueries(grid, pts, 1.0, Vec3::Zero(), 3);
  }
}

TEST(HashGrid, NegativeHugeAndTinyCoordinates) {
  const Vec3 negative(-7.3, -0.01, -12.0), huge(1e6, -1e6, 2e6);
  {
    const auto pts = makePoints(Layout::kUniform, 1500, 1, 1.0, negative);
    HashGrid grid(0.1);
    grid.build(pts);
    checkQueries(grid, pts, 1.0, negative, 2);
  }
  {
    const auto pts = makePoints(Layout::kSphere, 1500, 3, 1.0, huge);
    HashGrid grid(0.1);
    grid.build(pts);
    checkQueries(grid, pts, 1.0, huge, 4);
  }
  {
    const auto pts = makePoints(Layout::kClustered, 1500, 5, 1e-6);
    HashGrid grid(2e-8);
    grid.build(pts);
    checkQueries(grid, pts, 1e-6, Vec3::Zero(), 6);
  }
}

TEST(HashGrid, BoundaryCases) {
  std::vector<Vec3> pts = makePoints(Layout::kUniform, 300, 8);
  pts.push_back(pts[4]);
  pts.push_back(pts[4]);
  HashGrid grid(0.2);
  std::vector<Neighbor> out, knn(400);

  // Empty grid.
  EXPECT_EQ(grid.radius(Vec3::Zero(), 0.2, out), 0u);
  EXPECT_EQ(grid.knn(Vec3::Zero(), 3, knn.data()), 0u);

  grid.build(pts);
  // Far query: kNN expands straight to the occupied cells; radius query is empty.
  const Vec3 far(-3e7, 5e7, 1e7);
  ASSERT_EQ(grid.knn(far, 6, knn.data()), 6u);
  expectSameDists(bruteDists(pts, far, std::numeric_limits<double>::infinity(), 6), knn.data(), 6, pts, far);
  EXPECT_EQ(grid.radius(far, 0.2, out), 0u);
  // Radius 0 returns the coincident points.
  EXPECT_EQ(grid.radius(pts[4], 0.0, out), 3u);
  // k > n.
  ASSERT_EQ(grid.knn(Vec3(0.3, 0.2, 0.1), 400, knn.data()), pts.size());
  expectSameDists(bruteDists(pts, Vec3(0.3, 0.2, 0.1), std::numeric_limits<double>::infinity(), 400),
                  knn.data(), pts.size(), pts, Vec3(0.3, 0.2, 0.1));

  EXPECT_THROW(grid.radius(Vec3::Zero(), 0.21, out), std::invalid_argument);
  EXPECT_THROW(grid.radius(Vec3::Zero(), -0.1, out), std::invalid_argument);
  EXPECT_THROW(grid.insert(0, Vec3::Zero()), std::invalid_argument);  // present
  EXPECT_THROW(grid.remove(100000), std::invalid_argument);
  EXPECT_THROW(grid.insert(1000, Vec3(std::nan(""), 0, 0)), std::invalid_argument);
  EXPECT_THROW(grid.insert(1001, Vec3(1e300, 0, 0)), std::invalid_argument);
  EXPECT_THROW(HashGrid(0.0), std::invalid_argument);
}

TEST(HashGrid, PointsExactlyOnTheRadiusAndCellBoundaries) {
  // Integer lattice with cell size 2: many points sit exactly on cell faces and at exactly the query radius.
  std::vector<Vec3> grid_pts;
  for (int i = -4; i <= 4; ++i)
    for (int j = -4; j <= 4; ++j)
      for (int k = -4; k <= 4; ++k) grid_pts.emplace_back(i, j, k);
  HashGrid grid(1.0);
  grid.build(grid_pts);
  std::vector<Neighbor> out;
  for (const Vec3& q : {Vec3(0, 0, 0), Vec3(-2, 2, -4), Vec3(1, -1, 3)}) {
    // (the query first: argument order is unspecified, and out.data() changes when the query fills out)
    const size_t found = grid.radius(q, 1.0, out);
    expectSameDists(bruteDists(grid_pts, q, 1.0, 1000), out.data(), found, grid_pts, q);
  }
  EXPECT_EQ(grid.radius(Vec3(1, -1, 3), 1.0, out), 7u);
}

TEST(HashGrid, InsertRemoveMoveKeepsQueriesExact) {
  // Random dynamic edits (SPH-like motion plus births and deaths) checked against brute force.
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::uniform_int_distribution<int> pick(0, 1999);
  std::vector<Vec3> pts(2000, Vec3::Constant(std::nan("")));  // NaN = absent id
  HashGrid grid(0.15, 10);                                    // tiny table: grows by rehashing
  const size_t table0 = grid.tableSize();
  for (uint32_t id = 0; id < 1500; ++id) {
    pts[id] = Vec3(uni(rng), uni(rng), uni(rng));
    grid.insert(id, pts[id]);
  }
  EXPECT_GT(grid.tableSize(), table0);
  for (int step = 0; step < 5; ++step) {
    for (int e = 0; e < 800; ++e) {
      const uint32_t id = pick(rng);
      if (!pts[id].allFinite()) {
        pts[id] = Vec3(uni(rng), uni(rng), uni(rng));
        grid.insert(id, pts[id]);
      } else if (e % 7 == 0) {
        grid.remove(id);
        pts[id] = Vec3::Constant(std::nan(""));
      } else {
        // Small moves (mostly within a cell) and large jumps (across cells).
        const double step_len = e % 3 == 0 ? 0.5 : 0.02;
        pts[id] += step_len * Vec3(uni(rng), uni(rng), uni(rng));
        grid.move(id, pts[id]);
      }
    }
    size_t live = 0;
    for (uint32_t id = 0; id < pts.size(); ++id) {
      const bool present = pts[id].allFinite();
      live += present;
      ASSERT_EQ(grid.contains(id), present);
      if (present) {
        EXPECT_EQ(grid.position(id), pts[id]);
      }
    }
    EXPECT_EQ(grid.size(), live);
    checkQueries(grid, pts, 1.0, Vec3::Zero(), 40 + step);
  }
}

}  // namespace
}  // namespace rc
