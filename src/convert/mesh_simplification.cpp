#include "relaxed_connectivity/convert/mesh_simplification.h"

#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#if defined(RC_HAVE_CGAL)
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#endif

#include "relaxed_connectivity/mesh/mesh_metrics.h"

namespace rc {

#if defined(RC_HAVE_CGAL)
// GCC 12 flags a 4x4 Eigen quadric inside CGAL's Garland-Heckbert policies as maybe uninitialised: a false
// positive in their code. (A pragma, not a per-file option: the file is compiled in a unity group.)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;

/// Stops at the triangle count or before a collapse costing more than the squared error bound.
/// Reports progress every few thousand collapses (and cancels by throwing).
struct StopPredicate {
  size_t target_edges;  // a closed triangle mesh has 3/2 edges per triangle
  double max_cost;      // squared distance; infinity: none
  const StageProgress* progress;
  mutable size_t calls = 0;
  template <typename Profile>
  bool operator()(const double& cost, const Profile&, std::size_t initial_edges,
                  std::size_t current_edges) const {
    if (++calls % 2048 == 0 && *progress &&
        !(*progress)(double(initial_edges - current_edges) /
                     double(initial_edges > target_edges + 1 ? initial_edges - target_edges : 1)))
      throw ConversionCancelled("simplification");
    return current_edges <= target_edges || cost > max_cost;
  }
};

}  // namespace

TriangleMesh simplifyMesh(const TriangleMesh& input, const SimplificationOptions& options,
                          SimplificationStats* stats_out, const StageProgress& progress) {
  if (options.target_triangles == 0 && !(options.max_error > 0))
    throw std::invalid_argument("simplifyMesh: give target_triangles or max_error > 0");
  if (!(options.max_error >= 0)) throw std::invalid_argument("simplifyMesh: max_error must be >= 0");
  const EdgeStatistics edges = edgeStatistics(input);
  if (edges.non_manifold_edges > 0 || edges.misoriented_edges > 0 || edges.degenerate_triangles > 0)
    throw std::invalid_argument("simplifyMesh: the mesh is not an oriented manifold (" +
                                std::to_string(edges.non_manifold_edges) + " non-manifold, " +
                                std::to_string(edges.misoriented_edges) + " misoriented edges, " +
                                std::to_string(edges.degenerate_triangles) + " degenerate triangles)");
  // Only the vertices the triangles use, as a polygon soup -> Surface_mesh.
  std::vector<int64_t> index(input.vertices.size(), -1);
  std::vector<Kernel::Point_3> points;
  std::vector<std::vector<std::size_t>> polygons;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Triangle& t : input.triangles) {
    std::vector<std::size_t> polygon;
    for (uint32_t v : t) {
      if (v >= input.vertices.size())
        throw std::invalid_argument("simplifyMesh: a triangle names vertex " + std::to_string(v) + " of " +
                                    std::to_string(input.vertices.size()));
      if (index[v] < 0) {
        const Vec3& p = input.vertices.positions[v];
        if (!p.allFinite())
          throw std::invalid_argument("simplifyMesh: vertex " + std::to_string(v) + " is not finite");
        index[v] = int64_t(points.size());
        points.emplace_back(p.x(), p.y(), p.z());
        lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
      }
      polygon.push_back(std::size_t(index[v]));
    }
    polygons.push_back(std::move(polygon));
  }
  Mesh mesh;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, polygons, mesh);
  SimplificationStats stats;
  stats.input_triangles = input.triangles.size();
  const double diagonal = points.empty() ? 0.0 : (hi - lo).norm();
  const double bound = options.max_error > 0 ? options.max_error * diagonal : 0.0;
  StopPredicate stop{options.target_triangles > 0 ? options.target_triangles * 3 / 2 : 0,
                     bound > 0 ? bound * bound : std::numeric_limits<double>::infinity(), &progress};
  CGAL::Surface_mesh_simplification::GarlandHeckbert_plane_policies<Mesh, Kernel> policies(mesh);
  namespace SMS = CGAL::Surface_mesh_simplification;
  stats.collapses = std::size_t(SMS::edge_collapse(
      mesh, stop, CGAL::parameters::get_cost(policies.get_cost()).get_placement(policies.get_placement())));
  mesh.collect_garbage();

  TriangleMesh out;
  out.vertices.positions.reserve(mesh.number_of_vertices());
  for (const auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    out.vertices.positions.emplace_back(p.x(), p.y(), p.z());
  }
  for (const auto f : mesh.faces()) {
    Triangle t{};
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh))
      t[std::min(k++, 2)] = uint32_t(v.idx());
    out.triangles.push_back(t);
  }
  out.vertices.normals.assign(out.vertices.positions.size(), Vec3::Zero());
  for (const Triangle& t : out.triangles) {
    const Vec3& p0 = out.vertices.positions[t[0]];
    const Vec3 n = (out.vertices.positions[t[1]] - p0).cross(out.vertices.positions[t[2]] - p0);
    for (uint32_t v : t) out.vertices.normals[v] += n;
  }
  for (Vec3& n : out.vertices.normals) n = n.norm() > 0 ? Vec3(n.normalized()) : Vec3(Vec3::UnitZ());
  stats.triangles = out.triangles.size();
  if (stats_out) *stats_out = stats;
  return out;
}

#else

TriangleMesh simplifyMesh(const TriangleMesh&, const SimplificationOptions&, SimplificationStats*,
                          const StageProgress&) {
  throw std::runtime_error("simplifyMesh: this build has no CGAL (install libcgal-dev and rebuild)");
}

#pragma GCC diagnostic pop
#endif

}  // namespace rc
