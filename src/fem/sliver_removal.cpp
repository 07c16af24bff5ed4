#include "fem/sliver_removal.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

namespace rc {
namespace {

using Face = PolyhedralMesh::Face;
using ElementFaces = PolyhedralMesh::ElementFaces;
using Vec2 = Eigen::Vector2d;

void checkOptions(const SliverRemovalOptions& options, const char* caller) {
  auto bad = [caller](const std::string& what) {
    throw std::invalid_argument(std::string(caller) + ": " + what);
  };
  if (!(options.sliver_relative_thickness > 0.0 && options.sliver_relative_thickness < 1.0))
    bad("sliver_relative_thickness must be in (0, 1), got " +
        std::to_string(options.sliver_relative_thickness));
  if (!(options.needle_relative_edge >= 0.0 && options.needle_relative_edge < 1.0))
    bad("needle_relative_edge must be in [0, 1), got " + std::to_string(options.needle_relative_edge));
  if (!(options.merge_relative_distance >= 0.0 && options.merge_relative_distance < 0.5))
    bad("merge_relative_distance must be in [0, 0.5), got " +
        std::to_string(options.merge_relative_distance));
  if (!(options.max_relative_tolerance > 0.0 && options.max_relative_tolerance < 1e-2))
    bad("max_relative_tolerance must be in (0, 1e-2), got " + std::to_string(options.max_relative_tolerance));
}

double cross2(const Vec2& a, const Vec2& b) {
  return a.x() * b.y() - a.y() * b.x();
}

Vec3 newellNormal(const std::vector<Vec3>& nodes, const Face& face) {
  Vec3 n = Vec3::Zero();
  for (size_t k = 1; k + 1 < face.size(); ++k)
    n += (nodes[face[k]] - nodes[face[0]]).cross(nodes[face[k + 1]] - nodes[face[0]]);
  return n;
}

double surfaceVolume(const std::vector<Vec3>& nodes, const ElementFaces& faces) {
  double volume = 0.0;
  const Vec3& o = nodes[faces.front().front()];
  for (const Face& f : faces)
    for (size_t k = 1; k + 1 < f.size(); ++k)
      volume += (nodes[f[0]] - o).dot((nodes[f[k]] - o).cross(nodes[f[k + 1]] - o)) / 6.0;
  return volume;
}

std::vector<int> sortedKey(const Face& face) {
  std::vector<int> key = face;
  std::sort(key.begin(), key.end());
  return key;
}

std::pair<int, int> edgeKey(int a, int b) {
  return {std::min(a, b), std::max(a, b)};
}

// Mesh under modification: raw arrays; parent element and node origin tracked across removals.
struct MeshState {
  std::vector<Vec3> nodes;
  std::vector<Vec3> displacements;
  std::vector<ElementFaces> elements;
  std::vector<int> parent;    // per element
  std::vector<int> node_map;  // per input node: current node
};

struct RemovalCounts {
  int new_nodes = 0, merged_nodes = 0, collapsed = 0;
  double max_projection = 0.0;
};

std::vector<int> elementNodes(const ElementFaces& faces) {
  std::vector<int> ids;
  for (const Face& f : faces)
    for (int v : f)
      if (std::find(ids.begin(), ids.end(), v) == ids.end()) ids.push_back(v);
  return ids;
}

struct Plane {
  Vec3 center, normal;
};

// Least-squares plane through points (smallest principal axis).
Plane fitPlane(const std::vector<Vec3>& points) {
  Vec3 center = Vec3::Zero();
  for (const Vec3& p : points) center += p;
  center /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) covariance += (p - center) * (p - center).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  return {center, eigen.eigenvectors().col(0).normalized()};
}

// Sliver plane of the flat group (9.2: least-squares plane). If at least three of its nodes lie on the mesh
// boundary and those are coplanar, their plane is used instead, so the boundary does not move.
Plane sliverPlane(const std::vector<Vec3>& nodes, const std::vector<int>& ids,
                  const std::vector<char>& is_boundary_node, double eps) {
  std::vector<Vec3> all, boundary;
  for (int v : ids) {
    all.push_back(nodes[v]);
    if (v < static_cast<int>(is_boundary_node.size()) && is_boundary_node[v]) boundary.push_back(nodes[v]);
  }
  if (boundary.size() >= 3) {
    const Plane plane = fitPlane(boundary);
    double off = 0.0, extent = 0.0;
    for (const Vec3& p : boundary) {
      off = std::max(off, std::abs(plane.normal.dot(p - plane.center)));
      extent = std::max(extent, (p - plane.center).cross(plane.normal).norm());
    }
    double area = 0.0;  // non-collinear: some triangle of boundary nodes has area
    for (size_t i = 1; i + 1 < boundary.size(); ++i)
      for (size_t j = i + 1; j < boundary.size(); ++j)
        area = std::max(area, (boundary[i] - boundary[0]).cross(boundary[j] - boundary[0]).norm());
    if (off <= eps && area > eps * extent) return plane;
  }
  if (boundary.empty() || boundary.size() > 2) return fitPlane(all);
  // One or two boundary nodes: the least-squares plane through them.
  Plane plane{boundary.size() == 1 ? boundary[0] : 0.5 * (boundary[0] + boundary[1]), Vec3::Zero()};
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : all) covariance += (p - plane.center) * (p - plane.center).transpose();
  if (boundary.size() == 1) {
    plane.normal =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvectors().col(0).normalized();
    return plane;
  }
  const Vec3 d = (boundary[1] - boundary[0]).normalized(), u1 = d.unitOrthogonal(), u2 = d.cross(u1);
  Eigen::Matrix<double, 3, 2> basis;
  basis << u1, u2;
  const Eigen::Matrix2d reduced = basis.transpose() * covariance * basis;
  plane.normal =
      (basis * Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(reduced).eigenvectors().col(0)).normalized();
  return plane;
}

