// Neighbour search benchmark (thesis 3.4): all-pairs fixed-radius lists and kd-tree kNN / radius queries
// against nanoflann (and PCL's KdTreeFLANN when available). Prints tables; `--quick` uses smaller sizes.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <nanoflann.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "relaxed_connectivity/core/hash_grid.h"
#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/core/neighbor_lists.h"

#ifdef RC_HAVE_PCL
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>
#endif

namespace {

using rc::Vec3;

std::vector<Vec3> uniformCube(size_t n, uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<Vec3> pts(n);
  for (Vec3& p : pts) p = Vec3(uni(rng), uni(rng), uni(rng));
  return pts;
}

/// Radius giving `target` neighbours in expectation for n uniform points in the unit cube.
double radiusForCount(size_t n, double target) {
  return std::cbrt(3.0 * target / (4.0 * M_PI * double(n)));
}

double secondsOf(const std::function<void()>& fn) {
  const auto t0 = std::chrono::steady_clock::now();
  fn();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// A measured method: `fn` runs it once and returns the number of neighbours found (checksum).
struct Method {
  Method(std::string name_, std::function<size_t()> fn_, int runs_)
      : name(std::move(name_)), fn(std::move(fn_)), runs(runs_) {}
  std::string name;
  std::function<size_t()> fn;
  int runs;
  std::vector<double> seconds;
  size_t count = 0;
  double median() const {
    std::vector<double> t = seconds;
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
  }
};

/// Runs the methods round-robin (A B C A B C ...) so that background load hits all of them alike; method m
/// runs methods[m].runs times. The median is reported.
void measure(std::vector<Method>& methods) {
  int max_runs = 0;
  for (const Method& m : methods) max_runs = std::max(max_runs, m.runs);
  for (int r = 0; r < max_runs; ++r)
    for (Method& m : methods)
      if (r < m.runs) m.seconds.push_back(secondsOf([&] { m.count = m.fn(); }));
}

// The usual way to put a std::vector<Vec3> into nanoflann (as its examples do).
struct RawCloud {
  const std::vector<Vec3>& pts;
  size_t kdtree_get_point_count() const { return pts.size(); }
  double kdtree_get_pt(size_t i, size_t dim) const { return pts[i][dim]; }
  template <class Bbox>
  bool kdtree_get_bbox(Bbox&) const {
    return false;
  }
};
using RawTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, RawCloud>, RawCloud,
                                                    3, uint32_t>;

/// Prints one table; `peer` indexes the method the speedups refer to, `same_leaf` (if >= 0) the nanoflann row
/// at rc::KdTree's leaf size, for a second speedup column.
void printTable(const std::vector<Method>& methods, size_t per, const char* unit, size_t peer,
                int same_leaf = -1) {
  std::printf("  %-48s %5s %10s %12s %12s %9s%s\n", "method", "runs", "ms", unit, "neighbours", "speedup",
              same_leaf >= 0 ? "  vs leaf 24" : "");
  const double peer_seconds = methods[peer].median();
  for (const Method& m : methods) {
    std::printf("  %-48s %5d %10.1f %12.3f %12zu %8.2fx", m.name.c_str(), m.runs, 1e3 * m.median(),
                1e6 * m.median() / double(per), m.count, peer_seconds / m.median());
    if (same_leaf >= 0) std::printf(" %11.2fx", methods[same_leaf].median() / m.median());
    std::printf("\n");
  }
}

/// What rc::KdTree is, printed above its tables.
const char* const kKdTreeNote =
    "  rc::KdTree is nanoflann's KDTreeSingleIndexAdaptor with leaf size 24 (nanoflann's default: 10) over "
    "a\n"
    "  copy of the points in leaf order, with its own result sets; the \"leaf size 24\" nanoflann row has "
    "the\n"
    "  same leaf size on the caller's point order, so it separates the leaf size from the ordering.\n";

/// `runs` for the sorted-grid lists, `query_runs` for the per-point query methods (slow at 1M points).
void allPairsTable(size_t n, int runs, int query_runs) {
  const std::vector<Vec3> pts = uniformCube(n, 42 + n);
  const double h = radiusForCount(n, 30.0);
  rc::NeighborLists single_lists, multi_lists;
  rc::NeighborLists::Options single, multi;
  single.num_threads = 1;
  multi.num_threads = 0;
  single_lists.build(pts, h, single);  // warm-up: buffers reach their working size
  multi_lists.build(pts, h, multi);
  rc::HashGrid grid(h, n);
  std::vector<rc::Neighbor> out;
  std::vector<std::pair<uint32_t, double>> matches;

  std::vector<Method> methods;
  methods.push_back({"rc::NeighborLists, 1 thread",
                     [&] {
                       single_lists.build(pts, h, single);
                       return single_lists.numEntries();
                     },
                     runs});
  methods.push_back({"rc::NeighborLists, " + std::to_string(omp_get_max_threads()) + " threads",
                     [&] {
                       multi_lists.build(pts, h, multi);
                       return multi_lists.numEntries();
                     },
                     runs});
  methods.push_back({"rc::HashGrid build + radius per point",
                     [&] {
                       grid.build(pts);
                       size_t count = 0;
                       for (size_t i = 0; i < n; ++i) count += grid.radius(pts[i], h, out) - 1;
                       return count;
                     },
                     query_runs});
  methods.push_back({"rc::KdTree (leaf 24) build + radius per pt",
                     [&] {
                       rc::KdTree tree(pts);
                       size_t count = 0;
                       for (size_t i = 0; i < n; ++i) count += tree.radius(pts[i], h, out) - 1;
                       return count;
                     },
                     query_runs});
  methods.push_back({"nanoflann build + radiusSearch, leaf size 24",
                     [&] {
                       RawCloud cloud{pts};
                       RawTree tree(3, cloud, {24});
                       tree.buildIndex();
                       const nanoflann::SearchParams unsorted(32, 0, false);
                       size_t count = 0;
                       for (size_t i = 0; i < n; ++i)
                         count += tree.radiusSearch(pts[i].data(), h * h, matches, unsorted) - 1;
                       return count;
                     },
                     query_runs});
  methods.push_back({"nanoflann build + radiusSearch, leaf 10 (peer)",
                     [&] {
                       RawCloud cloud{pts};
                       RawTree tree(3, cloud, {10});
                       tree.buildIndex();
                       const nanoflann::SearchParams unsorted(32, 0, false);
                       size_t count = 0;
                       for (size_t i = 0; i < n; ++i)
                         count += tree.radiusSearch(pts[i].data(), h * h, matches, unsorted) - 1;
                       return count;
                     },
                     query_runs});
  measure(methods);
  std::printf(
      "\nAll-pairs neighbour lists: %zu uniform points in the unit cube, h = %.5f, mean %.2f neighbours\n"
      "(median of the runs shown, methods interleaved; 1 thread unless stated; speedup = peer time / time)\n",
      n, h, single_lists.meanCount());
  std::printf("%s", kKdTreeNote);
  printTable(methods, n, "us/point", methods.size() - 1, int(methods.size()) - 2);
}

void kdTreeTable(size_t n, size_t nq, int runs) {
  const std::vector<Vec3> pts = uniformCube(n, 7), queries = uniformCube(nq, 8);
  const double r = radiusForCount(n, 30.0);
  constexpr size_t k = 10;
  rc::KdTree tree(pts);
  RawCloud cloud{pts};
  RawTree raw(3, cloud, {10}), raw24(3, cloud, {24});
  raw.buildIndex();
  raw24.buildIndex();
  std::vector<rc::Neighbor> nb(k), out;
  std::vector<uint32_t> idx(k);
  std::vector<double> dist(k);
  std::vector<std::pair<uint32_t, double>> matches;
  const nanoflann::SearchParams unsorted(32, 0, false);
  double our_checksum = 0, raw_checksum = 0;

  std::vector<Method> knn;
  knn.push_back({"rc::KdTree::knn (leaf 24, leaf order)",
                 [&] {
                   our_checksum = 0;
                   for (const Vec3& q : queries) {
                     tree.knn(q, k, nb.data());
                     our_checksum += nb[k - 1].sq_dist;
                   }
                   return nq * k;
                 },
                 runs});
  knn.push_back({"nanoflann knnSearch, leaf size 10 (peer)",
                 [&] {
                   raw_checksum = 0;
                   for (const Vec3& q : queries) {
                     raw.knnSearch(q.data(), k, idx.data(), dist.data());
                     raw_checksum += dist[k - 1];
                   }
                   return nq * k;
                 },
                 runs});
  knn.push_back({"nanoflann knnSearch, leaf size 24",
                 [&] {
                   for (const Vec3& q : queries) raw24.knnSearch(q.data(), k, idx.data(), dist.data());
                   return nq * k;
                 },
                 runs});
  std::vector<Method> radius;
  radius.push_back({"rc::KdTree::radius (leaf 24, leaf order)",
                    [&] {
                      size_t count = 0;
                      for (const Vec3& q : queries) count += tree.radius(q, r, out);
                      return count;
                    },
                    runs});
  radius.push_back({"nanoflann radiusSearch, leaf 10 (peer)",
                    [&] {
                      size_t count = 0;
                      for (const Vec3& q : queries)
                        count += raw.radiusSearch(q.data(), r * r, matches, unsorted);
                      return count;
                    },
                    runs});
  radius.push_back({"nanoflann radiusSearch, leaf size 24",
                    [&] {
                      size_t count = 0;
                      for (const Vec3& q : queries)
                        count += raw24.radiusSearch(q.data(), r * r, matches, unsorted);
                      return count;
                    },
                    runs});
#ifdef RC_HAVE_PCL
  pcl::PointCloud<pcl::PointXYZ>::Ptr pcl_cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (const Vec3& p : pts) pcl_cloud->push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
  pcl::KdTreeFLANN<pcl::PointXYZ> pcl_tree;
  pcl_tree.setSortedResults(false);
  pcl_tree.setInputCloud(pcl_cloud);
  std::vector<int> pcl_idx;
  std::vector<float> pcl_dist;
  knn.push_back({"pcl::KdTreeFLANN::nearestKSearch",
                 [&] {
                   for (const Vec3& q : queries)
                     pcl_tree.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), k, pcl_idx, pcl_dist);
                   return nq * k;
                 },
                 runs});
  radius.push_back({"pcl::KdTreeFLANN::radiusSearch (float)",
                    [&] {
                      size_t count = 0;
                      for (const Vec3& q : queries)
                        count +=
                            pcl_tree.radiusSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), r, pcl_idx, pcl_dist);
                      return count;
                    },
                    runs});
