#include "relaxed_connectivity/fem/convex_polyhedron.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace rc {
namespace {

std::string formatVec(const Vec3& v) {
  std::ostringstream s;
  s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("ConvexPolyhedron: " + what);
}

double boundingBoxDiagonal(const std::vector<Vec3>& points) {
  Vec3 lo = points.front(), hi = points.front();
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

// Newell's normal: twice the vector area of a (possibly non-planar) polygon.
Vec3 newellNormal(const std::vector<Vec3>& nodes, const ConvexPolyhedron::Face& face) {
  Vec3 n = Vec3::Zero();
  const Vec3& origin = nodes[face[0]];
  for (size_t k = 1; k + 1 < face.size(); ++k)
    n += (nodes[face[k]] - origin).cross(nodes[face[k + 1]] - origin);
  return n;
}

// Fan triangulation from the apex that maximises the smallest fan triangle area.
std::vector<ConvexPolyhedron::Triangle> bestFan(const std::vector<Vec3>& nodes,
                                                const ConvexPolyhedron::Face& face, const Vec3& normal) {
  const int k = static_cast<int>(face.size());
  int best_apex = 0;
  double best_min_area = -1.0;
  for (int apex = 0; apex < k; ++apex) {
    double min_area = INFINITY;
    for (int j = 1; j + 1 < k; ++j) {
      const Vec3& a = nodes[face[apex]];
      const Vec3& b = nodes[face[(apex + j) % k]];
      const Vec3& c = nodes[face[(apex + j + 1) % k]];
      min_area = std::min(min_area, 0.5 * normal.dot((b - a).cross(c - a)));
    }
    if (min_area > best_min_area) {
      best_min_area = min_area;
      best_apex = apex;
    }
  }
  std::vector<ConvexPolyhedron::Triangle> fan;
  for (int j = 1; j + 1 < k; ++j)
    fan.push_back({face[best_apex], face[(best_apex + j) % k], face[(best_apex + j + 1) % k]});
  return fan;
}

}  // namespace

ConvexPolyhedron::ConvexPolyhedron(std::vector<Vec3> nodes, std::vector<Face> faces,
                                   double relative_tolerance, std::vector<int> global_node_ids)
    : nodes_(std::move(nodes)),
      global_node_ids_(std::move(global_node_ids)),
      faces_(std::move(faces)),
      relative_tolerance_(relative_tolerance) {
  validateAndBuild({}, false);
}

ConvexPolyhedron::ConvexPolyhedron(std::vector<Vec3> nodes, std::vector<Face> faces,
                                   std::vector<std::vector<Triangle>> face_triangles,
                                   double relative_tolerance, std::vector<int> global_node_ids)
    : nodes_(std::move(nodes)),
      global_node_ids_(std::move(global_node_ids)),
      faces_(std::move(faces)),
      relative_tolerance_(relative_tolerance) {
  validateAndBuild(std::move(face_triangles), true);
}

void ConvexPolyhedron::validateAndBuild(std::vector<std::vector<Triangle>> face_triangles,
                                        bool given_triangulation) {
  const int n = numNodes();
  if (n < 4) fail("needs at least 4 nodes, got " + std::to_string(n));
  if (faces_.size() < 4) fail("needs at least 4 faces, got " + std::to_string(faces_.size()));
  if (!(relative_tolerance_ >= 0.0 && relative_tolerance_ < 1e-2))
    fail("relative tolerance must be in [0, 1e-2), got " + std::to_string(relative_tolerance_));
  for (int i = 0; i < n; ++i)
    if (!nodes_[i].allFinite()) fail("node " + std::to_string(i) + " is not finite");
  if (global_node_ids_.empty()) {
    for (int i = 0; i < n; ++i) global_node_ids_.push_back(i);
  } else if (static_cast<int>(global_node_ids_.size()) != n) {
    fail("global_node_ids has " + std::to_string(global_node_ids_.size()) + " entries for " +
         std::to_string(n) + " nodes");
  }
  if (given_triangulation && face_triangles.size() != faces_.size())
    fail("face_triangles has " + std::to_string(face_triangles.size()) + " entries for " +
         std::to_string(faces_.size()) + " faces");
  scale_ = boundingBoxDiagonal(nodes_);
  tolerance_ = relative_tolerance_ * scale_;
  if (!(scale_ > 0.0)) fail("all nodes coincide");

  // Faces: indices, planarity, convexity of the polygon.
  std::vector<int> node_use(n, 0);
  face_normals_.resize(faces_.size());
  face_offsets_.resize(faces_.size());
  for (size_t f = 0; f < faces_.size(); ++f) {
    const Face& face = faces_[f];
    const std::string name = "face " + std::to_string(f);
    if (face.size() < 3) fail(name + " has " + std::to_string(face.size()) + " nodes (needs >= 3)");
    for (size_t k = 0; k < face.size(); ++k) {
      if (face[k] < 0 || face[k] >= n)
        fail(name + " references node " + std::to_string(face[k]) + " (have " + std::to_string(n) + ")");
      for (size_t l = 0; l < k; ++l)
        if (face[l] == face[k]) fail(name + " uses node " + std::to_string(face[k]) + " twice");
      ++node_use[face[k]];
    }
    const Vec3 area_normal = newellNormal(nodes_, face);
    if (!(area_normal.norm() > 2.0 * tolerance_ * scale_)) fail(name + " is degenerate (zero area)");
    const Vec3 normal = area_normal.normalized();
    double offset = 0.0;
    for (int i : face) offset += normal.dot(nodes_[i]);
    offset /= static_cast<double>(face.size());
    for (int i : face) {
      const double off_plane = normal.dot(nodes_[i]) - offset;
      if (std::abs(off_plane) > tolerance_)
        fail(name + " is not planar: node " + std::to_string(i) + " is " + std::to_string(off_plane) +
             " from its plane (tolerance " + std::to_string(tolerance_) + ")");
    }
    const int k = static_cast<int>(face.size());
    for (int c = 0; c < k; ++c) {
      const Vec3& a = nodes_[face[c]];
      const Vec3& b = nodes_[face[(c + 1) % k]];
      const Vec3& d = nodes_[face[(c + 2) % k]];
      const double ab = (b - a).norm();
      if (ab <= tolerance_)
        fail(name + " has coincident nodes " + std::to_string(face[c]) + " and " +
             std::to_string(face[(c + 1) % k]));
      if (normal.dot((b - a).cross(d - a)) / ab < -tolerance_)
        fail(name + " is not a convex polygon (reflex at node " + std::to_string(face[(c + 1) % k]) + ")");
    }
    face_normals_[f] = normal;
    face_offsets_[f] = offset;
  }
  for (int i = 0; i < n; ++i)
    if (node_use[i] == 0) fail("node " + std::to_string(i) + " is on no face");

  // Closed and consistently oriented: each directed edge once, its reverse once.
  std::map<std::pair<int, int>, int> edge_face;
  for (size_t f = 0; f < faces_.size(); ++f) {
    const Face& face = faces_[f];
    for (size_t k = 0; k < face.size(); ++k) {
      const std::pair<int, int> e(face[k], face[(k + 1) % face.size()]);
      auto inserted = edge_face.emplace(e, static_cast<int>(f));
      if (!inserted.second)
        fail("edge (" + std::to_string(e.first) + ", " + std::to_string(e.second) +
             ") is used in the same "
             "direction by faces " +
             std::to_string(inserted.first->second) + " and " + std::to_string(f) +
             " (inconsistent orientation or more than two faces at an edge)");
    }
  }
  for (const auto& entry : edge_face)
    if (edge_face.count({entry.first.second, entry.first.first}) == 0)
      fail("edge (" + std::to_string(entry.first.first) + ", " + std::to_string(entry.first.second) +
           ") of face " + std::to_string(entry.second) + " has no opposite edge: the surface is not closed");

  // Triangulation.
  triangles_.clear();
  triangle_face_.clear();
  for (size_t f = 0; f < faces_.size(); ++f) {
    const std::vector<Triangle> tris =
        given_triangulation ? face_triangles[f] : bestFan(nodes_, faces_[f], face_normals_[f]);
    const std::string name = "triangulation of face " + std::to_string(f);
    const Vec3 face_area_normal = newellNormal(nodes_, faces_[f]);
    double area_sum = 0.0;
    for (const Triangle& t : tris) {
      for (int v : t)
        if (std::find(faces_[f].begin(), faces_[f].end(), v) == faces_[f].end())
          fail(name + " uses node " + std::to_string(v) + " which is not on the face");
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) fail(name + " has a triangle with a repeated node");
      const double signed_area =
          0.5 * face_normals_[f].dot((nodes_[t[1]] - nodes_[t[0]]).cross(nodes_[t[2]] - nodes_[t[0]]));
      if (signed_area < -tolerance_ * scale_) fail(name + " has an inward-oriented triangle");
      area_sum += signed_area;
      triangles_.push_back(t);
      triangle_face_.push_back(static_cast<int>(f));
    }
    if (std::abs(area_sum - 0.5 * face_area_normal.norm()) >
        tolerance_ * scale_ * static_cast<double>(tris.size()))
      fail(name + " does not tile the face (triangle area " + std::to_string(area_sum) + ", face area " +
           std::to_string(0.5 * face_area_normal.norm()) + ")");
  }
  // Per face, the boundary chain of the triangles must be the polygon's boundary (interior edges cancel). Not
  // checked across faces: zero-area triangles may put a diagonal onto another face's collinear edge nodes.
  for (size_t f = 0; f < faces_.size(); ++f) {
    std::map<std::pair<int, int>, int> chain;
    auto add = [&chain](int a, int b, int sign) {
      if (a > b) {
        std::swap(a, b);
        sign = -sign;
      }
      chain[{a, b}] += sign;
    };
    const Face& face = faces_[f];
    for (size_t k = 0; k < face.size(); ++k) add(face[k], face[(k + 1) % face.size()], -1);
    for (size_t t = 0; t < triangles_.size(); ++t)
      if (triangle_face_[t] == static_cast<int>(f))
        for (int k = 0; k < 3; ++k) add(triangles_[t][k], triangles_[t][(k + 1) % 3], 1);
    for (const auto& entry : chain)
      if (entry.second != 0)
        fail("triangulation of face " + std::to_string(f) + " does not tile the face (edge (" +
             std::to_string(entry.first.first) + ", " + std::to_string(entry.first.second) + "))");
  }

