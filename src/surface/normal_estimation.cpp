#include "surface/normal_estimation.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <limits>
#include <queue>
#include <stdexcept>

#include "core/kd_tree.h"

namespace rc {

namespace {

/// Symmetric kNN graph (Hoppe's Riemannian graph without the EMST edges) as adjacency lists.
std::vector<std::vector<uint32_t>> symmetricKnnGraph(const KdTree& tree, const std::vector<Vec3>& pts,
                                                     int k) {
  const size_t n = pts.size(), kk = std::min<size_t>(k + 1, n);
  std::vector<Neighbor> rows;
  tree.knnBatch(pts, kk, rows);
  std::vector<std::vector<uint32_t>> adj(n);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < kk; ++j) {
      const uint32_t o = rows[i * kk + j].index;
      if (o == std::numeric_limits<uint32_t>::max() || o == i) continue;
      adj[i].push_back(o);
      adj[o].push_back(static_cast<uint32_t>(i));
    }
  for (auto& a : adj) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  return adj;
}

}  // namespace

void estimateNormals(SurfelCloud& cloud, const NormalEstimationConfig& config) {
  if (cloud.size() < 3) throw std::invalid_argument("estimateNormals: the cloud needs at least 3 points");
  if (config.k < 3) throw std::invalid_argument("estimateNormals: k must be >= 3");
  for (const Vec3& p : cloud.positions)
    if (!p.allFinite()) throw std::invalid_argument("estimateNormals: the cloud has non-finite positions");
  const size_t n = cloud.size(), k = std::min<size_t>(config.k, n);
  KdTree tree(cloud.positions);
  std::vector<Neighbor> rows;
  tree.knnBatch(cloud.positions, k, rows);
  cloud.normals.resize(n);
  if (config.write_curvature) cloud.curvature.resize(n);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < static_cast<long>(n); ++i) {
    // Covariance of the k nearest (PCA), centred at their mean.
    Vec3 mean = Vec3::Zero();
    size_t m = 0;
    for (size_t j = 0; j < k; ++j) {
      const Neighbor& nb = rows[i * k + j];
      if (nb.index == std::numeric_limits<uint32_t>::max()) continue;
      mean += cloud.positions[nb.index] - cloud.positions[i];
      ++m;
    }
    mean /= static_cast<double>(m);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (size_t j = 0; j < k; ++j) {
      const Neighbor& nb = rows[i * k + j];
      if (nb.index == std::numeric_limits<uint32_t>::max()) continue;
      const Vec3 d = cloud.positions[nb.index] - cloud.positions[i] - mean;
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
  if (!config.viewpoint) orientNormalsConsistently(cloud, config.k);
}

size_t orientNormalsConsistently(SurfelCloud& cloud, int k) {
  if (!cloud.hasNormals()) throw std::invalid_argument("orientNormalsConsistently: the cloud has no normals");
  if (k < 1) throw std::invalid_argument("orientNormalsConsistently: k must be >= 1");
  const size_t n = cloud.size();
  if (n == 0) return 0;
  KdTree tree(cloud.positions);
  const auto adj = symmetricKnnGraph(tree, cloud.positions, k);
  // Prim's minimum spanning tree over the Riemannian graph, edge cost 1 - |ni.nj|; each component starts at
  // its highest point, oriented +z, and the orientation is propagated parent -> child along the tree.
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
      for (uint32_t o : adj[node])
        if (!done[o]) heap.push({1.0 - std::abs(cloud.normals[node].dot(cloud.normals[o])), {o, node}});
    }
  }
  return flipped;
}

}  // namespace rc
