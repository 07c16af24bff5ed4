#include "relaxed_connectivity/mesh/surface_decimation.h"

#include <Eigen/Dense>

#include <algorithm>
#include <map>
#include <queue>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace rc {
namespace {

using Quadric = Eigen::Matrix4d;

struct Candidate {
  double cost;
  int a, b, version_a, version_b;
  Vec3 target;
  bool operator>(const Candidate& o) const { return cost > o.cost; }
};

}  // namespace

TriangleMesh decimateSurface(const TriangleMesh& surface, const DecimationOptions& options) {
  if (options.target_vertices < 4)
    throw std::invalid_argument("decimateSurface: target_vertices must be >= 4, got " +
                                std::to_string(options.target_vertices));
  std::vector<Vec3> x = surface.vertices.positions;
  const int n = static_cast<int>(x.size());
  std::vector<std::array<int, 3>> tris;
  for (const Triangle& t : surface.triangles) tris.push_back({int(t[0]), int(t[1]), int(t[2])});
  {
    std::map<std::pair<int, int>, int> directed;
    for (const auto& t : tris)
      for (int k = 0; k < 3; ++k) {
        if (t[k] < 0 || t[k] >= n) throw std::invalid_argument("decimateSurface: vertex index out of range");
        ++directed[{t[k], t[(k + 1) % 3]}];
      }
    for (const auto& [e, count] : directed)
      if (count != 1 || !directed.count({e.second, e.first}))
        throw std::invalid_argument("decimateSurface: edge (" + std::to_string(e.first) + ", " +
                                    std::to_string(e.second) +
                                    ") is not used once in each direction (open or non-manifold surface)");
  }
  std::vector<char> tri_alive(tris.size(), 1), vertex_alive(n, 0);
  std::vector<std::vector<int>> incident(n);
  std::vector<Quadric> quadric(n, Quadric::Zero());
  double mean_area = 0.0;
  for (size_t t = 0; t < tris.size(); ++t) {
    const auto& v = tris[t];
    const Vec3 normal = (x[v[1]] - x[v[0]]).cross(x[v[2]] - x[v[0]]);
    const double area2 = normal.norm();
    mean_area += 0.5 * area2 / tris.size();
    for (int k = 0; k < 3; ++k) {
      incident[v[k]].push_back(int(t));
      vertex_alive[v[k]] = 1;
    }
    if (!(area2 > 0.0)) continue;
    Eigen::Vector4d plane;
    plane << normal / area2, -(normal / area2).dot(x[v[0]]);
    const Quadric q = 0.5 * area2 * plane * plane.transpose();
    for (int k = 0; k < 3; ++k) quadric[v[k]] += q;
  }
  int alive = static_cast<int>(std::count(vertex_alive.begin(), vertex_alive.end(), 1));
  std::vector<int> version(n, 0);

  auto neighbours = [&](int a) {
    std::vector<int> out;
    for (int t : incident[a])
      if (tri_alive[t])
        for (int v : tris[t])
          if (v != a) out.push_back(v);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  };
  auto evaluate = [&](int a, int b) {
    const Quadric q = quadric[a] + quadric[b];
    auto cost = [&](const Vec3& p) {
      Eigen::Vector4d h;
      h << p, 1.0;
      return h.dot(q * h);
    };
    Vec3 best = 0.5 * (x[a] + x[b]);
    double best_cost = cost(best);
    const Eigen::Matrix3d a3 = q.topLeftCorner<3, 3>();
    if (std::abs(a3.determinant()) > 1e-12 * std::pow(a3.norm(), 3)) {
      const Vec3 p = a3.ldlt().solve(-q.topRightCorner<3, 1>());
      // Only near the edge (avoid far-off optima of nearly singular quadrics).
      if (p.allFinite() && (p - best).norm() < (x[a] - x[b]).norm() && cost(p) < best_cost) {
        best = p;
        best_cost = cost(p);
      }
    }
    for (const Vec3& p : {x[a], x[b]})
      if (cost(p) < best_cost) {
        best = p;
        best_cost = cost(p);
      }
    return Candidate{std::max(best_cost, 0.0), a, b, version[a], version[b], best};
  };
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> queue;
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k)
      if (t[k] < t[(k + 1) % 3]) queue.push(evaluate(t[k], t[(k + 1) % 3]));

  while (alive > options.target_vertices && !queue.empty()) {
    const Candidate c = queue.top();
    queue.pop();
    const int a = c.a, b = c.b;
    if (!vertex_alive[a] || !vertex_alive[b] || version[a] != c.version_a || version[b] != c.version_b)
      continue;
    // Link condition: exactly the two opposite vertices of the edge's triangles are common neighbours.
    const std::vector<int> na = neighbours(a), nb = neighbours(b);
    if (!std::binary_search(na.begin(), na.end(), b)) continue;
    std::vector<int> common;
    std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
    if (common.size() != 2 || na.size() + nb.size() <= 6) continue;  // keep at least a tetrahedron
    // No flipped or degenerate triangle around a and b.
    bool ok = true;
    for (int v : {a, b})
      for (int t : incident[v]) {
        if (!tri_alive[t] || !ok) continue;
        const auto& tri = tris[t];
        if ((tri[0] == a || tri[1] == a || tri[2] == a) && (tri[0] == b || tri[1] == b || tri[2] == b))
          continue;
        Vec3 p[3];
        for (int k = 0; k < 3; ++k) p[k] = (tri[k] == a || tri[k] == b) ? c.target : x[tri[k]];
        const Vec3 before = (x[tri[1]] - x[tri[0]]).cross(x[tri[2]] - x[tri[0]]);
        const Vec3 after = (p[1] - p[0]).cross(p[2] - p[0]);
        if (0.5 * after.norm() < options.min_relative_area * mean_area ||
            before.dot(after) < options.min_normal_cosine * before.norm() * after.norm())
          ok = false;
      }
    if (!ok) continue;
    // Collapse b into a.
    for (int t : incident[b]) {
      if (!tri_alive[t]) continue;
      auto& tri = tris[t];
      if (tri[0] == a || tri[1] == a || tri[2] == a) {
        tri_alive[t] = 0;
        continue;
      }
      for (int& v : tri)
        if (v == b) v = a;
      incident[a].push_back(t);
    }
    incident[b].clear();
    vertex_alive[b] = 0;
    --alive;
    x[a] = c.target;
    quadric[a] += quadric[b];
    ++version[a];
    std::vector<int> live;
    for (int t : incident[a])
      if (tri_alive[t]) live.push_back(t);
    incident[a] = live;
    for (int v : neighbours(a)) {
      ++version[v];  // neighbours' candidates moved with a; re-evaluate their edges to a
    }
    for (int v : neighbours(a)) {
      queue.push(evaluate(std::min(a, v), std::max(a, v)));
      for (int w : neighbours(v))
        if (w != a) queue.push(evaluate(std::min(v, w), std::max(v, w)));
    }
  }

  TriangleMesh out;
  std::vector<int> index(n, -1);
  for (int v = 0; v < n; ++v)
    if (vertex_alive[v]) {
      index[v] = static_cast<int>(out.vertices.positions.size());
      out.vertices.positions.push_back(x[v]);
    }
  for (size_t t = 0; t < tris.size(); ++t)
    if (tri_alive[t])
      out.triangles.push_back(
          {uint32_t(index[tris[t][0]]), uint32_t(index[tris[t][1]]), uint32_t(index[tris[t][2]])});
  return out;
}

}  // namespace rc
