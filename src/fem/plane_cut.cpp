#include "fem/plane_cut.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

namespace rc {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("cutMeshByPlane: " + what);
}

double boundingDiagonal(const std::vector<Vec3>& points) {
  Vec3 lo = points.front(), hi = points.front();
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

// Indices of points (around a plane section, coplanar) sorted counter-clockwise around e1 x e2.
std::vector<int> angularOrderIndices(const std::vector<Vec3>& points, const Vec3& e1, const Vec3& e2) {
  Vec3 center = Vec3::Zero();
  for (const Vec3& p : points) center += p;
  center /= static_cast<double>(points.size());
  std::vector<std::pair<double, int>> by_angle;
  for (size_t k = 0; k < points.size(); ++k) {
    const Vec3 d = points[k] - center;
    by_angle.emplace_back(std::atan2(e2.dot(d), e1.dot(d)), static_cast<int>(k));
  }
  std::sort(by_angle.begin(), by_angle.end());
  std::vector<int> order;
  for (const auto& entry : by_angle) order.push_back(entry.second);
  return order;
}

std::vector<Vec3> angularOrder(const std::vector<Vec3>& points, const Vec3& e1, const Vec3& e2) {
  std::vector<Vec3> sorted;
  for (int k : angularOrderIndices(points, e1, e2)) sorted.push_back(points[k]);
  return sorted;
}

// All turns of the closed polygon have the same sign (either orientation); area above area_tolerance.
bool isConvexPolygon(const std::vector<Eigen::Vector2d>& polygon, double area_tolerance) {
  const size_t k = polygon.size();
  int sign = 0;
  double area = 0.0;
  for (size_t i = 0; i < k; ++i) {
    const Eigen::Vector2d a = polygon[(i + 1) % k] - polygon[i],
                          b = polygon[(i + 2) % k] - polygon[(i + 1) % k];
    const double turn = a.x() * b.y() - a.y() * b.x();
    area += polygon[i].x() * polygon[(i + 1) % k].y() - polygon[i].y() * polygon[(i + 1) % k].x();
    if (std::abs(turn) <= area_tolerance) continue;
    const int s = turn > 0.0 ? 1 : -1;
    if (sign != 0 && s != sign) return false;
    sign = s;
  }
  return std::abs(area) > area_tolerance;
}

// Interiors of two convex polygons overlap by more than tol (separating axis test over both edge sets).
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

}  // namespace

