#include "relaxed_connectivity/convert/surface_reconstruction.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#if defined(RC_HAVE_CGAL)
#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#endif

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/mesh/mesh_metrics.h"

namespace rc {
namespace {

void checkInput(const SurfelCloud& surfels) {
  if (surfels.size() < 4)
    throw std::invalid_argument("reconstructSurface: " + std::to_string(surfels.size()) +
                                " surfels; a surface needs at least 4");
  if (!surfels.hasNormals())
    throw std::invalid_argument("reconstructSurface: the surfels have no normals (orient them first)");
  for (size_t i = 0; i < surfels.size(); ++i)
    if (!surfels.positions[i].allFinite() || !surfels.normals[i].allFinite())
      throw std::invalid_argument("reconstructSurface: surfel " + std::to_string(i) +
                                  " has a non-finite position or normal");
}

#if defined(RC_HAVE_CGAL)
/// Turns the triangles so that each edge shared by two of them is traversed once each way (a breadth-first
/// walk per component), then flips each component whose area-weighted normals disagree with the surfels'.
/// Returns false if a component cannot be oriented consistently (a Moebius-like or non-manifold patch).
bool orient(const SurfelCloud& surfels, std::vector<Triangle>& triangles, ReconstructionStats& stats) {
  // Edge -> the triangles using it.
  std::unordered_map<uint64_t, std::vector<uint32_t>> users;
  auto key = [](uint32_t a, uint32_t b) { return (uint64_t(std::min(a, b)) << 32) | std::max(a, b); };
  for (uint32_t t = 0; t < triangles.size(); ++t)
    for (int e = 0; e < 3; ++e) users[key(triangles[t][e], triangles[t][(e + 1) % 3])].push_back(t);
  std::vector<int> component(triangles.size(), -1);
  bool consistent = true;
  auto sameDirection = [](const Triangle& t, uint32_t a, uint32_t b) {
    for (int e = 0; e < 3; ++e)
      if (t[e] == a && t[(e + 1) % 3] == b) return true;
    return false;
  };
  int components = 0;
  std::vector<uint32_t> queue;
  for (uint32_t seed = 0; seed < triangles.size(); ++seed) {
    if (component[seed] >= 0) continue;
    const int c = components++;
    component[seed] = c;
    queue.assign(1, seed);
    std::vector<uint32_t> members;
    while (!queue.empty()) {
      const uint32_t t = queue.back();
      queue.pop_back();
      members.push_back(t);
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = triangles[t][e], b = triangles[t][(e + 1) % 3];
        for (const uint32_t u : users[key(a, b)]) {
          if (u == t) continue;
          if (component[u] < 0) {  // orient the neighbour against this triangle's edge
            if (sameDirection(triangles[u], a, b)) std::swap(triangles[u][1], triangles[u][2]);
            component[u] = c;
            queue.push_back(u);
          } else if (component[u] == c && sameDirection(triangles[u], a, b)) {
            consistent = false;
          }
        }
      }
    }
    // The surfels' normals vote, weighted by the triangle areas.
    double vote = 0;
    for (const uint32_t t : members) {
      const Vec3& p0 = surfels.positions[triangles[t][0]];
      const Vec3 n = (surfels.positions[triangles[t][1]] - p0).cross(surfels.positions[triangles[t][2]] - p0);
      vote += n.dot(surfels.normals[triangles[t][0]] + surfels.normals[triangles[t][1]] +
                    surfels.normals[triangles[t][2]]);
    }
    if (vote < 0) {
      for (const uint32_t t : members) std::swap(triangles[t][1], triangles[t][2]);
      ++stats.flipped_components;
    }
  }
  stats.components = size_t(components);
  return consistent;
}
#endif

}  // namespace

#if defined(RC_HAVE_CGAL)

bool meshGenerationAvailable() {
  return true;
}

/// CGAL's default priority (the smallest Delaunay radius of a candidate), reporting progress on the way, and
/// refusing (infinity: never in the output) candidates with an edge longer than max_edge_spacing times the
/// local sample spacing of its vertices: they bridge holes and gaps that the surfels do not cover (the open
/// side of a single-view scan, the space between separate objects).
struct ReportingPriority {
  const StageProgress* progress;
  double expected_calls;
  const std::vector<double>* spacing;  // per surfel; null: no edge bound
  double max_edge_spacing;
  mutable size_t calls = 0;
  template <typename AdvancingFront, typename CellHandle>
  double operator()(const AdvancingFront& front, CellHandle& cell, const int& index) const {
    if (++calls % 4096 == 0 && *progress && !(*progress)(std::min(0.99, double(calls) / expected_calls)))
      throw ConversionCancelled("reconstruction");
    if (spacing) {
      const auto a = cell->vertex((index + 1) & 3), b = cell->vertex((index + 2) & 3),
                 c = cell->vertex((index + 3) & 3);
      const double local =
          max_edge_spacing * std::max({(*spacing)[a->id()], (*spacing)[b->id()], (*spacing)[c->id()]});
      const double bound = local * local;
      if (CGAL::squared_distance(a->point(), b->point()) > bound ||
          CGAL::squared_distance(b->point(), c->point()) > bound ||
          CGAL::squared_distance(c->point(), a->point()) > bound)
        return std::numeric_limits<double>::infinity();
    }
    return front.smallest_radius_delaunay_sphere(cell, index);
  }
};

