#include "relaxed_connectivity/mesh/surface_closing.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

namespace rc {
namespace {

using DirectedEdge = std::pair<uint32_t, uint32_t>;

struct EdgeHash {
  size_t operator()(const DirectedEdge& e) const { return (size_t(e.first) << 32) ^ size_t(e.second); }
};

using EdgeMap = std::unordered_map<DirectedEdge, int, EdgeHash>;  // directed edge -> triangle

EdgeMap directedEdges(const TriangleMesh& surface) {
  const size_t n = surface.vertices.positions.size();
  EdgeMap edges;
  edges.reserve(3 * surface.triangles.size());
  for (size_t t = 0; t < surface.triangles.size(); ++t) {
    const Triangle& tri = surface.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (tri[k] >= n)
        throw std::invalid_argument("closeSurfaceHoles: triangle " + std::to_string(t) +
                                    " references vertex " + std::to_string(tri[k]) + " (surface has " +
                                    std::to_string(n) + ")");
      const DirectedEdge e(tri[k], tri[(k + 1) % 3]);
      if (!edges.emplace(e, int(t)).second)
        throw std::invalid_argument("closeSurfaceHoles: edge (" + std::to_string(e.first) + ", " +
                                    std::to_string(e.second) +
                                    ") is used twice in the same direction (inconsistent orientation or "
                                    "non-manifold edge), triangle " +
                                    std::to_string(t));
    }
  }
  return edges;
}

Vec3 triangleNormal(const std::vector<Vec3>& x, uint32_t a, uint32_t b, uint32_t c) {
  return (x[b] - x[a]).cross(x[c] - x[a]);
}

double angleBetween(const Vec3& n0, const Vec3& n1) {
  const double d = n0.norm() * n1.norm();
  if (!(d > 0.0)) return M_PI;  // degenerate: worst
  return std::acos(std::clamp(n0.dot(n1) / d, -1.0, 1.0));
}

// Liepa's weight: (largest dihedral angle, area), compared lexicographically.
struct Weight {
  double angle = std::numeric_limits<double>::infinity(), area = std::numeric_limits<double>::infinity();
  Weight operator+(const Weight& o) const { return {std::max(angle, o.angle), area + o.area}; }
  bool operator<(const Weight& o) const {
    if (angle != o.angle) return angle < o.angle;
    return area < o.area;
  }
};

// Fills one loop (vertices in the direction of the surface's boundary edges) and appends the triangles.
double fillLoop(const std::vector<Vec3>& x, const std::vector<uint32_t>& loop,
                const std::vector<Vec3>& outside, std::vector<Triangle>& out) {
  const int n = static_cast<int>(loop.size());
  if (n == 3) {
    out.push_back({loop[2], loop[1], loop[0]});
    return angleBetween(triangleNormal(x, loop[2], loop[1], loop[0]), outside[0]);
  }
  // Fill triangle on loop positions i < m < k, oriented against the loop: (k, m, i).
  auto normal = [&](int i, int m, int k) { return triangleNormal(x, loop[k], loop[m], loop[i]); };
  std::vector<Weight> w(size_t(n) * n);
  std::vector<int> best(size_t(n) * n, -1);
  auto at = [n](int i, int k) { return size_t(i) * n + k; };
  for (int i = 0; i + 1 < n; ++i) w[at(i, i + 1)] = {0.0, 0.0};
  // Normal of the triangle across edge (i, k) below it: the surface for loop edges, else the sub-solution.
  auto belowNormal = [&](int i, int k) -> Vec3 {
    if (k == i + 1) return outside[i];
    const int m = best[at(i, k)];
    return normal(i, m, k);
  };
  for (int length = 2; length < n; ++length)
    for (int i = 0; i + length < n; ++i) {
      const int k = i + length;
      Weight best_w;
      int best_m = -1;
      for (int m = i + 1; m < k; ++m) {
        const Vec3 nt = normal(i, m, k);
        double angle = std::max(angleBetween(nt, belowNormal(i, m)), angleBetween(nt, belowNormal(m, k)));
        if (i == 0 && k == n - 1) angle = std::max(angle, angleBetween(nt, outside[n - 1]));
        const Weight candidate = w[at(i, m)] + w[at(m, k)] + Weight{angle, 0.5 * nt.norm()};
        if (best_m < 0 || candidate < best_w) {
          best_w = candidate;
          best_m = m;
        }
      }
      w[at(i, k)] = best_w;
      best[at(i, k)] = best_m;
    }
  std::vector<std::pair<int, int>> stack = {{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, k] = stack.back();
    stack.pop_back();
    if (k - i < 2) continue;
    const int m = best[at(i, k)];
    out.push_back({loop[k], loop[m], loop[i]});
    stack.push_back({i, m});
    stack.push_back({m, k});
  }
  return w[at(0, n - 1)].angle;
}

}  // namespace