PlaneCutResult cutMeshByPlane(const PolyhedralMesh& mesh, const std::vector<Vec3>& displacements,
                              const Vec3& plane_point, const Vec3& plane_normal,
                              const PlaneCutOptions& options) {
  if (!plane_point.allFinite()) fail("plane_point is not finite");
  if (!plane_normal.allFinite() || !(plane_normal.norm() > 0.0))
    fail("plane_normal must be finite and non-zero");
  if (!displacements.empty() && static_cast<int>(displacements.size()) != mesh.numNodes())
    fail("displacements has " + std::to_string(displacements.size()) + " entries, the mesh has " +
         std::to_string(mesh.numNodes()) + " nodes");
  if (!(options.snap_relative_distance >= 0.0) || !std::isfinite(options.snap_relative_distance))
    fail("snap_relative_distance must be finite and >= 0");

  const Vec3 normal = plane_normal.normalized();
  std::vector<Vec3> nodes = mesh.nodes();
  std::vector<Vec3> disp = displacements;
  const bool has_disp = !disp.empty();
  const double snap = options.snap_relative_distance * boundingDiagonal(nodes);

  PlaneCutResult result{mesh, {}, {}, {}, {}, 0, 0, 0};
  std::vector<double> distance(nodes.size());
  std::vector<int>& side = result.node_side;
  side.resize(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    distance[i] = normal.dot(nodes[i] - plane_point);
    side[i] = std::abs(distance[i]) <= snap ? 0 : (distance[i] > 0.0 ? 1 : -1);
    if (side[i] == 0 && distance[i] != 0.0) ++result.num_snapped_nodes;
  }

  std::map<std::pair<int, int>, int> edge_node;
  auto cutNode = [&](int a, int b) {
    const auto key = std::make_pair(std::min(a, b), std::max(a, b));
    auto it = edge_node.find(key);
    if (it != edge_node.end()) return it->second;
    const double t = distance[key.first] / (distance[key.first] - distance[key.second]);
    nodes.push_back((1.0 - t) * nodes[key.first] + t * nodes[key.second]);
    if (has_disp) disp.push_back((1.0 - t) * disp[key.first] + t * disp[key.second]);
    distance.push_back(0.0);
    side.push_back(0);
    const int id = static_cast<int>(nodes.size()) - 1;
    edge_node.emplace(key, id);
    return id;
  };

  const Vec3 e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
  auto planeCoordinates = [&](const Vec3& x) { return Eigen::Vector2d(e1.dot(x), e2.dot(x)); };
  const double diagonal = boundingDiagonal(nodes);
  std::vector<Eigen::Vector2d> region;
  if (!options.region.empty()) {
    if (options.region.size() < 3) fail("region needs at least 3 points");
    for (size_t k = 0; k < options.region.size(); ++k) {
      if (!options.region[k].allFinite()) fail("region point " + std::to_string(k) + " is not finite");
      if (std::abs(normal.dot(options.region[k] - plane_point)) > 1e-9 * diagonal)
        fail("region point " + std::to_string(k) + " does not lie in the plane");
      region.push_back(planeCoordinates(options.region[k]));
    }
    if (!isConvexPolygon(region, 1e-12 * diagonal * diagonal)) fail("region is not a convex polygon");
  }

  // Crossed elements and the ones to split (crossed, and their cut polygon overlaps the region).
  const int num_elements = mesh.numElements();
  std::vector<char> crossed(num_elements, 0), selected(num_elements, 0);
  for (int e = 0; e < num_elements; ++e) {
    bool has_positive = false, has_negative = false;
    for (int v : mesh.element(e).globalNodeIds()) {
      has_positive = has_positive || side[v] > 0;
      has_negative = has_negative || side[v] < 0;
    }
    if (!has_positive && !has_negative)
      throw std::runtime_error("cutMeshByPlane: element " + std::to_string(e) +
                               " lies within the snap distance of the plane (lower snap_relative_distance)");
    crossed[e] = has_positive && has_negative;
    if (!crossed[e]) continue;
    if (region.empty()) {
      selected[e] = 1;
      continue;
    }
    std::vector<Vec3> points;  // element section: nodes on the plane and edge intersections
    for (const auto& face : mesh.elementFaces(e))
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        if (side[a] == 0) points.push_back(nodes[a]);
        if (side[a] * side[b] < 0) {
          const double t = distance[a] / (distance[a] - distance[b]);
          points.push_back((1.0 - t) * nodes[a] + t * nodes[b]);
        }
      }
    std::vector<Eigen::Vector2d> section;
    for (const Vec3& x : angularOrder(points, e1, e2)) section.push_back(planeCoordinates(x));
    selected[e] = convexPolygonsOverlap(section, region, 1e-9 * diagonal);
  }
  // Faces of split elements that get split (shared neighbours must split them identically: T-junctions).
  std::set<std::vector<int>> split_faces;

  std::vector<std::vector<PolyhedralMesh::ElementFaces>> parts(num_elements);
  double max_snapped_distance = 0.0, min_part_scale = INFINITY;
  for (int e = 0; e < num_elements; ++e) {
    if (!selected[e]) continue;
    const PolyhedralMesh::ElementFaces& faces = mesh.elementFaces(e);
    ++result.num_split_elements;
    PolyhedralMesh::ElementFaces positive, negative;
    std::vector<int> cut;  // nodes of the cut polygon
    auto addCut = [&cut](int v) {
      if (std::find(cut.begin(), cut.end(), v) == cut.end()) cut.push_back(v);
    };
    for (size_t f = 0; f < faces.size(); ++f) {
      const PolyhedralMesh::Face& face = faces[f];
      PolyhedralMesh::Face pos, neg;
      bool face_positive = false, face_negative = false;
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        if (side[a] >= 0) pos.push_back(a);
        if (side[a] <= 0) neg.push_back(a);
        face_positive = face_positive || side[a] > 0;
        face_negative = face_negative || side[a] < 0;
        if (side[a] == 0) {
          addCut(a);
          max_snapped_distance = std::max(max_snapped_distance, std::abs(distance[a]));
        }
        if (side[a] * side[b] < 0) {
          const int m = cutNode(a, b);
          pos.push_back(m);
          neg.push_back(m);
          addCut(m);
        }
      }
      if (!face_positive && !face_negative)
        throw std::runtime_error("cutMeshByPlane: face " + std::to_string(f) + " of element " +
                                 std::to_string(e) +
                                 " lies in the cut plane but the element is crossed (lower "
                                 "snap_relative_distance)");
      if (face_positive) positive.push_back(pos);
      if (face_negative) negative.push_back(neg);
      if (face_positive && face_negative) {
        std::vector<int> key = face;
        std::sort(key.begin(), key.end());
        split_faces.insert(key);
      }
    }
    // Cut polygon counter-clockwise around the normal: outward for the negative part.
    std::vector<Vec3> cut_points;
    for (int m : cut) cut_points.push_back(nodes[m]);
    PolyhedralMesh::Face polygon;
    for (int k : angularOrderIndices(cut_points, e1, e2)) polygon.push_back(cut[k]);
    negative.push_back(polygon);
    positive.push_back(PolyhedralMesh::Face(polygon.rbegin(), polygon.rend()));
    for (const auto* part : {&negative, &positive}) {
      std::vector<Vec3> points;
      for (const auto& face : *part)
        for (int v : face) points.push_back(nodes[v]);
      min_part_scale = std::min(min_part_scale, boundingDiagonal(points));
    }
    parts[e] = {std::move(negative), std::move(positive)};
  }
  // Crossed elements left whole: faces shared with a split element are split alike (two coplanar faces),
  // other faces get the new nodes on their edges (T-junctions, 9.3.1).
  for (int e = 0; e < num_elements; ++e) {
    if (!crossed[e] || selected[e]) continue;
    PolyhedralMesh::ElementFaces whole;
    for (const auto& face : mesh.elementFaces(e)) {
      std::vector<int> key = face;
      std::sort(key.begin(), key.end());
      const bool split = split_faces.count(key) > 0;
      PolyhedralMesh::Face pos, neg, all;
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        if (side[a] >= 0) pos.push_back(a);
        if (side[a] <= 0) neg.push_back(a);
        all.push_back(a);
        auto it = edge_node.find(std::make_pair(std::min(a, b), std::max(a, b)));
        if (side[a] * side[b] < 0 && it != edge_node.end()) {
          pos.push_back(it->second);
          neg.push_back(it->second);
          all.push_back(it->second);
        }
      }
      if (split) {
        whole.push_back(pos);
        whole.push_back(neg);
      } else {
        whole.push_back(all);
      }
    }
    parts[e] = {std::move(whole)};
  }

  std::vector<PolyhedralMesh::ElementFaces> elements;
  for (int e = 0; e < num_elements; ++e) {
    if (parts[e].empty()) {
      elements.push_back(mesh.elementFaces(e));
      result.parent_element.push_back(e);
      bool has_positive = false;
      for (int v : mesh.element(e).globalNodeIds()) has_positive = has_positive || side[v] > 0;
      result.element_side.push_back(has_positive ? 1 : -1);
      continue;
    }
    for (size_t k = 0; k < parts[e].size(); ++k) {
      elements.push_back(std::move(parts[e][k]));
      result.parent_element.push_back(e);
      result.element_side.push_back(parts[e].size() == 1 ? 0 : (k == 0 ? -1 : 1));
    }
  }
  result.num_new_nodes = static_cast<int>(edge_node.size());

  // Keep the input tolerance; widen it to cover cut faces bent through snapped nodes.
  double relative_tolerance = ConvexPolyhedron::kDefaultRelativeTolerance;
  for (const ConvexPolyhedron& element : mesh.elements())
    relative_tolerance = std::max(relative_tolerance, element.tolerance() / element.scale());
  if (max_snapped_distance > 0.0)
    relative_tolerance = std::max(relative_tolerance, 4.0 * max_snapped_distance / min_part_scale);
  result.mesh = PolyhedralMesh(std::move(nodes), std::move(elements), relative_tolerance);
  result.displacements = std::move(disp);
  return result;
}