#endif
  measure(knn);
  std::printf("\nkNN, k = %zu: %zu uniform points, %zu queries, 1 thread (median, methods interleaved)\n", k,
              n, nq);
  std::printf("%s", kKdTreeNote);
  printTable(knn, nq, "us/query", 1, 2);
  if (std::abs(raw_checksum - our_checksum) > 1e-9 * std::abs(raw_checksum))
    std::printf("  WARNING: kNN distances differ from nanoflann (%.12g vs %.12g)\n", our_checksum,
                raw_checksum);
  measure(radius);
  std::printf(
      "\nRadius queries (unsorted results), r = %.5f: %zu uniform points, %zu queries, 1 thread (median, "
      "methods interleaved)\n",
      r, n, nq);
  printTable(radius, nq, "us/query", 1, 2);
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else {
      std::fprintf(stderr, "usage: %s [--quick]\n", argv[0]);
      return 2;
    }
  }
#ifndef RC_HAVE_PCL
  std::printf("(built without PCL: no pcl::KdTreeFLANN rows)\n");
#endif
  std::printf("OpenMP threads: %d%s\n", omp_get_max_threads(), quick ? ", --quick sizes" : "");
  if (quick) {
    allPairsTable(20000, 5, 5);
    kdTreeTable(20000, 20000, 5);
  } else {
    allPairsTable(100000, 5, 5);
    allPairsTable(1000000, 5, 1);  // per-point queries at 1M take seconds each: one run
    kdTreeTable(100000, 100000, 5);
  }
  return 0;
}