int countBoundaryEdges(const TriangleMesh& surface) {
  std::map<DirectedEdge, int> count;
  for (const Triangle& t : surface.triangles)
    for (int k = 0; k < 3; ++k) ++count[std::minmax(t[k], t[(k + 1) % 3])];
  int boundary = 0;
  for (const auto& entry : count) boundary += entry.second == 1;
  return boundary;
}

TriangleMesh closeSurfaceHoles(const TriangleMesh& surface, HoleFillingStats* stats, int max_hole_edges) {
  const std::vector<Vec3>& x = surface.vertices.positions;
  const EdgeMap edges = directedEdges(surface);
  // Boundary half-edges a -> b (no b -> a), chained by their start vertex.
  std::unordered_map<uint32_t, uint32_t> next;
  std::unordered_map<uint32_t, int> triangle_of_start;
  std::vector<uint32_t> starts;
  for (const auto& [e, t] : edges) {
    if (edges.count({e.second, e.first})) continue;
    if (!next.emplace(e.first, e.second).second)
      throw std::invalid_argument("closeSurfaceHoles: boundary vertex " + std::to_string(e.first) +
                                  " lies on more than one hole (non-manifold vertex)");
    triangle_of_start[e.first] = t;
    starts.push_back(e.first);
  }
  std::sort(starts.begin(), starts.end());  // deterministic loop order
  HoleFillingStats s;
  s.boundary_edges = static_cast<int>(next.size());
  TriangleMesh closed = surface;
  std::unordered_map<uint32_t, char> visited;
  for (uint32_t start : starts) {
    if (visited.count(start)) continue;
    std::vector<uint32_t> loop;
    std::vector<Vec3> outside;  // normal of the surface triangle on loop edge j -> j + 1
    for (uint32_t v = start;;) {
      if (visited.count(v))
        throw std::invalid_argument("closeSurfaceHoles: boundary loop through vertex " + std::to_string(v) +
                                    " does not close");
      visited[v] = 1;
      loop.push_back(v);
      const Triangle& t = surface.triangles[triangle_of_start.at(v)];
      outside.push_back(triangleNormal(x, t[0], t[1], t[2]));
      auto it = next.find(v);
      if (it == next.end())
        throw std::invalid_argument("closeSurfaceHoles: boundary loop ends at vertex " + std::to_string(v));
      v = it->second;
      if (v == start) break;
    }
    if (static_cast<int>(loop.size()) > max_hole_edges)
      throw std::invalid_argument("closeSurfaceHoles: a hole has " + std::to_string(loop.size()) +
                                  " edges (more than max_hole_edges = " + std::to_string(max_hole_edges) +
                                  ")");
    const double angle = fillLoop(x, loop, outside, closed.triangles);
    ++s.holes;
    s.added_triangles += static_cast<int>(loop.size()) - 2;
    s.largest_hole = std::max(s.largest_hole, static_cast<int>(loop.size()));
    s.max_dihedral_degrees = std::max(s.max_dihedral_degrees, angle * 180.0 / M_PI);
  }
  if (stats) *stats = s;
  return closed;
}

}  // namespace rc