SeparatedMesh separateAlongPlane(const PlaneCutResult& cut) {
  const PolyhedralMesh& mesh = cut.mesh;
  SeparatedMesh out;
  out.nodes = mesh.nodes();
  out.displacements = cut.displacements;
  const int n = mesh.numNodes();
  // used[v] bit 0: by a negative element, bit 1: by a positive element.
  std::vector<int> used(n, 0);
  int counts[2] = {0, 0};
  for (int e = 0; e < mesh.numElements(); ++e) {
    if (cut.element_side[e] == 0)
      throw std::invalid_argument("separateAlongPlane: element " + std::to_string(e) +
                                  " was left whole across the plane (region-restricted cut); partial cuts "
                                  "cannot be separated");
    const int s = cut.element_side[e] > 0 ? 1 : 0;
    ++counts[s];
    for (const auto& face : mesh.elementFaces(e))
      for (int v : face) used[v] |= 1 << s;
  }
  if (counts[0] == 0 || counts[1] == 0)
    throw std::invalid_argument("separateAlongPlane: the " +
                                std::string(counts[0] ? "positive" : "negative") +
                                " side of the plane has no elements (the plane does not cross the mesh)");
  std::vector<int> copy(n, -1);
  for (int v = 0; v < n; ++v)
    if (used[v] == 3) {
      if (cut.node_side[v] != 0)
        throw std::logic_error("separateAlongPlane: node " + std::to_string(v) +
                               " off the plane is shared across the cut");
      copy[v] = static_cast<int>(out.nodes.size());
      out.nodes.push_back(out.nodes[v]);
      if (!out.displacements.empty()) out.displacements.push_back(out.displacements[v]);
      out.duplicate_of.push_back(v);
    }
  double relative_tolerance = ConvexPolyhedron::kDefaultRelativeTolerance;
  for (const ConvexPolyhedron& element : mesh.elements())
    relative_tolerance = std::max(relative_tolerance, element.tolerance() / element.scale());

  out.side_node_ids.resize(2);
  out.side_element_ids.resize(2);
  std::vector<std::vector<PolyhedralMesh::ElementFaces>> side_elements(2);
  std::vector<int> local(out.nodes.size(), -1);
  for (int s = 0; s < 2; ++s) {
    std::fill(local.begin(), local.end(), -1);
    for (int e = 0; e < mesh.numElements(); ++e) {
      if ((cut.element_side[e] > 0 ? 1 : 0) != s) continue;
      PolyhedralMesh::ElementFaces faces = mesh.elementFaces(e);
      if (s == 1)
        for (auto& face : faces)
          for (int& v : face)
            if (copy[v] >= 0) v = copy[v];
      if (s == 0) out.elements.push_back(faces);
      PolyhedralMesh::ElementFaces side_faces = faces;
      for (auto& face : side_faces)
        for (int& v : face) {
          if (local[v] < 0) {
            local[v] = static_cast<int>(out.side_node_ids[s].size());
            out.side_node_ids[s].push_back(v);
          }
          v = local[v];
        }
      side_elements[s].push_back(std::move(side_faces));
      out.side_element_ids[s].push_back(e);
      if (s == 1) out.elements.push_back(std::move(faces));
    }
  }
  // Combined elements in the cut mesh's order.
  std::vector<PolyhedralMesh::ElementFaces> ordered(mesh.numElements());
  int next[2] = {0, 0};
  for (int e = 0; e < mesh.numElements(); ++e) {
    const int s = cut.element_side[e] > 0 ? 1 : 0;
    ordered[e] = std::move(out.elements[(s == 0 ? 0 : counts[0]) + next[s]++]);
  }
  out.elements = std::move(ordered);
  for (int s = 0; s < 2; ++s) {
    std::vector<Vec3> side_nodes;
    for (int v : out.side_node_ids[s]) side_nodes.push_back(out.nodes[v]);
    out.sides.emplace_back(std::move(side_nodes), std::move(side_elements[s]), relative_tolerance);
  }
  return out;
}

}  // namespace rc
