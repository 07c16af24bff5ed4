#include "relaxed_connectivity/fem/fem_cut_polygon.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/fem/polygon_geometry.h"

namespace rc {

FemSceneCut femCutFromPolygon(const std::vector<Vec3>& input, double planarity_tolerance) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("cut polygon: " + what); };
  for (size_t k = 0; k < input.size(); ++k)
    if (!input[k].allFinite()) fail("point " + std::to_string(k) + " is not finite");
  double diameter = 0.0;
  for (const Vec3& a : input)
    for (const Vec3& b : input) diameter = std::max(diameter, (a - b).norm());
  // Repeated consecutive points (also a closing copy of the first) are dropped.
  std::vector<Vec3> polygon;
  for (const Vec3& p : input)
    if (polygon.empty() || (p - polygon.back()).norm() > 1e-12 * diameter) polygon.push_back(p);
  while (polygon.size() > 1 && (polygon.back() - polygon.front()).norm() <= 1e-12 * diameter)
    polygon.pop_back();
  if (polygon.size() < 3)
    fail("needs at least 3 distinct points (got " + std::to_string(input.size()) + " points, " +
         std::to_string(polygon.size()) + " distinct)");

  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : polygon) centroid += p;
  centroid /= double(polygon.size());
  Vec3 normal = Vec3::Zero();  // Newell: twice the vector area
  for (size_t k = 0; k < polygon.size(); ++k)
    normal += (polygon[k] - centroid).cross(polygon[(k + 1) % polygon.size()] - centroid);
  if (!(0.5 * normal.norm() > 1e-9 * diameter * diameter)) fail("zero area (collinear or coincident points)");
  normal.normalize();
  for (size_t k = 0; k < polygon.size(); ++k) {
    const double distance = std::abs(normal.dot(polygon[k] - centroid));
    if (distance > planarity_tolerance * diameter)
      fail("not planar: point " + std::to_string(k) + " lies " + std::to_string(distance) +
           " m from the polygon's plane (tolerance " + std::to_string(planarity_tolerance * diameter) +
           " m)");
  }

  FemSceneCut cut;
  cut.point = centroid;
  cut.normal = normal;
  const Vec3 e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
  std::vector<Eigen::Vector2d> in_plane;
  for (const Vec3& p : polygon) {
    const Vec3 projected = p - normal * normal.dot(p - centroid);
    cut.region.push_back(projected);
    in_plane.emplace_back(e1.dot(projected - centroid), e2.dot(projected - centroid));
  }
  const double area_tolerance = 1e-12 * diameter * diameter;
  if (!isConvexPolygon(in_plane, area_tolerance, area_tolerance)) fail("not convex");
  return cut;
}

std::vector<std::vector<Vec3>> bladeSweepPolygons(const Vec3& blade_start, const Vec3& blade_end,
                                                  const std::vector<Vec3>& path) {
  if (path.size() < 2)
    throw std::invalid_argument("blade sweep: the path needs at least 2 points, got " +
                                std::to_string(path.size()));
  const Vec3 blade = blade_end - blade_start;
  if (!(blade.norm() > 0.0) || !blade.allFinite())
    throw std::invalid_argument("blade sweep: the blade has zero length");
  std::vector<std::vector<Vec3>> polygons;
  for (size_t k = 0; k + 1 < path.size(); ++k) {
    const Vec3 step = path[k + 1] - path[k];
    if (!(blade.cross(step).norm() > 1e-9 * blade.norm() * step.norm()) || !(step.norm() > 0.0))
      throw std::invalid_argument("blade sweep: path step " + std::to_string(k) +
                                  " is zero or parallel to the blade");
    polygons.push_back(
        {blade_start + path[k], blade_end + path[k], blade_end + path[k + 1], blade_start + path[k + 1]});
  }
  return polygons;
}

}  // namespace rc