/// Distance from each surfel to its k-th nearest neighbour.
std::vector<double> sampleSpacing(const SurfelCloud& surfels, size_t k) {
  const KdTree tree(surfels.positions);
  std::vector<Neighbor> nn;
  tree.knnBatch(surfels.positions, k + 1, nn);
  std::vector<double> spacing(surfels.size());
  for (size_t i = 0; i < surfels.size(); ++i) {
    double d = 0;
    for (size_t j = k + 1; j-- > 0;)
      if (nn[i * (k + 1) + j].index != UINT32_MAX) {
        d = std::sqrt(nn[i * (k + 1) + j].sq_dist);
        break;
      }
    spacing[i] = d;
  }
  return spacing;
}

TriangleMesh reconstructSurface(const SurfelCloud& surfels, const ReconstructionOptions& options,
                                ReconstructionStats* stats_out, const StageProgress& progress) {
  checkInput(surfels);
  if (!(options.radius_ratio_bound > 0) || !(options.beta > 0) || !(options.beta < M_PI / 2))
    throw std::invalid_argument("reconstructSurface: radius_ratio_bound must be > 0 and beta in (0, pi/2)");
  if (!(options.max_edge_spacing >= 0) || options.spacing_neighbors < 1)
    throw std::invalid_argument(
        "reconstructSurface: max_edge_spacing must be >= 0 and spacing_neighbors >= 1");
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::vector<Kernel::Point_3> points;
  points.reserve(surfels.size());
  for (const Vec3& p : surfels.positions) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::array<std::size_t, 3>> faces;
  // (CGAL evaluated the priority about 12 times per surfel on the Igea and the bunny.)
  std::vector<double> spacing;
  if (options.max_edge_spacing > 0) spacing = sampleSpacing(surfels, size_t(options.spacing_neighbors));
  const ReportingPriority priority{&progress, 12.0 * double(surfels.size()),
                                   options.max_edge_spacing > 0 ? &spacing : nullptr,
                                   options.max_edge_spacing};
  CGAL::advancing_front_surface_reconstruction(points.begin(), points.end(), std::back_inserter(faces),
                                               priority, options.radius_ratio_bound, options.beta);
  if (progress && !progress(1.0)) throw ConversionCancelled("reconstruction");
  TriangleMesh mesh;
  mesh.vertices = surfels;
  mesh.triangles.reserve(faces.size());
  for (const auto& f : faces) mesh.triangles.push_back({uint32_t(f[0]), uint32_t(f[1]), uint32_t(f[2])});
  ReconstructionStats stats;
  const bool consistent = orient(surfels, mesh.triangles, stats);
  const EdgeStatistics edges = edgeStatistics(mesh);
  if (options.require_manifold &&
      (!consistent || edges.non_manifold_edges > 0 || edges.misoriented_edges > 0))
    throw std::invalid_argument("reconstructSurface: the reconstruction is not an orientable manifold (" +
                                std::to_string(edges.non_manifold_edges) +
                                " edges with more than two triangles, " +
                                std::to_string(edges.misoriented_edges) + " that could not be oriented)");
  std::vector<bool> used(surfels.size(), false);
  for (const Triangle& t : mesh.triangles)
    for (uint32_t v : t) used[v] = true;
  stats.triangles = mesh.triangles.size();
  stats.unused_surfels = size_t(std::count(used.begin(), used.end(), false));
  stats.boundary_edges = edges.boundary_edges;
  if (stats_out) *stats_out = stats;
  return mesh;
}

#else

bool meshGenerationAvailable() {
  return false;
}

TriangleMesh reconstructSurface(const SurfelCloud& surfels, const ReconstructionOptions&,
                                ReconstructionStats*, const StageProgress&) {
  checkInput(surfels);
  throw std::runtime_error("reconstructSurface: this build has no CGAL (install libcgal-dev and rebuild)");
}

#endif

}  // namespace rc
