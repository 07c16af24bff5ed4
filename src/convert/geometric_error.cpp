#include "relaxed_connectivity/convert/geometric_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#if defined(RC_HAVE_CGAL)
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#endif

#include "relaxed_connectivity/core/kd_tree.h"

namespace rc {

#if defined(RC_HAVE_CGAL)

GeometricError geometricError(const TriangleMesh& mesh, const SurfelCloud& surfels, size_t samples) {
  if (mesh.triangles.empty() || surfels.empty())
    throw std::invalid_argument("geometricError: an empty mesh or surfel cloud");
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Triangle3 = Kernel::Triangle_3;
  using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle3>::const_iterator>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
  auto point = [](const Vec3& p) { return Kernel::Point_3(p.x(), p.y(), p.z()); };
  std::vector<Triangle3> triangles;
  std::vector<double> cumulative_area;
  triangles.reserve(mesh.triangles.size());
  double area = 0;
  for (const Triangle& t : mesh.triangles) {
    for (uint32_t v : t)
      if (v >= mesh.vertices.size() || !mesh.vertices.positions[v].allFinite())
        throw std::invalid_argument("geometricError: a triangle names a missing or non-finite vertex " +
                                    std::to_string(v));
    const Vec3 &a = mesh.vertices.positions[t[0]], &b = mesh.vertices.positions[t[1]],
               &c = mesh.vertices.positions[t[2]];
    triangles.emplace_back(point(a), point(b), point(c));
    area += 0.5 * (b - a).cross(c - a).norm();
    cumulative_area.push_back(area);
  }
  GeometricError e;
  Vec3 lo = surfels.positions.front(), hi = lo;
  for (const Vec3& p : surfels.positions) {
    if (!p.allFinite()) throw std::invalid_argument("geometricError: a surfel position is not finite");
    lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  }
  e.diagonal = (hi - lo).norm();

  // Surfel centres -> mesh (exact closest points).
  Tree tree(triangles.begin(), triangles.end());
  tree.accelerate_distance_queries();
  double sum = 0;
  for (const Vec3& p : surfels.positions) {
    const double d2 = CGAL::to_double(tree.squared_distance(point(p)));
    sum += d2;
    e.points_to_mesh_max = std::max(e.points_to_mesh_max, std::sqrt(d2));
  }
  e.points_to_mesh_rms = std::sqrt(sum / double(surfels.size()));

  // Mesh -> surfels at area-uniform samples (fixed seed): the distance to the nearest of the surfel discs
  // around (radius: the surfel's, unbounded without radii; the centre alone without normals).
  constexpr size_t kDiscs = 8;
  auto discDistance = [&](const Vec3& q, uint32_t i) {
    const Vec3 n = surfels.normals[i].normalized(), d = q - surfels.positions[i];
    const double height = d.dot(n);
    const double radius = surfels.hasRadii() ? surfels.radii[i] : std::numeric_limits<double>::infinity();
    const double outside = std::max(0.0, (d - height * n).norm() - radius);
    return std::sqrt(height * height + outside * outside);
  };
  e.samples = samples > 0 ? samples : surfels.size();
  const KdTree centres(surfels.positions);
  std::mt19937_64 random(20071);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  sum = 0;
  for (size_t s = 0; s < e.samples; ++s) {
    const double at = unit(random) * area;
    const size_t t = size_t(std::lower_bound(cumulative_area.begin(), cumulative_area.end(), at) -
                            cumulative_area.begin());
    const Triangle& tri = mesh.triangles[std::min(t, mesh.triangles.size() - 1)];
    double u = unit(random), v = unit(random);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Vec3& a = mesh.vertices.positions[tri[0]];
    const Vec3 q = a + u * (mesh.vertices.positions[tri[1]] - a) + v * (mesh.vertices.positions[tri[2]] - a);
    Neighbor nearest[kDiscs];
    const size_t found = centres.knn(q, kDiscs, nearest);
    double d = std::sqrt(nearest[0].sq_dist);
    if (surfels.hasNormals())
      for (size_t k = 0; k < found; ++k) d = std::min(d, discDistance(q, nearest[k].index));
    sum += d * d;
    e.mesh_to_points_max = std::max(e.mesh_to_points_max, d);
  }
  e.mesh_to_points_rms = std::sqrt(sum / double(e.samples));
  const double diagonal = e.diagonal > 0 ? e.diagonal : 1.0;
  e.hausdorff = std::max(e.points_to_mesh_max, e.mesh_to_points_max) / diagonal;
  e.rms = std::sqrt(0.5 * (e.points_to_mesh_rms * e.points_to_mesh_rms +
                           e.mesh_to_points_rms * e.mesh_to_points_rms)) /
          diagonal;
  return e;
}

#else

GeometricError geometricError(const TriangleMesh&, const SurfelCloud&, size_t) {
  throw std::runtime_error("geometricError: this build has no CGAL (install libcgal-dev and rebuild)");
}

#endif

}  // namespace rc
