// Small planar-polygon helpers shared by the mesh builders and the cuts (thesis 9.1, 9.3): bounding
// diagonal, 2D convexity and overlap tests, counter-clockwise ordering of a plane section and the fan
// triangulation of element faces.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// Diagonal of the axis-aligned bounding box of points (non-empty).
double boundingDiagonal(const std::vector<Vec3>& points);

/// z component of the cross product of two 2D vectors.
inline double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

/// Signed area of a closed 2D polygon (positive counter-clockwise).
double signedArea(const std::vector<Eigen::Vector2d>& polygon);

/// All turns (cross products of consecutive edges) of the closed polygon beyond turn_tolerance have the same
/// sign (either orientation), and |signed area| > area_tolerance.
bool isConvexPolygon(const std::vector<Eigen::Vector2d>& polygon, double turn_tolerance,
                     double area_tolerance);

/// Interiors of two convex polygons overlap by more than tol (separating axis test over both edge sets).
bool convexPolygonsOverlap(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b,
                           double tol);

/// Fan triangulation of a planar polygon face (node ids into nodes) from the apex that maximises the
/// smallest fan triangle area (first such apex).
std::vector<std::array<int, 3>> bestFanTriangulation(const std::vector<Vec3>& nodes,
                                                     const std::vector<int>& face);

/// Indices of coplanar points sorted counter-clockwise around their centroid: by the angle of
/// in_plane(point - centroid), a Vec2 in the plane's frame; equal angles keep the input order. Point is an
/// Eigen vector (3D points with a frame projection, or 2D points with the identity).
template <class Point, class InPlane>
std::vector<int> counterClockwiseOrder(const std::vector<Point>& points, const InPlane& in_plane) {
  Point center = Point::Zero();
  for (const Point& p : points) center += p;
  center /= static_cast<double>(points.size());
  std::vector<std::pair<double, int>> by_angle;
  by_angle.reserve(points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector2d d = in_plane(Point(points[k] - center));
    by_angle.emplace_back(std::atan2(d.y(), d.x()), static_cast<int>(k));
  }
  std::sort(by_angle.begin(), by_angle.end());
  std::vector<int> order;
  order.reserve(by_angle.size());
  for (const auto& entry : by_angle) order.push_back(entry.second);
  return order;
}

}  // namespace rc
