#include "relaxed_connectivity/fem/polygon_geometry.h"

#include <Eigen/Geometry>

namespace rc {

double boundingDiagonal(const std::vector<Vec3>& points) {
  Vec3 lo = points.front(), hi = points.front();
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

double signedArea(const std::vector<Eigen::Vector2d>& polygon) {
  double area = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i) area += cross2(polygon[i], polygon[(i + 1) % polygon.size()]);
  return 0.5 * area;
}

bool isConvexPolygon(const std::vector<Eigen::Vector2d>& polygon, double turn_tolerance,
                     double area_tolerance) {
  const size_t k = polygon.size();
  int sign = 0;
  for (size_t i = 0; i < k; ++i) {
    const double turn =
        cross2(polygon[(i + 1) % k] - polygon[i], polygon[(i + 2) % k] - polygon[(i + 1) % k]);
    if (std::abs(turn) <= turn_tolerance) continue;
    const int s = turn > 0.0 ? 1 : -1;
    if (sign != 0 && s != sign) return false;
    sign = s;
  }
  return std::abs(signedArea(polygon)) > area_tolerance;
}

bool convexPolygonsOverlap(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b,
                           double tol) {
  for (const auto* polygon : {&a, &b})
    for (size_t k = 0; k < polygon->size(); ++k) {
      const Eigen::Vector2d edge = (*polygon)[(k + 1) % polygon->size()] - (*polygon)[k];
      if (!(edge.norm() > 0.0)) continue;
      const Eigen::Vector2d axis = Eigen::Vector2d(-edge.y(), edge.x()).normalized();
      double lo_a = INFINITY, hi_a = -INFINITY, lo_b = INFINITY, hi_b = -INFINITY;
      for (const auto& p : a) {
        lo_a = std::min(lo_a, axis.dot(p));
        hi_a = std::max(hi_a, axis.dot(p));
      }
      for (const auto& p : b) {
        lo_b = std::min(lo_b, axis.dot(p));
        hi_b = std::max(hi_b, axis.dot(p));
      }
      if (std::min(hi_a, hi_b) - std::max(lo_a, lo_b) <= tol) return false;
    }
  return true;
}

std::vector<std::array<int, 3>> bestFanTriangulation(const std::vector<Vec3>& nodes,
                                                     const std::vector<int>& face) {
  const int k = static_cast<int>(face.size());
  Vec3 normal = Vec3::Zero();
  for (int j = 1; j + 1 < k; ++j)
    normal += (nodes[face[j]] - nodes[face[0]]).cross(nodes[face[j + 1]] - nodes[face[0]]);
  int best_apex = 0;
  double best_min_area = -INFINITY;
  for (int apex = 0; apex < k; ++apex) {
    double min_area = INFINITY;
    for (int j = 1; j + 1 < k; ++j) {
      const Vec3& a = nodes[face[apex]];
      const Vec3& b = nodes[face[(apex + j) % k]];
      const Vec3& c = nodes[face[(apex + j + 1) % k]];
      min_area = std::min(min_area, normal.dot((b - a).cross(c - a)));
    }
    if (min_area > best_min_area) {
      best_min_area = min_area;
      best_apex = apex;
    }
  }
  std::vector<std::array<int, 3>> fan;
  for (int j = 1; j + 1 < k; ++j)
    fan.push_back({face[best_apex], face[(best_apex + j) % k], face[(best_apex + j + 1) % k]});
  return fan;
}

}  // namespace rc
