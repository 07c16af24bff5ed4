#include "relaxed_connectivity/mesh/mesh_metrics.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace rc {

namespace {
void checkIndices(const TriangleMesh& mesh, const char* function) {
  const size_t n = mesh.vertices.size();
  for (size_t i = 0; i < mesh.triangles.size(); ++i)
    for (uint32_t index : mesh.triangles[i])
      if (index >= n)
        throw std::invalid_argument(std::string(function) + ": triangle " + std::to_string(i) +
                                    " references vertex " + std::to_string(index) + " of " +
                                    std::to_string(n));
}
}  // namespace

EdgeStatistics edgeStatistics(const TriangleMesh& mesh) {
  checkIndices(mesh, "edgeStatistics");
  // Directed half-edges keyed (min, max, direction); sorting groups the uses of each undirected edge.
  struct HalfEdge {
    uint64_t key;
    bool forward;  // traversed from the smaller to the larger index
    bool operator<(const HalfEdge& o) const { return key < o.key || (key == o.key && forward < o.forward); }
  };
  std::vector<HalfEdge> half_edges;
  half_edges.reserve(3 * mesh.triangles.size());
  EdgeStatistics stats;
  for (const Triangle& t : mesh.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
      ++stats.degenerate_triangles;
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      half_edges.push_back({(static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b), a < b});
    }
  }
  std::sort(half_edges.begin(), half_edges.end());
  for (size_t i = 0; i < half_edges.size();) {
    size_t j = i, forward = 0;
    for (; j < half_edges.size() && half_edges[j].key == half_edges[i].key; ++j)
      forward += half_edges[j].forward;
    const size_t uses = j - i;
    ++stats.edges;
    if (uses == 1)
      ++stats.boundary_edges;
    else if (uses > 2)
      ++stats.non_manifold_edges;
    else if (forward != 1)
      ++stats.misoriented_edges;
    i = j;
  }
  return stats;
}

bool isWatertight(const TriangleMesh& mesh) {
  const EdgeStatistics s = edgeStatistics(mesh);
  return s.edges > 0 && s.boundary_edges == 0 && s.non_manifold_edges == 0 && s.misoriented_edges == 0 &&
         s.degenerate_triangles == 0;
}

double signedVolume(const TriangleMesh& mesh) {
  checkIndices(mesh, "signedVolume");
  const auto& p = mesh.vertices.positions;
  double volume = 0.0;
  for (const Triangle& t : mesh.triangles) volume += p[t[0]].dot(p[t[1]].cross(p[t[2]]));
  return volume / 6.0;
}

double surfaceArea(const TriangleMesh& mesh) {
  checkIndices(mesh, "surfaceArea");
  const auto& p = mesh.vertices.positions;
  double area = 0.0;
  for (const Triangle& t : mesh.triangles) area += (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).norm();
  return 0.5 * area;
}

}  // namespace rc