// Removes element s as in 9.2, together with the neighbours that lie in its sliver plane within thin_distance
// (relative to the sliver's diameter; they would be flattened further). Throws std::runtime_error where the
// construction fails. Returns the number of elements removed (not counting collapsed ones).
int removeElement(MeshState& state, int s, double merge_relative_distance, double thin_relative,
                  const std::vector<char>& is_boundary_node, RemovalCounts& counts) {
  std::vector<Vec3>& nodes = state.nodes;
  const bool has_disp = !state.displacements.empty();
  std::vector<int> ids = elementNodes(state.elements[s]);
  double diameter = 0.0;
  for (int a : ids)
    for (int b : ids) diameter = std::max(diameter, (nodes[a] - nodes[b]).norm());
  const double eps = 1e-9 * diameter, area_eps = eps * diameter;

  // Flat group: the sliver and face neighbours with all nodes near its plane.
  std::map<std::vector<int>, std::vector<int>> face_elements;
  for (size_t e = 0; e < state.elements.size(); ++e)
    for (const Face& face : state.elements[e]) face_elements[sortedKey(face)].push_back(int(e));
  std::vector<char> in_group(state.elements.size(), 0);
  in_group[s] = 1;
  std::vector<int> group = {s};
  Plane plane = sliverPlane(nodes, ids, is_boundary_node, eps);
  for (bool grown = true; grown;) {
    grown = false;
    for (size_t g = 0; g < group.size() && !grown; ++g)
      for (const Face& face : state.elements[group[g]]) {
        for (int e : face_elements[sortedKey(face)]) {
          if (in_group[e]) continue;
          bool flat = true;
          for (int v : elementNodes(state.elements[e]))
            flat = flat && std::abs(plane.normal.dot(nodes[v] - plane.center)) <= thin_relative * diameter;
          if (!flat) continue;
          in_group[e] = 1;
          group.push_back(e);
          for (int v : elementNodes(state.elements[e]))
            if (std::find(ids.begin(), ids.end(), v) == ids.end()) ids.push_back(v);
          plane = sliverPlane(nodes, ids, is_boundary_node, eps);
          grown = true;
          break;
        }
        if (grown) break;
      }
  }
  const Vec3 center = plane.center, normal = plane.normal;
  const Vec3 e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
  auto plane2d = [&](int v) { return Vec2(e1.dot(nodes[v] - center), e2.dot(nodes[v] - center)); };

  // Project, then merge nodes closer than the merge distance (union-find over the element's nodes).
  std::vector<char> moved(nodes.size(), 0);
  for (int v : ids) {
    const double d = normal.dot(nodes[v] - center);
    counts.max_projection = std::max(counts.max_projection, std::abs(d));
    nodes[v] -= d * normal;
    moved[v] = 1;
  }
  std::vector<int> merged(nodes.size());
  std::iota(merged.begin(), merged.end(), 0);
  std::function<int(int)> root = [&](int v) { return merged[v] == v ? v : merged[v] = root(merged[v]); };
  const double merge_distance = merge_relative_distance * diameter;
  for (size_t i = 0; i < ids.size(); ++i)
    for (size_t j = i + 1; j < ids.size(); ++j)
      if ((nodes[ids[i]] - nodes[ids[j]]).norm() < merge_distance) {
        const int a = root(ids[i]), b = root(ids[j]);
        if (a != b) merged[std::max(a, b)] = std::min(a, b);
      }
  std::map<int, std::vector<int>> clusters;
  for (int v : ids) clusters[root(v)].push_back(v);
  for (const auto& cluster : clusters) {
    if (cluster.second.size() < 2) continue;
    Vec3 position = Vec3::Zero(), displacement = Vec3::Zero();
    for (int v : cluster.second) {
      position += nodes[v];
      if (has_disp) displacement += state.displacements[v];
    }
    const double k = static_cast<double>(cluster.second.size());
    nodes[cluster.first] = position / k;
    if (has_disp) state.displacements[cluster.first] = displacement / k;
    counts.merged_nodes += static_cast<int>(cluster.second.size()) - 1;
  }

  // Apply the merge everywhere: drop repeated nodes, faces without area and elements without volume.
  std::vector<char> deleted(state.elements.size(), 0);
  for (size_t e = 0; e < state.elements.size(); ++e) {
    ElementFaces next;
    bool touched = false;
    for (const Face& face : state.elements[e]) {
      Face f;
      for (int v : face) {
        touched = touched || moved[v];
        const int r = root(v);
        if (f.empty() || f.back() != r) f.push_back(r);
      }
      while (f.size() > 1 && f.front() == f.back()) f.pop_back();
      if (f.size() < 3) continue;
      if (touched && newellNormal(nodes, f).norm() <= 2.0 * area_eps) continue;
      next.push_back(std::move(f));
    }
    state.elements[e] = std::move(next);
    if (in_group[e] || !touched) continue;
    if (state.elements[e].size() < 4) {
      deleted[e] = 1;
      continue;
    }
    std::vector<Vec3> element_points;
    for (int v : elementNodes(state.elements[e])) element_points.push_back(nodes[v]);
    double scale = 0.0;
    for (const Vec3& p : element_points) scale = std::max(scale, (p - element_points[0]).norm());
    if (std::abs(surfaceVolume(nodes, state.elements[e])) <= 1e-9 * scale * scale * scale) deleted[e] = 1;
  }
  for (char d : deleted) counts.collapsed += d;

  // Upper (counter-clockwise around the normal) and lower faces of the flattened element; each set tiles the
  // projected polygon.
  // The flat group's surface: faces not shared by two group elements.
  ElementFaces sliver;
  {
    std::map<std::vector<int>, int> uses;
    for (int g : group)
      for (const Face& face : state.elements[g]) ++uses[sortedKey(face)];
    for (int g : group)
      for (const Face& face : state.elements[g])
        if (uses[sortedKey(face)] == 1) sliver.push_back(face);
  }
  std::vector<std::vector<Vec2>> polygon(sliver.size());
  std::vector<int> orientation(sliver.size(), 0);
  for (size_t f = 0; f < sliver.size(); ++f) {
    double area = 0.0;
    for (size_t k = 0; k < sliver[f].size(); ++k) {
      polygon[f].push_back(plane2d(sliver[f][k]));
      if (k > 0) area += cross2(polygon[f][k - 1], polygon[f][k]);
    }
    area += cross2(polygon[f].back(), polygon[f].front());
    orientation[f] = area > 0.0 ? 1 : -1;
    if (orientation[f] < 0) std::reverse(polygon[f].begin(), polygon[f].end());  // 2D counter-clockwise
  }
  // Neighbours across the sliver faces (before their faces change).
  std::map<std::vector<int>, std::vector<std::pair<int, int>>> face_users;
  for (size_t e = 0; e < state.elements.size(); ++e)
    if (!deleted[e] && !in_group[e])
      for (size_t f = 0; f < state.elements[e].size(); ++f)
        face_users[sortedKey(state.elements[e][f])].emplace_back(int(e), int(f));
  // The neighbour's copy runs opposite to the sliver's (merged needles may leave two faces on one node set).
  std::vector<std::pair<int, int>> neighbour(sliver.size(), {-1, -1});
  for (size_t f = 0; f < sliver.size(); ++f) {
    auto it = face_users.find(sortedKey(sliver[f]));
    if (it == face_users.end()) continue;
    Face reversed(sliver[f].rbegin(), sliver[f].rend());
    for (const auto& user : it->second) {
      const Face& other = state.elements[user.first][user.second];
      const auto start = std::find(other.begin(), other.end(), reversed[0]);
      Face rotated(start, other.end());
      rotated.insert(rotated.end(), other.begin(), start);
      if (rotated == reversed) neighbour[f] = user;
    }
  }

  // Sliver points: its (merged) nodes and the intersections of upper with lower edges (new nodes).
  std::vector<int> points = elementNodes(sliver);
  std::map<int, Vec2> point2d;
  for (int v : points) point2d[v] = plane2d(v);
  std::set<std::pair<int, int>> upper_edges, lower_edges;
  for (size_t f = 0; f < sliver.size(); ++f)
    for (size_t k = 0; k < sliver[f].size(); ++k)
      (orientation[f] > 0 ? upper_edges : lower_edges)
          .insert(edgeKey(sliver[f][k], sliver[f][(k + 1) % sliver[f].size()]));
  std::map<std::pair<int, int>, std::vector<std::pair<double, int>>> on_edge;  // along (min, max)
  for (const auto& up : upper_edges)
    for (const auto& low : lower_edges) {
      if (up.first == low.first || up.first == low.second || up.second == low.first ||
          up.second == low.second)
        continue;
      const Vec2 p = point2d[up.first], r = point2d[up.second] - p;
      const Vec2 q = point2d[low.first], d = point2d[low.second] - q;
      const double denominator = cross2(r, d);
      if (std::abs(denominator) <= area_eps) continue;  // parallel
      const double t = cross2(q - p, d) / denominator, u = cross2(q - p, r) / denominator;
      const double tol_t = eps / r.norm(), tol_u = eps / d.norm();
      if (t <= tol_t || t >= 1.0 - tol_t || u <= tol_u || u >= 1.0 - tol_u) continue;
      const int id = static_cast<int>(nodes.size());
      nodes.push_back((1.0 - t) * nodes[up.first] + t * nodes[up.second]);
      moved.push_back(1);
      if (has_disp)
        state.displacements.push_back(
            0.5 * ((1.0 - t) * state.displacements[up.first] + t * state.displacements[up.second] +
                   (1.0 - u) * state.displacements[low.first] + u * state.displacements[low.second]));
      point2d[id] = p + t * r;
      points.push_back(id);
      on_edge[up].emplace_back(t, id);
      on_edge[low].emplace_back(u, id);
      ++counts.new_nodes;
    }
  // Nodes lying inside an edge of the other tiling (T-junctions in the plane).
  for (const auto* edges : {&upper_edges, &lower_edges})
    for (const auto& edge : *edges)
      for (int v : elementNodes(sliver)) {
        if (v == edge.first || v == edge.second) continue;
        const Vec2 p = point2d[edge.first], r = point2d[edge.second] - p;
        const double t = (point2d[v] - p).dot(r) / r.squaredNorm();
        if (t <= 0.0 || t >= 1.0 || std::abs(cross2(r, point2d[v] - p)) / r.norm() > eps) continue;
        auto& list = on_edge[edge];
        if (std::find_if(list.begin(), list.end(), [v](const auto& x) { return x.second == v; }) ==
            list.end())
          list.emplace_back(t, v);
      }

  // Re-tessellation: cells = upper face ∩ lower face (convex), counter-clockwise around the normal.
  auto inside = [&](const std::vector<Vec2>& poly, const Vec2& x) {
    for (size_t k = 0; k < poly.size(); ++k) {
      const Vec2 edge = poly[(k + 1) % poly.size()] - poly[k];
      if (cross2(edge, x - poly[k]) / edge.norm() < -eps) return false;
    }
    return true;
  };
  auto polygonArea = [](const std::vector<Vec2>& poly) {
    double area = 0.0;
    for (size_t k = 0; k < poly.size(); ++k) area += cross2(poly[k], poly[(k + 1) % poly.size()]);
    return 0.5 * area;
  };
  std::vector<std::vector<Face>> cells_of(sliver.size());  // per sliver face: its cells (2D ccw)
  for (size_t fu = 0; fu < sliver.size(); ++fu) {
    if (orientation[fu] < 0) continue;
    double covered = 0.0;
    for (size_t fl = 0; fl < sliver.size(); ++fl) {
      if (orientation[fl] > 0) continue;
      Face cell;
      Vec2 mean = Vec2::Zero();
      for (int v : points)
        if (inside(polygon[fu], point2d[v]) && inside(polygon[fl], point2d[v])) {
          cell.push_back(v);
          mean += point2d[v];
        }
      if (cell.size() < 3) continue;
      mean /= static_cast<double>(cell.size());
      std::sort(cell.begin(), cell.end(), [&](int a, int b) {
        const Vec2 da = point2d[a] - mean, db = point2d[b] - mean;
        return std::atan2(da.y(), da.x()) < std::atan2(db.y(), db.x());
      });
      std::vector<Vec2> cell2d;
      for (int v : cell) cell2d.push_back(point2d[v]);
      const double area = polygonArea(cell2d);
      if (area <= area_eps) continue;
      covered += area;
      cells_of[fu].push_back(cell);
      cells_of[fl].push_back(cell);
    }
    if (std::abs(covered - polygonArea(polygon[fu])) > 1e-9 * diameter * diameter)
      throw std::runtime_error("sliver re-tessellation does not cover upper face " + std::to_string(fu));
  }

  // New and T-junction nodes enter every face along the split edges.
  for (auto& entry : on_edge) std::sort(entry.second.begin(), entry.second.end());
  for (size_t e = 0; e < state.elements.size(); ++e) {
    if (deleted[e] || in_group[e]) continue;
    for (Face& face : state.elements[e]) {
      Face next;
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        next.push_back(a);
        auto it = on_edge.find(edgeKey(a, b));
        if (it == on_edge.end()) continue;
        if (a < b)
          for (const auto& x : it->second) next.push_back(x.second);
        else
          for (auto x = it->second.rbegin(); x != it->second.rend(); ++x) next.push_back(x->second);
      }
      face = std::move(next);
    }
  }
  // Each neighbour's face on the sliver is replaced by the cells it covers (outward for the neighbour).
  std::map<std::pair<int, int>, std::vector<Face>> replacement;
  for (size_t f = 0; f < sliver.size(); ++f) {
    if (neighbour[f].first < 0) continue;
    for (Face cell : cells_of[f]) {
      if (orientation[f] > 0) std::reverse(cell.begin(), cell.end());  // neighbour above: outward is -normal
      replacement[neighbour[f]].push_back(cell);
    }
  }
  for (const auto& entry : replacement) {
    ElementFaces& faces = state.elements[entry.first.first];
    faces[entry.first.second].clear();
    for (const Face& cell : entry.second) faces.push_back(cell);
  }
  for (int g : group) deleted[g] = 1;

  // Faces bent by the projection (non-planar, more than 3 nodes) are fan-triangulated, identically on both
  // sides.
  std::map<std::vector<int>, std::pair<Face, std::vector<Face>>> triangulated;  // key -> (first copy, fan)
  for (size_t e = 0; e < state.elements.size(); ++e) {
    if (deleted[e]) continue;
    ElementFaces next;
    for (Face& face : state.elements[e]) {
      if (face.empty()) continue;
      bool bent = false;
      if (face.size() > 3 && std::any_of(face.begin(), face.end(), [&](int v) { return moved[v] != 0; })) {
        const Vec3 n = newellNormal(nodes, face).normalized();
        for (int v : face) bent = bent || std::abs(n.dot(nodes[v] - nodes[face[0]])) > eps;
      }
      if (!bent) {
        next.push_back(std::move(face));
        continue;
      }
      const std::vector<int> key = sortedKey(face);
      auto it = triangulated.find(key);
      if (it == triangulated.end()) {
        // Apex with the largest smallest fan triangle.
        const Vec3 n = newellNormal(nodes, face);
        const int k = static_cast<int>(face.size());
        int best = 0;
        double best_area = -INFINITY;
        for (int apex = 0; apex < k; ++apex) {
          double smallest = INFINITY;
          for (int j = 1; j + 1 < k; ++j)
            smallest =
                std::min(smallest, n.dot((nodes[face[(apex + j) % k]] - nodes[face[apex]])
                                             .cross(nodes[face[(apex + j + 1) % k]] - nodes[face[apex]])));
          if (smallest > best_area) {
            best_area = smallest;
            best = apex;
          }
        }
        std::vector<Face> fan;
        for (int j = 1; j + 1 < k; ++j)
          fan.push_back({face[best], face[(best + j) % k], face[(best + j + 1) % k]});
        it = triangulated.emplace(key, std::make_pair(face, fan)).first;
        for (const Face& t : fan) next.push_back(t);
        continue;
      }
      const bool same = face == it->second.first;  // else the opposite copy
      for (Face t : it->second.second) {
        if (!same) std::reverse(t.begin(), t.end());
        next.push_back(t);
      }
    }
    state.elements[e] = std::move(next);
  }

  // Compact: drop deleted elements and unused nodes.
  MeshState out;
  std::vector<int> new_id(nodes.size(), -1);
  for (size_t e = 0; e < state.elements.size(); ++e) {
    if (deleted[e]) continue;
    for (Face& face : state.elements[e])
      for (int& v : face) {
        if (new_id[v] < 0) {
          new_id[v] = static_cast<int>(out.nodes.size());
          out.nodes.push_back(nodes[v]);
          if (has_disp) out.displacements.push_back(state.displacements[v]);
        }
        v = new_id[v];
      }
    out.elements.push_back(std::move(state.elements[e]));
    out.parent.push_back(state.parent[e]);
  }
  for (int& v : state.node_map)
    if (v >= 0) v = new_id[root(v)];
  out.node_map = std::move(state.node_map);
  state = std::move(out);
  return static_cast<int>(group.size());
}