  // Volume and centroid by the divergence theorem, relative to the first node.
  const Vec3 origin = nodes_[0];
  double volume = 0.0;
  Vec3 moment = Vec3::Zero();
  for (const Triangle& t : triangles_) {
    const Vec3 a = nodes_[t[0]] - origin, b = nodes_[t[1]] - origin, c = nodes_[t[2]] - origin;
    const double v = a.dot(b.cross(c)) / 6.0;
    volume += v;
    moment += v * (a + b + c) / 4.0;
  }
  if (!(volume > relative_tolerance_ * scale_ * scale_ * scale_))
    fail("volume " + std::to_string(volume) +
         " is not positive: the element is inverted (faces oriented inward) "
         "or degenerate");
  volume_ = volume;
  centroid_ = origin + moment / volume;

  // Convexity: every node on the inner side of every face plane.
  for (size_t f = 0; f < faces_.size(); ++f)
    for (int i = 0; i < n; ++i) {
      const double distance = face_normals_[f].dot(nodes_[i]) - face_offsets_[f];
      if (distance > tolerance_)
        fail("not convex: node " + std::to_string(i) + " " + formatVec(nodes_[i]) + " is " +
             std::to_string(distance) + " outside the plane of face " + std::to_string(f));
    }
}

ConvexPolyhedron ConvexPolyhedron::relabelled(std::vector<int> global_node_ids,
                                              double relative_tolerance) const {
  if (static_cast<int>(global_node_ids.size()) != numNodes())
    fail("relabelled: " + std::to_string(global_node_ids.size()) + " global node ids for " +
         std::to_string(numNodes()) + " nodes");
  if (!(relative_tolerance >= 0.0 && relative_tolerance < 1e-2))
    fail("relabelled: relative tolerance must be in [0, 1e-2), got " + std::to_string(relative_tolerance));
  ConvexPolyhedron copy(*this);
  copy.global_node_ids_ = std::move(global_node_ids);
  copy.relative_tolerance_ = relative_tolerance;
  copy.tolerance_ = relative_tolerance * scale_;
  return copy;
}

