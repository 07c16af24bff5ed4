#include "relaxed_connectivity/fem/fem_scene_regions.h"

#include <algorithm>
#include <iterator>

namespace rc {

Vec3 FemHeldRegion::displacementAt(double time) const {
  if (path.empty()) return displacement;
  if (time <= path.front().first) return path.front().second;
  if (time >= path.back().first) return path.back().second;
  const auto next =
      std::upper_bound(path.begin(), path.end(), time,
                       [](double t, const std::pair<double, Vec3>& key) { return t < key.first; });
  const auto previous = std::prev(next);
  const double s = (time - previous->first) / (next->first - previous->first);
  return (1.0 - s) * previous->second + s * next->second;
}

bool inFemBox(const Vec3& r, const Vec3& lo, const Vec3& hi, double tolerance) {
  return ((r - lo).array() >= -tolerance).all() && ((hi - r).array() >= -tolerance).all();
}

bool femSelects(const Vec3& lo, const Vec3& hi, const std::vector<Vec3>& points, const Vec3& r,
                double tolerance) {
  if (!inFemBox(r, lo, hi, tolerance)) return false;
  return points.empty() || std::any_of(points.begin(), points.end(), [&](const Vec3& p) {
           return ((p - r).array().abs() <= tolerance).all();
         });
}

Eigen::VectorXd femTractionForces(const PolyhedralMesh& mesh, const FemLoad& load, double tolerance,
                                  double* area) {
  Eigen::VectorXd forces = Eigen::VectorXd::Zero(3 * mesh.numNodes());
  double loaded = 0.0;
  for (const PolyhedralMesh::Triangle& tri : mesh.boundaryTriangles()) {
    if (!std::all_of(tri.begin(), tri.end(),
                     [&](int v) { return femSelects(load, mesh.node(v), tolerance); }))
      continue;
    const double a =
        0.5 * (mesh.node(tri[1]) - mesh.node(tri[0])).cross(mesh.node(tri[2]) - mesh.node(tri[0])).norm();
    loaded += a;
    for (int v : tri) forces.segment<3>(3 * v) += a / 3.0 * load.force;
  }
  if (area) *area = loaded;
  return forces;
}

}  // namespace rc