// Relative tolerance that covers the face planarity and convexity deviations of all elements.
double requiredRelativeTolerance(const MeshState& state) {
  double required = 0.0;
  for (const ElementFaces& faces : state.elements) {
    const std::vector<int> ids = elementNodes(faces);
    Vec3 lo = state.nodes[ids[0]], hi = lo;
    for (int v : ids) {
      lo = lo.cwiseMin(state.nodes[v]);
      hi = hi.cwiseMax(state.nodes[v]);
    }
    const double scale = (hi - lo).norm();
    for (const Face& face : faces) {
      const Vec3 n = newellNormal(state.nodes, face).normalized();
      double offset = 0.0;
      for (int v : face) offset += n.dot(state.nodes[v]);
      offset /= static_cast<double>(face.size());
      for (int v : face) required = std::max(required, std::abs(n.dot(state.nodes[v]) - offset) / scale);
      for (int v : ids) required = std::max(required, (n.dot(state.nodes[v]) - offset) / scale);
    }
  }
  return required;
}

}  // namespace

ElementQuality elementQuality(const ConvexPolyhedron& element) {
  ElementQuality q;
  const auto& x = element.nodes();
  for (size_t a = 0; a < x.size(); ++a)
    for (size_t b = a + 1; b < x.size(); ++b) q.diameter = std::max(q.diameter, (x[a] - x[b]).norm());
  q.thickness = INFINITY;
  double min_edge = INFINITY;
  for (int f = 0; f < element.numFaces(); ++f) {
    double height = 0.0;
    for (const Vec3& p : x) height = std::max(height, element.faceOffset(f) - element.faceNormal(f).dot(p));
    q.thickness = std::min(q.thickness, height);
    const auto& face = element.faces()[f];
    for (size_t k = 0; k < face.size(); ++k)
      min_edge = std::min(min_edge, (x[face[k]] - x[face[(k + 1) % face.size()]]).norm());
  }
  q.relative_thickness = q.thickness / q.diameter;
  q.relative_min_edge = min_edge / q.diameter;
  q.volume_ratio = element.volume() / (q.diameter * q.diameter * q.diameter);
  return q;
}

