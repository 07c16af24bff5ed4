#include "relaxed_connectivity/surface/normal_estimation.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/surface/mls_fits.h"

namespace rc {

namespace {

/// Symmetric kNN graph (Hoppe's Riemannian graph without the EMST edges) in CSR form from knnBatch rows of
/// `kk` entries: the sorted, distinct neighbours of i are adj[first[i] .. first[i + 1]).
void symmetricKnnGraph(const std::vector<Neighbor>& rows, size_t n, size_t kk, std::vector<uint32_t>& first,
                       std::vector<uint32_t>& adj) {
  const uint32_t none = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> degree(n + 1, 0);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < kk; ++j) {
      const uint32_t o = rows[i * kk + j].index;
      if (o != none && o != i) ++degree[i + 1], ++degree[o + 1];
    }
  for (size_t i = 0; i < n; ++i) degree[i + 1] += degree[i];
  adj.resize(degree[n]);
  std::vector<uint32_t> fill(degree.begin(), degree.end() - 1);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < kk; ++j) {
      const uint32_t o = rows[i * kk + j].index;
      if (o == none || o == i) continue;
      adj[fill[i]++] = o;
      adj[fill[o]++] = static_cast<uint32_t>(i);
    }
  first.assign(n + 1, 0);
  size_t used = 0;
  for (size_t i = 0; i < n; ++i) {
    uint32_t* row = adj.data() + degree[i];
    std::sort(row, adj.data() + degree[i + 1]);
    const uint32_t* end = std::unique(row, adj.data() + degree[i + 1]);
    for (const uint32_t* o = row; o != end; ++o) adj[used++] = *o;
    first[i + 1] = static_cast<uint32_t>(used);
  }
  adj.resize(used);
}

/// Prim's minimum spanning tree over the Riemannian graph, edge cost 1 - |ni.nj|; each component starts at
/// its highest point, oriented +z, and the orientation is propagated parent -> child along the tree.
size_t orientOverGraph(SurfelCloud& cloud, const std::vector<uint32_t>& first,
                       const std::vector<uint32_t>& adj) {
  const size_t n = cloud.size();
  std::vector<size_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return cloud.positions[a].z() > cloud.positions[b].z(); });
  std::vector<char> done(n, 0);
  size_t flipped = 0;
  using Item = std::pair<double, std::pair<uint32_t, uint32_t>>;  // cost, (node, parent)
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  for (size_t root : order) {
    if (done[root]) continue;
    if (cloud.normals[root].z() < 0) cloud.normals[root] = -cloud.normals[root], ++flipped;
    heap.push({0.0, {static_cast<uint32_t>(root), static_cast<uint32_t>(root)}});
    while (!heap.empty()) {
      const auto [cost, edge] = heap.top();
      heap.pop();
      const uint32_t node = edge.first, parent = edge.second;
      if (done[node]) continue;
      done[node] = 1;
      if (node != parent && cloud.normals[node].dot(cloud.normals[parent]) < 0)
        cloud.normals[node] = -cloud.normals[node], ++flipped;
      for (uint32_t e = first[node]; e < first[node + 1]; ++e) {
        const uint32_t o = adj[e];
        if (!done[o]) heap.push({1.0 - std::abs(cloud.normals[node].dot(cloud.normals[o])), {o, node}});
      }
    }
  }
  return flipped;
}

}  // namespace