Vec3 ConvexPolyhedron::faceCentroid(int f) const {
  const Face& face = faces_[f];
  const Vec3& origin = nodes_[face[0]];
  Vec3 moment = Vec3::Zero();
  double area = 0.0;
  for (size_t k = 1; k + 1 < face.size(); ++k) {
    const Vec3& b = nodes_[face[k]];
    const Vec3& c = nodes_[face[k + 1]];
    const double a = 0.5 * face_normals_[f].dot((b - origin).cross(c - origin));
    area += a;
    moment += a * (origin + b + c) / 3.0;
  }
  return moment / area;
}

double ConvexPolyhedron::maxFacePlaneDistance(const Vec3& x) const {
  double d = -INFINITY;
  for (size_t f = 0; f < faces_.size(); ++f) d = std::max(d, face_normals_[f].dot(x) - face_offsets_[f]);
  return d;
}

ConvexPolyhedron ConvexPolyhedron::tetrahedron(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return ConvexPolyhedron({a, b, c, d}, {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}});
}

ConvexPolyhedron ConvexPolyhedron::hexahedron(const std::array<Vec3, 8>& corners, double relative_tolerance) {
  return ConvexPolyhedron(
      std::vector<Vec3>(corners.begin(), corners.end()),
      {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}},
      relative_tolerance);
}