std::vector<ElementDefect> classifyElements(const PolyhedralMesh& mesh, const SliverRemovalOptions& options) {
  checkOptions(options, "classifyElements");
  std::vector<ElementDefect> defects(mesh.numElements(), ElementDefect::kNone);
  for (int e = 0; e < mesh.numElements(); ++e) {
    const ElementQuality q = elementQuality(mesh.element(e));
    if (q.relative_thickness < options.sliver_relative_thickness)
      defects[e] = q.relative_min_edge < options.needle_relative_edge ? ElementDefect::kNeedle
                                                                      : ElementDefect::kSliver;
  }
  return defects;
}

SliverRemovalResult removeSlivers(const PolyhedralMesh& mesh, const std::vector<Vec3>& displacements,
                                  const SliverRemovalOptions& options) {
  checkOptions(options, "removeSlivers");
  if (!displacements.empty() && static_cast<int>(displacements.size()) != mesh.numNodes())
    throw std::invalid_argument("removeSlivers: displacements has " + std::to_string(displacements.size()) +
                                " entries, the mesh has " + std::to_string(mesh.numNodes()) + " nodes");
  double input_tolerance = ConvexPolyhedron::kDefaultRelativeTolerance;
  for (const ConvexPolyhedron& element : mesh.elements())
    input_tolerance = std::max(input_tolerance, element.tolerance() / element.scale());

  MeshState state;
  state.nodes = mesh.nodes();
  state.displacements = displacements;
  for (int e = 0; e < mesh.numElements(); ++e) {
    state.elements.push_back(mesh.elementFaces(e));
    state.parent.push_back(e);
  }
  state.node_map.resize(mesh.numNodes());
  std::iota(state.node_map.begin(), state.node_map.end(), 0);

  SliverRemovalResult result{mesh, displacements, state.node_map, state.parent};
  PolyhedralMesh current = mesh;
  double tolerance = input_tolerance;
  std::set<int> rejected;  // input element ids whose removal failed
  for (int removal = 0; options.max_removals < 0 || removal < options.max_removals; ++removal) {
    // Thinnest removable element.
    int worst = -1;
    double worst_thickness = options.sliver_relative_thickness;
    ElementDefect defect = ElementDefect::kNone;
    for (int e = 0; e < current.numElements(); ++e) {
      if (rejected.count(state.parent[e])) continue;
      const ElementQuality q = elementQuality(current.element(e));
      if (q.relative_thickness < worst_thickness) {
        worst_thickness = q.relative_thickness;
        worst = e;
        defect = q.relative_min_edge < options.needle_relative_edge ? ElementDefect::kNeedle
                                                                    : ElementDefect::kSliver;
      }
    }
    if (worst < 0) break;
    MeshState next = state;
    RemovalCounts counts;
    int removed = 0;
    try {
      removed = removeElement(next, worst, options.merge_relative_distance, options.sliver_relative_thickness,
                              current.isBoundaryNode(), counts);
      const double required = std::max(tolerance, 1.5 * requiredRelativeTolerance(next));
      if (required > options.max_relative_tolerance)
        throw std::runtime_error("neighbours too far from convex");
      PolyhedralMesh candidate(next.nodes, next.elements, required);
      current = std::move(candidate);
      tolerance = required;
      state = std::move(next);
    } catch (const std::exception&) {  // invalid neighbours or overlay: keep the element
      rejected.insert(state.parent[worst]);
      ++result.num_rejected;
      continue;
    }
    (defect == ElementDefect::kNeedle ? result.num_needles_removed : result.num_slivers_removed) += removed;
    result.num_new_nodes += counts.new_nodes;
    result.num_merged_nodes += counts.merged_nodes;
    result.num_collapsed_elements += counts.collapsed;
    result.max_projection_distance = std::max(result.max_projection_distance, counts.max_projection);
  }
  result.mesh = std::move(current);
  result.displacements = std::move(state.displacements);
  result.node_map = std::move(state.node_map);
  result.parent_element = std::move(state.parent);
  return result;
}

}  // namespace rc