void estimateNormals(SurfelCloud& cloud, const NormalEstimationConfig& config) {
  if (cloud.size() < 3) throw std::invalid_argument("estimateNormals: the cloud needs at least 3 points");
  if (config.k < 3) throw std::invalid_argument("estimateNormals: k must be >= 3");
  for (const Vec3& p : cloud.positions)
    if (!p.allFinite()) throw std::invalid_argument("estimateNormals: the cloud has non-finite positions");
  const size_t n = cloud.size(), k = std::min<size_t>(config.k, n);
  // One kNN query serves the covariances (the first k of each row) and, without a viewpoint, the orientation
  // graph (k + 1: the point itself and k others).
  const size_t kk = config.viewpoint ? k : std::min<size_t>(config.k + 1, n);
  KdTree tree(cloud.positions);
  std::vector<Neighbor> rows;
  tree.knnBatch(cloud.positions, kk, rows);
  cloud.normals.resize(n);
  if (config.write_curvature) cloud.curvature.resize(n);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < static_cast<long>(n); ++i) {
    // Covariance of the k nearest (PCA), centred at their mean.
    const Neighbor* row = rows.data() + i * kk;
    Vec3 mean = Vec3::Zero();
    size_t m = 0;
    for (size_t j = 0; j < k; ++j) {
      if (row[j].index == std::numeric_limits<uint32_t>::max()) continue;
      mean += cloud.positions[row[j].index] - cloud.positions[i];
      ++m;
    }
    mean /= static_cast<double>(m);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (size_t j = 0; j < k; ++j) {
      if (row[j].index == std::numeric_limits<uint32_t>::max()) continue;
      const Vec3 d = cloud.positions[row[j].index] - cloud.positions[i] - mean;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    Vec3 normal = eig.eigenvectors().col(0).normalized();
    if (!normal.allFinite()) normal = Vec3::UnitZ();
    if (config.viewpoint && normal.dot(*config.viewpoint - cloud.positions[i]) < 0) normal = -normal;
    cloud.normals[i] = normal;
    if (config.write_curvature) {
      const Eigen::Vector3d l = eig.eigenvalues().cwiseMax(0.0);
      const double sum = l.sum();
      cloud.curvature[i] = sum > 0 ? static_cast<float>(l(0) / sum) : 0.0f;
    }
  }
  if (config.viewpoint) return;
  std::vector<uint32_t> first, adj;
  symmetricKnnGraph(rows, n, kk, first, adj);
  orientOverGraph(cloud, first, adj);
}

namespace {

/// Candidates of sample i from prebuilt neighbour lists (the sample itself included).
struct ListCandidates {
  const NeighborLists& lists;
  size_t gather(const std::vector<Vec3>& positions, const Vec3* normals, uint32_t i, MlsLocalSamples& s,
                double support, const WeightFunction& weight) {
    return s.gather(positions.data(), normals, lists.begin(i), lists.count(i), i, positions[i], support,
                    weight,
                    /*orient_normals=*/normals != nullptr);
  }
};

/// Candidates of sample i from a kd-tree radius query (each thread its own copy: the buffers).
struct TreeCandidates {
  const KdTree& tree;
  std::vector<Neighbor> hits;
  std::vector<uint32_t> ids;
  size_t gather(const std::vector<Vec3>& positions, const Vec3* normals, uint32_t i, MlsLocalSamples& s,
                double support, const WeightFunction& weight) {
    if (!positions[i].allFinite()) return 0;
    tree.radius(positions[i], support, hits);
    ids.resize(hits.size());
    for (size_t k = 0; k < hits.size(); ++k) ids[k] = hits[k].index;
    return s.gather(positions.data(), normals, ids.data(), ids.size(), MlsLocalSamples::kNoExtra,
                    positions[i], support, weight, /*orient_normals=*/normals != nullptr);
  }
};

/// fit(i, samples) for every sample i, in parallel, on the samples of positive weight around x_i (with
/// `normals` when given, oriented per neighbourhood) when there are at least min_n of them.
template <class Candidates, class Fit>
void forEachNeighbourhood(const std::vector<Vec3>& positions, const Vec3* normals, Candidates candidates,
                          double support, const WeightFunction& weight, size_t min_n, Fit&& fit) {
#pragma omp parallel firstprivate(candidates)
  {
    MlsLocalSamples samples;
#pragma omp for schedule(dynamic, 256)
    for (long k = 0; k < static_cast<long>(positions.size()); ++k) {
      const uint32_t i = static_cast<uint32_t>(k);
      if (candidates.gather(positions, normals, i, samples, support, weight) >= min_n) fit(i, samples);
    }
  }
}

/// The plane normal (3.5) at every sample.
template <class Candidates>
void planeNormals(const std::vector<Vec3>& positions, Candidates candidates, const WeightFunction& weight,
                  double support, size_t min_neighbors, std::vector<Vec3>& normals) {
  normals.assign(positions.size(), Vec3::Zero());
  forEachNeighbourhood(positions, nullptr, candidates, support, weight, std::max<size_t>(min_neighbors, 3),
                       [&](uint32_t i, const MlsLocalSamples& samples) {
                         Vec3 mean, normal;
                         if (fitLocalPlane(samples, &mean, &normal)) normals[i] = normal;
                       });
}

/// One refinement pass: at every sample the oriented sphere fit (APSS) over its neighbours with the current
/// normals, oriented per neighbourhood; the new normal is the sphere's gradient at the sample (u_l, the
/// sample being the local origin), signed like the old one: the neighbours' normals averaged as the fit
/// weighs them, with the curvature the positions give.
template <class Candidates>
void sphereRefinement(const std::vector<Vec3>& positions, Candidates candidates, const WeightFunction& weight,
                      double support, size_t min_neighbors, std::vector<Vec3>& normals) {
  std::vector<Vec3> refined(normals);
  forEachNeighbourhood(positions, normals.data(), candidates, support, weight,
                       std::max<size_t>(min_neighbors, 4), [&](uint32_t i, const MlsLocalSamples& samples) {
                         LocalSphere sphere;
                         if (normals[i].isZero() || !fitLocalSphereWithNormals(samples, &sphere)) return;
                         const double length = sphere.ul.norm();
                         if (!(length > 0) || !std::isfinite(length)) return;
                         const Vec3 normal = sphere.ul / length;
                         refined[i] = normal.dot(normals[i]) < 0 ? Vec3(-normal) : normal;
                       });
  normals.swap(refined);
}

}  // namespace