ConvexPolyhedron ConvexPolyhedron::convexHull(const std::vector<Vec3>& points, double relative_tolerance) {
  const int n = static_cast<int>(points.size());
  if (n < 4) fail("convexHull: needs at least 4 points, got " + std::to_string(n));
  if (n > 64) fail("convexHull: brute-force hull is limited to 64 points, got " + std::to_string(n));
  for (int i = 0; i < n; ++i)
    if (!points[i].allFinite()) fail("convexHull: point " + std::to_string(i) + " is not finite");
  const double scale = boundingBoxDiagonal(points);
  const double tol = relative_tolerance * scale;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < i; ++j)
      if ((points[i] - points[j]).norm() <= tol)
        fail("convexHull: points " + std::to_string(j) + " and " + std::to_string(i) + " coincide");

  // Supporting planes through point triples with all points on one side.
  std::vector<Vec3> plane_normals;
  std::vector<double> plane_offsets;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int k = j + 1; k < n; ++k) {
        Vec3 normal = (points[j] - points[i]).cross(points[k] - points[i]);
        const double norm = normal.norm();
        if (norm <= tol * scale) continue;  // (nearly) collinear
        normal /= norm;
        double offset = normal.dot(points[i]);
        double lo = INFINITY, hi = -INFINITY;
        for (const Vec3& p : points) {
          const double s = normal.dot(p) - offset;
          lo = std::min(lo, s);
          hi = std::max(hi, s);
        }
        if (hi <= tol) {
        } else if (lo >= -tol) {
          normal = -normal;
          offset = -offset;
        } else {
          continue;
        }
        bool known = false;
        for (size_t q = 0; q < plane_normals.size() && !known; ++q)
          known = plane_normals[q].dot(normal) > 0.0 &&
                  std::abs(plane_normals[q].dot(points[i]) - plane_offsets[q]) <= tol &&
                  std::abs(plane_normals[q].dot(points[j]) - plane_offsets[q]) <= tol &&
                  std::abs(plane_normals[q].dot(points[k]) - plane_offsets[q]) <= tol;
        if (!known) {
          plane_normals.push_back(normal);
          plane_offsets.push_back(offset);
        }
      }
  if (plane_normals.size() < 4) fail("convexHull: the points are coplanar");

  // Each plane: boundary polygon of the points on it (corners counter-clockwise around the outward normal,
  // plus points on the polygon edges).
  std::vector<std::vector<int>> point_faces;
  for (size_t q = 0; q < plane_normals.size(); ++q) {
    const Vec3& normal = plane_normals[q];
    std::vector<int> on_plane;
    for (int i = 0; i < n; ++i)
      if (std::abs(normal.dot(points[i]) - plane_offsets[q]) <= tol) on_plane.push_back(i);
    const Vec3 e1 = normal.unitOrthogonal();
    const Vec3 e2 = normal.cross(e1);
    auto uv = [&](int i) { return Eigen::Vector2d(e1.dot(points[i]), e2.dot(points[i])); };
    std::sort(on_plane.begin(), on_plane.end(), [&](int a, int b) {
      const Eigen::Vector2d pa = uv(a), pb = uv(b);
      return pa.x() < pb.x() || (pa.x() == pb.x() && pa.y() < pb.y());
    });
    auto cross2 = [&](int o, int a, int b) {
      const Eigen::Vector2d po = uv(o), pa = uv(a), pb = uv(b);
      const Eigen::Vector2d oa = pa - po, ob = pb - po;
      return (oa.x() * ob.y() - oa.y() * ob.x()) / std::max(oa.norm(), ob.norm());
    };
    std::vector<int> hull(2 * on_plane.size());
    int m = 0;
    for (size_t t = 0; t < on_plane.size(); ++t) {  // Andrew's monotone chain, strict corners only
      while (m >= 2 && cross2(hull[m - 2], hull[m - 1], on_plane[t]) <= tol) --m;
      hull[m++] = on_plane[t];
    }
    for (int t = static_cast<int>(on_plane.size()) - 2, lower = m + 1; t >= 0; --t) {
      while (m >= lower && cross2(hull[m - 2], hull[m - 1], on_plane[t]) <= tol) --m;
      hull[m++] = on_plane[t];
    }
    hull.resize(m - 1);
    std::vector<int> polygon;
    for (size_t c = 0; c < hull.size(); ++c) {
      const int a = hull[c], b = hull[(c + 1) % hull.size()];
      polygon.push_back(a);
      const Vec3 ab = points[b] - points[a];
      std::vector<std::pair<double, int>> on_edge;
      for (int p : on_plane) {
        if (p == a || p == b) continue;
        const double t = (points[p] - points[a]).dot(ab) / ab.squaredNorm();
        if (t > 0.0 && t < 1.0 && (points[a] + t * ab - points[p]).norm() <= tol) on_edge.emplace_back(t, p);
      }
      std::sort(on_edge.begin(), on_edge.end());
      for (const auto& entry : on_edge) polygon.push_back(entry.second);
    }
    point_faces.push_back(polygon);
  }

  // Keep the points used by faces, renumbered in input order.
  std::vector<int> local(n, -1);
  for (const auto& face : point_faces)
    for (int p : face) local[p] = 0;
  std::vector<Vec3> nodes;
  std::vector<int> ids;
  for (int i = 0; i < n; ++i)
    if (local[i] == 0) {
      local[i] = static_cast<int>(nodes.size());
      nodes.push_back(points[i]);
      ids.push_back(i);
    }
  std::vector<Face> faces;
  for (const auto& face : point_faces) {
    Face f;
    for (int p : face) f.push_back(local[p]);
    faces.push_back(f);
  }
  return ConvexPolyhedron(std::move(nodes), std::move(faces), relative_tolerance, std::move(ids));
}

}  // namespace rc
