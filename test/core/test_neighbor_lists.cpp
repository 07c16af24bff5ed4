#include "relaxed_connectivity/core/neighbor_lists.h"

#include <gtest/gtest.h>

#include "spatial_test_points.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace rc {
namespace {

using test::Layout;
using test::makePoints;
/// Lists equal brute force as sets per point, distances match, and the relation is symmetric.
/// Returns the total number of entries.
size_t expectBruteForce(const NeighborLists& lists, const std::vector<Vec3>& pts, double h) {
  const size_t n = pts.size();
  EXPECT_EQ(lists.numPoints(), n);
  EXPECT_EQ(lists.offsets().size(), n + 1);
  std::vector<std::vector<uint32_t>> rows(n);
  for (size_t i = 0; i < n; ++i) {
    rows[i].assign(lists.begin(i), lists.end(i));
    if (!lists.sqDists().empty()) {
      for (size_t e = 0; e < lists.count(i); ++e)
        EXPECT_EQ(lists.sqDistsBegin(i)[e], (pts[i] - pts[rows[i][e]]).squaredNorm());
    }
    std::sort(rows[i].begin(), rows[i].end());
  }
  size_t total = 0;
  std::vector<uint32_t> expected;
  for (size_t i = 0; i < n; ++i) {
    expected.clear();
    for (size_t j = 0; j < n; ++j)
      if (j != i && (pts[i] - pts[j]).squaredNorm() <= h * h) expected.push_back(static_cast<uint32_t>(j));
    EXPECT_EQ(rows[i], expected) << "point " << i;
    total += expected.size();
    for (uint32_t j : rows[i]) EXPECT_TRUE(std::binary_search(rows[j].begin(), rows[j].end(), i));
  }
  EXPECT_EQ(lists.numEntries(), total);
  return total;
}

TEST(NeighborLists, MatchesBruteForceSingleAndMultiThreaded) {
  for (Layout layout : {Layout::kUniform, Layout::kClustered, Layout::kSphere}) {
    const std::vector<Vec3> pts = makePoints(layout, 2500, 31 + int(layout));
    const double h = layout == Layout::kClustered ? 0.02 : layout == Layout::kUniform ? 0.25 : 0.15;
    NeighborLists lists;
    for (int threads : {1, 2, 3}) {
      NeighborLists::Options options;
      options.num_threads = threads;
      options.store_sq_dists = threads != 2;
      lists.build(pts, h, options);
      EXPECT_GT(expectBruteForce(lists, pts, h), 5 * pts.size());
    }
  }
}

TEST(NeighborLists, NegativeHugeAndTinyCoordinates) {
  NeighborLists lists;
  NeighborLists::Options options;
  options.store_sq_dists = true;
  for (const auto& [pts, h] :
       {std::make_pair(makePoints(Layout::kUniform, 1500, 1, 1.0, Vec3(-9, -4, -0.5)), 0.2),
        std::make_pair(makePoints(Layout::kSphere, 1500, 2, 1.0, Vec3(1e6, -1e6, 1e6)), 0.1),
        std::make_pair(makePoints(Layout::kClustered, 1500, 3, 1e-6), 2e-8)}) {
    lists.build(pts, h, options);
    EXPECT_GT(expectBruteForce(lists, pts, h), 2 * pts.size());
  }
}

TEST(NeighborLists, ExactRadiusDuplicatesAndRadiusZero) {
  std::vector<Vec3> pts;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 6; ++k) pts.emplace_back(i, j, k);
  NeighborLists lists;
  lists.build(pts, 1.0);
  expectBruteForce(lists, pts, 1.0);
  EXPECT_EQ(lists.count(7 + 36 * 2), 6u);  // interior lattice point: 6 neighbours at exactly h
  pts.push_back(pts[0]);
  pts.push_back(pts[0]);
  lists.build(pts, 0.0);
  EXPECT_EQ(expectBruteForce(lists, pts, 0.0), 6u);  // three coincident points, each sees the other two
  EXPECT_EQ(lists.count(0), 2u);
}

TEST(NeighborLists, SparseOutlierCoarsensGridButStaysExact) {
  // One far point would make a fine dense grid enormous; the grid is coarsened and the lists stay exact.
  std::vector<Vec3> pts = makePoints(Layout::kUniform, 1200, 4);
  pts.emplace_back(1e5, -1e5, 1e5);
  NeighborLists lists;
  lists.build(pts, 0.1);
  expectBruteForce(lists, pts, 0.1);
  EXPECT_EQ(lists.count(pts.size() - 1), 0u);
}

TEST(NeighborLists, RebuildReusesAndEdgeInputs) {
  NeighborLists lists;
  lists.build({}, 0.5);
  EXPECT_EQ(lists.numPoints(), 0u);
  EXPECT_EQ(lists.numEntries(), 0u);
  lists.build({Vec3(1, 2, 3)}, 0.5);
  EXPECT_EQ(lists.numEntries(), 0u);
  ASSERT_EQ(lists.offsets().size(), 2u);
  // Larger, then smaller: stale entries from the larger build must not leak.
  const auto big = makePoints(Layout::kUniform, 2000, 5), small = makePoints(Layout::kSphere, 700, 6);
  lists.build(big, 0.2);
  expectBruteForce(lists, big, 0.2);
  lists.build(small, 0.3);
  expectBruteForce(lists, small, 0.3);
  EXPECT_NEAR(lists.meanCount(), double(lists.numEntries()) / 700.0, 1e-12);

  EXPECT_THROW(lists.build(small, -1.0), std::invalid_argument);
  EXPECT_THROW(lists.build(small, std::nan("")), std::invalid_argument);
  std::vector<Vec3> bad = small;
  bad[17].y() = std::nan("");
  try {
    lists.build(bad, 0.1);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("point 17"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rc
