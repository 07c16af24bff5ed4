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
#include <CGAL/Random.h>
#include <CGAL/Scale_space_reconstruction_3/Advancing_front_mesher.h>
#include <CGAL/Scale_space_reconstruction_3/Weighted_PCA_smoother.h>
#include <CGAL/Scale_space_surface_reconstruction_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/compute_average_spacing.h>
#include <CGAL/poisson_surface_reconstruction.h>
#include <CGAL/property_map.h>
#endif

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/mesh/mesh_metrics.h"

namespace rc {

ReconstructionMethod reconstructionMethodFromName(const std::string& name) {
  if (name == "advancing_front") return ReconstructionMethod::kAdvancingFront;
  if (name == "scale_space") return ReconstructionMethod::kScaleSpace;
  if (name == "poisson") return ReconstructionMethod::kPoisson;
  throw std::invalid_argument("reconstruction method '" + name +
                              "': choose advancing_front, scale_space or poisson");
}

const char* reconstructionMethodName(ReconstructionMethod method) {
  switch (method) {
    case ReconstructionMethod::kAdvancingFront:
      return "advancing_front";
    case ReconstructionMethod::kScaleSpace:
      return "scale_space";
    case ReconstructionMethod::kPoisson:
      return "poisson";
  }
  return "?";
}

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
  const std::vector<Vec3>* positions;  // the surfels'
  double max_edge_spacing;
  mutable size_t calls = 0;
  template <typename AdvancingFront, typename CellHandle>
  double operator()(const AdvancingFront& front, CellHandle& cell, const int& index) const {
    if (++calls % 4096 == 0 && *progress && !(*progress)(std::min(0.99, double(calls) / expected_calls)))
      throw ConversionCancelled("reconstruction");
    // Only facets of three surfels are bounded: not those of the infinite vertex, nor those of the vertex
    // CGAL adds above coplanar input (its id is not a surfel's: checked against the surfel's position).
    const auto& dt = front.triangulation_3();
    auto isSurfel = [&](const auto& v) {
      if (dt.is_infinite(v) || v->id() >= positions->size()) return false;
      const Vec3& p = (*positions)[v->id()];
      return v->point().x() == p.x() && v->point().y() == p.y() && v->point().z() == p.z();
    };
    if (spacing) {
      const auto a = cell->vertex((index + 1) & 3), b = cell->vertex((index + 2) & 3),
                 c = cell->vertex((index + 3) & 3);
      if (!isSurfel(a) || !isSurfel(b) || !isSurfel(c))
        return front.smallest_radius_delaunay_sphere(cell, index);
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

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

/// Connected components of a mesh's triangles (through shared vertices).
size_t countComponents(const TriangleMesh& mesh) {
  std::vector<uint32_t> parent(mesh.vertices.size());
  for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  auto find = [&](uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const Triangle& t : mesh.triangles) {
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  std::vector<bool> used(parent.size(), false), root(parent.size(), false);
  for (const Triangle& t : mesh.triangles)
    for (uint32_t v : t) used[v] = true;
  size_t count = 0;
  for (uint32_t v = 0; v < parent.size(); ++v)
    if (used[v] && !root[find(v)]) root[find(v)] = true, ++count;
  return count;
}

/// Poisson reconstruction (CGAL's Delaunay-refined implicit function and surface mesher).
TriangleMesh reconstructPoisson(const SurfelCloud& surfels, const ReconstructionOptions& options,
                                ReconstructionStats* stats_out, const StageProgress& progress) {
  using PointWithNormal = std::pair<Kernel::Point_3, Kernel::Vector_3>;
  std::vector<PointWithNormal> input;
  input.reserve(surfels.size());
  for (size_t i = 0; i < surfels.size(); ++i) {
    const Vec3& p = surfels.positions[i];
    const Vec3 n = surfels.normals[i].normalized();
    input.emplace_back(Kernel::Point_3(p.x(), p.y(), p.z()), Kernel::Vector_3(n.x(), n.y(), n.z()));
  }
  const double spacing = CGAL::compute_average_spacing<CGAL::Sequential_tag>(
      input, 6, CGAL::parameters::point_map(CGAL::First_of_pair_property_map<PointWithNormal>()));
  if (progress && !progress(0.1)) throw ConversionCancelled("reconstruction");
  CGAL::Surface_mesh<Kernel::Point_3> output;
  if (!CGAL::poisson_surface_reconstruction_delaunay(input.begin(), input.end(),
                                                     CGAL::First_of_pair_property_map<PointWithNormal>(),
                                                     CGAL::Second_of_pair_property_map<PointWithNormal>(),
                                                     output, spacing, 20.0, 30.0, options.poisson_distance))
    throw std::invalid_argument(
        "reconstructSurface: the Poisson reconstruction failed (its solver did not "
        "converge, or the normals are inconsistent)");
  if (progress && !progress(1.0)) throw ConversionCancelled("reconstruction");
  TriangleMesh mesh;
  std::vector<uint32_t> index(output.number_of_vertices() + output.number_of_removed_vertices(), 0);
  for (const auto v : output.vertices()) {
    index[size_t(v)] = uint32_t(mesh.vertices.positions.size());
    const auto& p = output.point(v);
    mesh.vertices.positions.emplace_back(p.x(), p.y(), p.z());
  }
  for (const auto f : output.faces()) {
    Triangle t{};
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(output.halfedge(f), output)) {
      if (k < 3) t[size_t(k)] = index[size_t(v)];
      ++k;
    }
    if (k == 3) mesh.triangles.push_back(t);
  }
  const EdgeStatistics edges = edgeStatistics(mesh);
  if (options.require_manifold && (edges.non_manifold_edges > 0 || edges.misoriented_edges > 0))
    throw std::invalid_argument("reconstructSurface: the Poisson surface is not an oriented manifold");
  ReconstructionStats stats;
  stats.triangles = mesh.triangles.size();
  stats.boundary_edges = edges.boundary_edges;
  stats.components = countComponents(mesh);
  if (stats_out) *stats_out = stats;
  return mesh;
}

TriangleMesh reconstructSurface(const SurfelCloud& surfels, const ReconstructionOptions& options,
                                ReconstructionStats* stats_out, const StageProgress& progress) {
  checkInput(surfels);
  // CGAL's default random generator seeds Poisson's surface mesher: a fixed seed per call makes its result
  // the same from run to run. (Exactly cospherical input, such as a sampled sphere, has several Delaunay
  // triangulations; which one the advancing front starts from can still depend on the heap's layout.)
  CGAL::get_default_random() = CGAL::Random(20071);
  if (!(options.radius_ratio_bound > 0) || !(options.beta > 0) || !(options.beta < M_PI / 2))
    throw std::invalid_argument("reconstructSurface: radius_ratio_bound must be > 0 and beta in (0, pi/2)");
  if (!(options.max_edge_spacing >= 0) || options.spacing_neighbors < 1)
    throw std::invalid_argument(
        "reconstructSurface: max_edge_spacing must be >= 0 and spacing_neighbors >= 1");
  std::vector<Kernel::Point_3> points;
  points.reserve(surfels.size());
  for (const Vec3& p : surfels.positions) points.emplace_back(p.x(), p.y(), p.z());
  if (options.scale_space_iterations < 0 || options.scale_space_neighbors < 3 ||
      !(options.poisson_distance > 0))
    throw std::invalid_argument(
        "reconstructSurface: scale_space_iterations must be >= 0, scale_space_neighbors >= 3, "
        "poisson_distance > 0");
  if (options.method == ReconstructionMethod::kPoisson)
    return reconstructPoisson(surfels, options, stats_out, progress);
  std::vector<double> spacing;
  if (options.max_edge_spacing > 0)
    spacing = KdTree(surfels.positions).kthNeighborDistances(size_t(options.spacing_neighbors));
  std::vector<std::array<std::size_t, 3>> faces;
  if (options.method == ReconstructionMethod::kScaleSpace) {
    // Smooth, mesh the smoothed points with the advancing front (edges bounded by the median spacing), keep
    // the facets on the original points.
    using Reconstruction = CGAL::Scale_space_surface_reconstruction_3<Kernel>;
    Reconstruction reconstruction(points.begin(), points.end());
    reconstruction.increase_scale(size_t(options.scale_space_iterations),
                                  CGAL::Scale_space_reconstruction_3::Weighted_PCA_smoother<Kernel>(
                                      unsigned(options.scale_space_neighbors)));
    if (progress && !progress(0.5)) throw ConversionCancelled("reconstruction");
    double bound = 0;
    if (!spacing.empty()) {
      std::vector<double> sorted = spacing;
      std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
      bound = options.max_edge_spacing * sorted[sorted.size() / 2];
    }
    reconstruction.reconstruct_surface(CGAL::Scale_space_reconstruction_3::Advancing_front_mesher<Kernel>(
        bound, options.radius_ratio_bound, options.beta));
    for (auto it = reconstruction.facets_begin(); it != reconstruction.facets_end(); ++it)
      faces.push_back({(*it)[0], (*it)[1], (*it)[2]});
  } else {
    // (CGAL evaluated the priority about 12 times per surfel on the Igea and the bunny.)
    const ReportingPriority priority{&progress, 12.0 * double(surfels.size()),
                                     options.max_edge_spacing > 0 ? &spacing : nullptr, &surfels.positions,
                                     options.max_edge_spacing};
    CGAL::advancing_front_surface_reconstruction(points.begin(), points.end(), std::back_inserter(faces),
                                                 priority, options.radius_ratio_bound, options.beta);
  }
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