void refineNormalsBySpheres(const std::vector<Vec3>& positions, const NeighborLists& lists,
                            const WeightFunction& weight, double support, size_t min_neighbors,
                            std::vector<Vec3>& normals) {
  if (lists.numPoints() != positions.size() || lists.radius() < support || normals.size() != positions.size())
    throw std::invalid_argument(
        "refineNormalsBySpheres: the lists or the normals do not cover the points at the support radius");
  sphereRefinement(positions, ListCandidates{lists}, weight, support, min_neighbors, normals);
}

void refineNormalsBySpheres(const std::vector<Vec3>& positions, const KdTree& tree,
                            const WeightFunction& weight, double support, size_t min_neighbors,
                            std::vector<Vec3>& normals) {
  if (tree.size() != positions.size() || normals.size() != positions.size())
    throw std::invalid_argument("refineNormalsBySpheres: the tree or the normals do not hold the points");
  sphereRefinement(positions, TreeCandidates{tree, {}, {}}, weight, support, min_neighbors, normals);
}

void estimatePlaneNormals(const std::vector<Vec3>& positions, const NeighborLists& lists,
                          const WeightFunction& weight, double support, size_t min_neighbors,
                          std::vector<Vec3>& normals) {
  if (lists.numPoints() != positions.size() || lists.radius() < support)
    throw std::invalid_argument(
        "estimatePlaneNormals: the lists do not cover the points at the support radius");
  planeNormals(positions, ListCandidates{lists}, weight, support, min_neighbors, normals);
}

void estimatePlaneNormals(const std::vector<Vec3>& positions, const KdTree& tree,
                          const WeightFunction& weight, double support, size_t min_neighbors,
                          std::vector<Vec3>& normals) {
  if (tree.size() != positions.size())
    throw std::invalid_argument("estimatePlaneNormals: the tree does not hold the points");
  planeNormals(positions, TreeCandidates{tree, {}, {}}, weight, support, min_neighbors, normals);
}

size_t orientNormalsConsistently(SurfelCloud& cloud, int k) {
  if (!cloud.hasNormals()) throw std::invalid_argument("orientNormalsConsistently: the cloud has no normals");
  if (k < 1) throw std::invalid_argument("orientNormalsConsistently: k must be >= 1");
  const size_t n = cloud.size();
  if (n == 0) return 0;
  KdTree tree(cloud.positions);
  const size_t kk = std::min<size_t>(k + 1, n);
  std::vector<Neighbor> rows;
  tree.knnBatch(cloud.positions, kk, rows);
  std::vector<uint32_t> first, adj;
  symmetricKnnGraph(rows, n, kk, first, adj);
  return orientOverGraph(cloud, first, adj);
}

}  // namespace rc
