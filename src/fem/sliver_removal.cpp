#include "relaxed_connectivity/fem/sliver_removal.h"

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

// Mesh under modification: raw arrays; parent element and node origin tracked across removals. Deleted
// elements are left empty until compaction; adjacency lists the live elements using each node.
struct MeshState {
  std::vector<Vec3> nodes;
  std::vector<Vec3> displacements;
  std::vector<ElementFaces> elements;
  std::vector<std::vector<char>> crack;  // empty or per element face
  std::vector<int> parent;               // per element
  std::vector<int> node_map;             // per input node: current node
  std::vector<std::vector<int>> adjacency;
  std::vector<int> replacement;           // per node: the node it was merged into (itself if kept)
  std::vector<NodeStencil> new_stencils;  // per node appended after num_input_nodes
  int num_input_nodes = 0;
};

struct RemovalCounts {
  int new_nodes = 0, merged_nodes = 0, collapsed = 0;
  double max_projection = 0.0;
};

// Local mode (after cuts): the plane keeps the boundary, merged nodes keep an on-plane node's position,
// elements are not compacted and the adjacency is kept up to date.
struct RemovalSettings {
  double merge_relative_distance = 0.1, thin_relative = 0.05;
  bool local = false;
  int first_new_node = 0;  // local: nodes below existed before the cut
};

// Saved state of the elements a removal touches (local mode: undo of a rejected removal).
struct RemovalUndo {
  std::vector<int> elements;
  std::vector<ElementFaces> faces;
  std::vector<std::vector<char>> crack;
  std::vector<std::vector<int>> element_nodes;
  size_t num_nodes = 0;
  std::vector<std::pair<int, Vec3>> positions, displacements;
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

std::vector<std::vector<int>> buildAdjacency(const MeshState& state) {
  std::vector<std::vector<int>> adjacency(state.nodes.size());
  for (size_t e = 0; e < state.elements.size(); ++e)
    for (int v : elementNodes(state.elements[e])) adjacency[v].push_back(static_cast<int>(e));
  for (auto& list : adjacency) std::sort(list.begin(), list.end());
  return adjacency;
}

// (element, face) users of face's node set.
std::vector<std::pair<int, int>> faceUsers(const MeshState& state, const Face& face) {
  std::vector<std::pair<int, int>> users;
  const std::vector<int> key = sortedKey(face);
  for (int e : state.adjacency[face[0]])
    for (size_t f = 0; f < state.elements[e].size(); ++f)
      if (state.elements[e][f].size() == face.size() && sortedKey(state.elements[e][f]) == key)
        users.emplace_back(e, static_cast<int>(f));
  return users;
}

bool isCrack(const MeshState& state, int e, int f) {
  return !state.crack.empty() && state.crack[e][f] != 0;
}

// Local mode: the plane of the group's large faces on the boundary (mesh surface or crack) when only one
// side has neighbours, else the plane of the nodes that existed before the cut if they are coplanar, else
// least squares. Throws if neither large side has a neighbour (a free thin sheet: nothing to merge into).
Plane localSliverPlane(const MeshState& state, const std::vector<int>& group,
                       const std::vector<char>& in_group, const std::vector<int>& ids, int first_new_node,
                       double eps, double thin_distance) {
  std::vector<Vec3> all;
  for (int v : ids) all.push_back(state.nodes[v]);
  const Plane fit = fitPlane(all);
  std::vector<int> side_nodes[2];
  bool has_neighbour[2] = {false, false};
  for (int g : group)
    for (size_t f = 0; f < state.elements[g].size(); ++f) {
      const Face& face = state.elements[g][f];
      const std::vector<std::pair<int, int>> users = faceUsers(state, face);
      bool internal = false, neighbour = false;
      for (const auto& user : users)
        if (user.first != g) (in_group[user.first] ? internal : neighbour) = true;
      if (internal) continue;
      const double alignment = newellNormal(state.nodes, face).normalized().dot(fit.normal);
      if (std::abs(alignment) < 0.5) continue;  // rim face
      const int side = alignment > 0.0 ? 1 : 0;
      has_neighbour[side] = has_neighbour[side] || (neighbour && !isCrack(state, g, static_cast<int>(f)));
      for (int v : face)
        if (std::find(side_nodes[side].begin(), side_nodes[side].end(), v) == side_nodes[side].end())
          side_nodes[side].push_back(v);
    }
  if (!has_neighbour[0] && !has_neighbour[1])
    throw std::runtime_error("thin element without neighbours on its large faces (free sheet)");
  auto planeThrough = [&](const std::vector<int>& nodes, Plane* plane) {
    std::vector<Vec3> points;
    for (int v : nodes) points.push_back(state.nodes[v]);
    if (points.size() < 3) return false;
    *plane = fitPlane(points);
    double area = 0.0;
    for (size_t i = 1; i + 1 < points.size(); ++i)
      for (size_t j = i + 1; j < points.size(); ++j)
        area = std::max(area, (points[i] - points[0]).cross(points[j] - points[0]).norm());
    return area > eps * eps * 1e6;
  };
  Plane plane = fit;
  // The mesh boundary (surface or crack) along the group: its faces around the group's nodes that are
  // parallel to the group and near its plane. If they lie in one plane, that plane stays where it is.
  std::vector<int> surface;
  for (int v : ids)
    for (int e : state.adjacency[v])
      for (size_t f = 0; f < state.elements[e].size(); ++f) {
        const Face& face = state.elements[e][f];
        if (std::find(face.begin(), face.end(), v) == face.end()) continue;
        if (faceUsers(state, face).size() > 1 && !isCrack(state, e, static_cast<int>(f))) continue;
        if (std::abs(newellNormal(state.nodes, face).normalized().dot(fit.normal)) < 0.9) continue;
        bool near = true;
        for (int u : face)
          near = near && std::abs(fit.normal.dot(state.nodes[u] - fit.center)) <= thin_distance;
        if (!near) continue;
        for (int u : face)
          if (std::find(surface.begin(), surface.end(), u) == surface.end()) surface.push_back(u);
      }
  if (planeThrough(surface, &plane)) {
    double off = 0.0;
    for (int v : surface) off = std::max(off, std::abs(plane.normal.dot(state.nodes[v] - plane.center)));
    if (off <= eps) return plane;
  }
  if (has_neighbour[0] != has_neighbour[1] && planeThrough(side_nodes[has_neighbour[0] ? 1 : 0], &plane))
    return plane;
  std::vector<int> old_nodes;
  for (int v : ids)
    if (v < first_new_node) old_nodes.push_back(v);
  if (planeThrough(old_nodes, &plane)) {
    double off = 0.0;
    for (int v : old_nodes) off = std::max(off, std::abs(plane.normal.dot(state.nodes[v] - plane.center)));
    if (off <= eps) return plane;
  }
  return fit;
}

// Least-squares plane through the nodes ids.
Plane fitPlaneOfNodes(const std::vector<Vec3>& nodes, const std::vector<int>& ids) {
  std::vector<Vec3> p;
  for (int v : ids) p.push_back(nodes[v]);
  return fitPlane(p);
}

// The sliver and the neighbours that lie in its plane (9.2), its nodes and the sliver plane.
struct FlatGroup {
  std::vector<int> ids;  // nodes of the group's elements
  double diameter = 0.0, eps = 0.0, area_eps = 0.0;
  std::vector<char> in_group;  // per element
  std::vector<int> group;      // the sliver first
  Plane plane;
};

// Grows the group from sliver s by face neighbours with all nodes within thin_relative * diameter of the
// plane (refitted after each one).
FlatGroup findFlatGroup(const MeshState& state, int s, const RemovalSettings& settings,
                        const std::vector<char>& is_boundary_node) {
  const std::vector<Vec3>& nodes = state.nodes;
  FlatGroup flat;
  std::vector<int>& ids = flat.ids;
  ids = elementNodes(state.elements[s]);
  for (int a : ids)
    for (int b : ids) flat.diameter = std::max(flat.diameter, (nodes[a] - nodes[b]).norm());
  flat.eps = 1e-9 * flat.diameter;
  flat.area_eps = flat.eps * flat.diameter;
  const double diameter = flat.diameter, eps = flat.eps, thin_relative = settings.thin_relative;

  // Flat group: the sliver and face neighbours with all nodes near its plane.
  std::vector<char>& in_group = flat.in_group;
  in_group.assign(state.elements.size(), 0);
  in_group[s] = 1;
  std::vector<int>& group = flat.group;
  group = {s};
  Plane plane = settings.local ? fitPlaneOfNodes(nodes, ids) : sliverPlane(nodes, ids, is_boundary_node, eps);
  for (bool grown = true; grown;) {
    grown = false;
    for (size_t g = 0; g < group.size() && !grown; ++g)
      for (const Face& face : state.elements[group[g]]) {
        for (const auto& user : faceUsers(state, face)) {
          const int e = user.first;
          if (in_group[e]) continue;
          bool flat_element = true;
          for (int v : elementNodes(state.elements[e]))
            flat_element = flat_element &&
                           std::abs(plane.normal.dot(nodes[v] - plane.center)) <= thin_relative * diameter;
          if (!flat_element) continue;
          in_group[e] = 1;
          group.push_back(e);
          for (int v : elementNodes(state.elements[e]))
            if (std::find(ids.begin(), ids.end(), v) == ids.end()) ids.push_back(v);
          if (settings.local) {
            plane = fitPlaneOfNodes(nodes, ids);
          } else {
            plane = sliverPlane(nodes, ids, is_boundary_node, eps);
          }
          grown = true;
          break;
        }
        if (grown) break;
      }
  }
  if (settings.local)
    plane =
        localSliverPlane(state, group, in_group, ids, settings.first_new_node, eps, thin_relative * diameter);
  flat.plane = plane;
  return flat;
}

// The sliver plane with an in-plane frame (e1, e2, normal).
struct PlaneFrame {
  Vec3 center, normal, e1, e2;
  explicit PlaneFrame(const Plane& plane)
      : center(plane.center), normal(plane.normal), e1(normal.unitOrthogonal()), e2(normal.cross(e1)) {}
  Vec2 project(const std::vector<Vec3>& nodes, int v) const {
    return Vec2(e1.dot(nodes[v] - center), e2.dot(nodes[v] - center));
  }
};

// Elements using the group's nodes: the only ones the removal changes.
std::vector<int> affectedElements(const MeshState& state, const std::vector<int>& ids) {
  std::vector<int> affected;
  for (int v : ids) affected.insert(affected.end(), state.adjacency[v].begin(), state.adjacency[v].end());
  std::sort(affected.begin(), affected.end());
  affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
  return affected;
}

void saveUndo(const MeshState& state, const std::vector<int>& affected, const std::vector<int>& ids,
              RemovalUndo* undo) {
  const bool has_disp = !state.displacements.empty(), has_crack = !state.crack.empty();
  undo->elements = affected;
  for (int e : affected) {
    undo->faces.push_back(state.elements[e]);
    if (has_crack) undo->crack.push_back(state.crack[e]);
    undo->element_nodes.push_back(elementNodes(state.elements[e]));
  }
  undo->num_nodes = state.nodes.size();
  for (int v : ids) {
    undo->positions.emplace_back(v, state.nodes[v]);
    if (has_disp) undo->displacements.emplace_back(v, state.displacements[v]);
  }
}

// Per node: whether the removal moved it (projected or new) and the node it is merged into.
struct NodeMerge {
  std::vector<char> moved;
  std::vector<int> target;
};

// Project, then merge nodes closer than the merge distance (union-find over the element's nodes).
NodeMerge projectAndMergeNodes(MeshState& state, const FlatGroup& flat, const Vec3& center,
                               const Vec3& normal, const RemovalSettings& settings, RemovalCounts& counts) {
  std::vector<Vec3>& nodes = state.nodes;
  const std::vector<int>& ids = flat.ids;
  const bool has_disp = !state.displacements.empty();
  NodeMerge merge;
  std::vector<char>& moved = merge.moved;
  moved.assign(nodes.size(), 0);
  std::vector<char> on_plane(nodes.size(), 0);
  std::map<int, Vec3> original;
  for (int v : ids) original[v] = nodes[v];
  for (int v : ids) {
    const double d = normal.dot(nodes[v] - center);
    counts.max_projection = std::max(counts.max_projection, std::abs(d));
    on_plane[v] = std::abs(d) <= flat.eps;
    nodes[v] -= d * normal;
    moved[v] = 1;
  }
  std::vector<int> merged(nodes.size());
  std::iota(merged.begin(), merged.end(), 0);
  std::function<int(int)> root = [&](int v) { return merged[v] == v ? v : merged[v] = root(merged[v]); };
  const double merge_distance = settings.merge_relative_distance * flat.diameter;
  for (size_t i = 0; i < ids.size(); ++i)
    for (size_t j = i + 1; j < ids.size(); ++j)
      if ((nodes[ids[i]] - nodes[ids[j]]).norm() < merge_distance) {
        const int a = root(ids[i]), b = root(ids[j]);
        if (a != b) merged[std::max(a, b)] = std::min(a, b);
      }
  std::map<int, std::vector<int>> clusters;
  for (int v : ids) clusters[root(v)].push_back(v);
  std::vector<int>& target = merge.target;  // merged node -> the node kept
  target.resize(nodes.size());
  std::iota(target.begin(), target.end(), 0);
  for (const auto& cluster : clusters) {
    if (cluster.second.size() < 2) continue;
    counts.merged_nodes += static_cast<int>(cluster.second.size()) - 1;
    int keep = cluster.first;
    if (settings.local) {
      // A node that was on the plane keeps its place (and its values), else a node from before the cut
      // returns to its place: the new nodes snap to the existing geometry (9.3.1).
      auto rank = [&](int v) { return on_plane[v] ? 0 : (v < settings.first_new_node ? 1 : 2); };
      for (int v : cluster.second)
        if (rank(v) < rank(keep) || (rank(v) == rank(keep) && v < keep)) keep = v;
      if (rank(keep) == 1) nodes[keep] = original[keep];
      for (int v : cluster.second) target[v] = keep;
      continue;
    }
    Vec3 position = Vec3::Zero(), displacement = Vec3::Zero();
    for (int v : cluster.second) {
      position += nodes[v];
      if (has_disp) displacement += state.displacements[v];
    }
    const double k = static_cast<double>(cluster.second.size());
    nodes[keep] = position / k;
    if (has_disp) state.displacements[keep] = displacement / k;
    for (int v : cluster.second) target[v] = keep;
  }
  return merge;
}

// Apply the merge: drop repeated nodes, faces without area and elements without volume. Returns per element
// whether it collapsed.
std::vector<char> applyNodeMerge(MeshState& state, const std::vector<int>& affected, const FlatGroup& flat,
                                 const NodeMerge& merge, RemovalCounts& counts) {
  const std::vector<Vec3>& nodes = state.nodes;
  const bool has_crack = !state.crack.empty();
  std::vector<char> deleted(state.elements.size(), 0);
  for (int e : affected) {
    ElementFaces next;
    std::vector<char> flags;
    bool touched = false;
    for (size_t fi = 0; fi < state.elements[e].size(); ++fi) {
      const Face& face = state.elements[e][fi];
      Face f;
      for (int v : face) {
        touched = touched || merge.moved[v];
        const int r = merge.target[v];
        if (f.empty() || f.back() != r) f.push_back(r);
      }
      while (f.size() > 1 && f.front() == f.back()) f.pop_back();
      if (f.size() < 3) continue;
      if (touched && newellNormal(nodes, f).norm() <= 2.0 * flat.area_eps) continue;
      next.push_back(std::move(f));
      if (has_crack) flags.push_back(state.crack[e][fi]);
    }
    state.elements[e] = std::move(next);
    if (has_crack) state.crack[e] = std::move(flags);
    if (flat.in_group[e] || !touched) continue;
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
  for (int e : affected) counts.collapsed += deleted[e];
  return deleted;
}

// The flattened group's surface: its upper (counter-clockwise around the normal) and lower faces, each set
// tiling the projected polygon, and the neighbours across them.
struct SliverSurface {
  ElementFaces faces;
  std::vector<char> crack;
  std::vector<std::vector<Vec2>> polygon;      // per face: 2D counter-clockwise
  std::vector<int> orientation;                // per face: +1 upper, -1 lower
  std::vector<std::pair<int, int>> neighbour;  // per face: (element, face) across it, or (-1, -1)
};

// Upper (counter-clockwise around the normal) and lower faces of the flattened element; each set tiles the
// projected polygon.
// The flat group's surface: faces not shared by two group elements.
SliverSurface sliverSurface(const MeshState& state, const FlatGroup& flat, const PlaneFrame& frame) {
  const bool has_crack = !state.crack.empty();
  SliverSurface surface;
  ElementFaces& sliver = surface.faces;
  {
    std::map<std::vector<int>, int> uses;
    for (int g : flat.group)
      for (const Face& face : state.elements[g]) ++uses[sortedKey(face)];
    for (int g : flat.group)
      for (size_t f = 0; f < state.elements[g].size(); ++f)
        if (uses[sortedKey(state.elements[g][f])] == 1) {
          sliver.push_back(state.elements[g][f]);
          surface.crack.push_back(has_crack ? state.crack[g][f] : 0);
        }
  }
  std::vector<std::vector<Vec2>>& polygon = surface.polygon;
  std::vector<int>& orientation = surface.orientation;
  polygon.resize(sliver.size());
  orientation.assign(sliver.size(), 0);
  for (size_t f = 0; f < sliver.size(); ++f) {
    double area = 0.0;
    for (size_t k = 0; k < sliver[f].size(); ++k) {
      polygon[f].push_back(frame.project(state.nodes, sliver[f][k]));
      if (k > 0) area += cross2(polygon[f][k - 1], polygon[f][k]);
    }
    area += cross2(polygon[f].back(), polygon[f].front());
    orientation[f] = area > 0.0 ? 1 : -1;
    if (orientation[f] < 0) std::reverse(polygon[f].begin(), polygon[f].end());  // 2D counter-clockwise
  }
  return surface;
}

// Neighbours across the sliver faces (before their faces change); crack faces have none.
void findSliverNeighbours(const MeshState& state, const std::vector<int>& affected,
                          const std::vector<char>& deleted, const FlatGroup& flat, SliverSurface& surface) {
  const bool has_crack = !state.crack.empty();
  const ElementFaces& sliver = surface.faces;
  std::map<std::vector<int>, std::vector<std::pair<int, int>>> face_users;
  for (int e : affected)
    if (!deleted[e] && !flat.in_group[e])
      for (size_t f = 0; f < state.elements[e].size(); ++f)
        if (!has_crack || !state.crack[e][f])
          face_users[sortedKey(state.elements[e][f])].emplace_back(e, int(f));
  // The neighbour's copy runs opposite to the sliver's (merged needles may leave two faces on one node set).
  std::vector<std::pair<int, int>>& neighbour = surface.neighbour;
  neighbour.assign(sliver.size(), {-1, -1});
  for (size_t f = 0; f < sliver.size(); ++f) {
    if (surface.crack[f]) continue;
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
}

// Points of the sliver plane: the sliver's (merged) nodes, new edge intersection nodes, and per edge of the
// tilings the nodes inside it.
struct SliverPoints {
  std::vector<int> points;
  std::map<int, Vec2> point2d;
  std::set<std::pair<int, int>> upper_edges, lower_edges;
  std::map<std::pair<int, int>, std::vector<std::pair<double, int>>> on_edge;  // along (min, max)
};

// Sliver points: its (merged) nodes and the intersections of upper with lower edges (new nodes).
SliverPoints intersectSliverEdges(MeshState& state, const SliverSurface& surface, const PlaneFrame& frame,
                                  const FlatGroup& flat, const RemovalSettings& settings, NodeMerge& merge,
                                  RemovalCounts& counts) {
  std::vector<Vec3>& nodes = state.nodes;
  const bool has_disp = !state.displacements.empty();
  const ElementFaces& sliver = surface.faces;
  const double eps = flat.eps;
  SliverPoints sp;
  std::vector<int>& points = sp.points;
  std::map<int, Vec2>& point2d = sp.point2d;
  points = elementNodes(sliver);
  for (int v : points) point2d[v] = frame.project(nodes, v);
  for (size_t f = 0; f < sliver.size(); ++f)
    for (size_t k = 0; k < sliver[f].size(); ++k)
      (surface.orientation[f] > 0 ? sp.upper_edges : sp.lower_edges)
          .insert(edgeKey(sliver[f][k], sliver[f][(k + 1) % sliver[f].size()]));
  for (const auto& up : sp.upper_edges)
    for (const auto& low : sp.lower_edges) {
      if (up.first == low.first || up.first == low.second || up.second == low.first ||
          up.second == low.second)
        continue;
      const Vec2 p = point2d[up.first], r = point2d[up.second] - p;
      const Vec2 q = point2d[low.first], d = point2d[low.second] - q;
      const double denominator = cross2(r, d);
      if (std::abs(denominator) <= flat.area_eps) continue;  // parallel
      const double t = cross2(q - p, d) / denominator, u = cross2(q - p, r) / denominator;
      const double tol_t = eps / r.norm(), tol_u = eps / d.norm();
      if (t <= tol_t || t >= 1.0 - tol_t || u <= tol_u || u >= 1.0 - tol_u) continue;
      const int id = static_cast<int>(nodes.size());
      nodes.push_back((1.0 - t) * nodes[up.first] + t * nodes[up.second]);
      merge.moved.push_back(1);
      merge.target.push_back(id);
      state.adjacency.emplace_back();
      if (settings.local) state.replacement.push_back(id);
      // The interpolant is linear on edges: the mean of its values along the two crossing edges.
      if (settings.local)
        state.new_stencils.push_back({{up.first, 0.5 * (1.0 - t)},
                                      {up.second, 0.5 * t},
                                      {low.first, 0.5 * (1.0 - u)},
                                      {low.second, 0.5 * u}});
      if (has_disp)
        state.displacements.push_back(
            0.5 * ((1.0 - t) * state.displacements[up.first] + t * state.displacements[up.second] +
                   (1.0 - u) * state.displacements[low.first] + u * state.displacements[low.second]));
      point2d[id] = p + t * r;
      points.push_back(id);
      sp.on_edge[up].emplace_back(t, id);
      sp.on_edge[low].emplace_back(u, id);
      ++counts.new_nodes;
    }
  return sp;
}

// Nodes lying inside an edge of the other tiling (T-junctions in the plane).
void addTJunctions(const ElementFaces& sliver, double eps, SliverPoints& sp) {
  std::map<int, Vec2>& point2d = sp.point2d;
  for (const auto* edges : {&sp.upper_edges, &sp.lower_edges})
    for (const auto& edge : *edges)
      for (int v : elementNodes(sliver)) {
        if (v == edge.first || v == edge.second) continue;
        const Vec2 p = point2d[edge.first], r = point2d[edge.second] - p;
        const double t = (point2d[v] - p).dot(r) / r.squaredNorm();
        if (t <= 0.0 || t >= 1.0 || std::abs(cross2(r, point2d[v] - p)) / r.norm() > eps) continue;
        auto& list = sp.on_edge[edge];
        if (std::find_if(list.begin(), list.end(), [v](const auto& x) { return x.second == v; }) ==
            list.end())
          list.emplace_back(t, v);
      }
}

// Whether x lies in the counter-clockwise convex polygon poly (within eps).
bool insideConvex(const std::vector<Vec2>& poly, const Vec2& x, double eps) {
  for (size_t k = 0; k < poly.size(); ++k) {
    const Vec2 edge = poly[(k + 1) % poly.size()] - poly[k];
    if (cross2(edge, x - poly[k]) / edge.norm() < -eps) return false;
  }
  return true;
}

double polygonArea(const std::vector<Vec2>& poly) {
  double area = 0.0;
  for (size_t k = 0; k < poly.size(); ++k) area += cross2(poly[k], poly[(k + 1) % poly.size()]);
  return 0.5 * area;
}

// Per sliver face: its cells (2D ccw) and the sliver face on the other side of each.
using SliverCells = std::vector<std::vector<std::pair<Face, int>>>;

// Re-tessellation: cells = upper face ∩ lower face (convex), counter-clockwise around the normal.
SliverCells retessellateSliver(const SliverSurface& surface, SliverPoints& sp, const FlatGroup& flat) {
  const std::vector<std::vector<Vec2>>& polygon = surface.polygon;
  const std::vector<int>& orientation = surface.orientation;
  std::map<int, Vec2>& point2d = sp.point2d;
  const size_t num_faces = surface.faces.size();
  SliverCells cells_of(num_faces);
  for (size_t fu = 0; fu < num_faces; ++fu) {
    if (orientation[fu] < 0) continue;
    double covered = 0.0;
    for (size_t fl = 0; fl < num_faces; ++fl) {
      if (orientation[fl] > 0) continue;
      Face cell;
      Vec2 mean = Vec2::Zero();
      for (int v : sp.points)
        if (insideConvex(polygon[fu], point2d[v], flat.eps) &&
            insideConvex(polygon[fl], point2d[v], flat.eps)) {
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
      if (area <= flat.area_eps) continue;
      covered += area;
      cells_of[fu].emplace_back(cell, static_cast<int>(fl));
      cells_of[fl].emplace_back(cell, static_cast<int>(fu));
    }
    if (std::abs(covered - polygonArea(polygon[fu])) > 1e-9 * flat.diameter * flat.diameter)
      throw std::runtime_error("sliver re-tessellation does not cover upper face " + std::to_string(fu));
  }
  return cells_of;
}

// New and T-junction nodes enter every face along the split edges.
void insertEdgeNodes(MeshState& state, const std::vector<int>& affected, const std::vector<char>& deleted,
                     const std::vector<char>& in_group,
                     std::map<std::pair<int, int>, std::vector<std::pair<double, int>>>& on_edge) {
  for (auto& entry : on_edge) std::sort(entry.second.begin(), entry.second.end());
  for (int e : affected) {
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
}

// Each neighbour's face on the sliver is replaced by the cells it covers (outward for the neighbour); a
// cell is a crack face where the sliver face on its other side was one.
void replaceNeighbourFaces(MeshState& state, const SliverSurface& surface, const SliverCells& cells_of) {
  const bool has_crack = !state.crack.empty();
  std::map<std::pair<int, int>, std::vector<std::pair<Face, char>>> replacement;
  for (size_t f = 0; f < surface.faces.size(); ++f) {
    if (surface.neighbour[f].first < 0) continue;
    for (auto [cell, other] : cells_of[f]) {
      if (surface.orientation[f] > 0)
        std::reverse(cell.begin(), cell.end());  // neighbour above: outward is -normal
      replacement[surface.neighbour[f]].emplace_back(cell, surface.crack[other]);
    }
  }
  for (const auto& entry : replacement) {
    ElementFaces& faces = state.elements[entry.first.first];
    faces[entry.first.second].clear();
    for (const auto& cell : entry.second) {
      faces.push_back(cell.first);
      if (has_crack) state.crack[entry.first.first].push_back(cell.second);
    }
  }
}

// A neighbour's face that merged nodes made coincide with a crack face of the group lies on the crack now.
void markCrackFacesOfGroup(MeshState& state, const std::vector<int>& affected,
                           const std::vector<char>& deleted, const FlatGroup& flat) {
  std::set<std::vector<int>> crack_keys;
  for (int g : flat.group)
    for (size_t f = 0; f < state.elements[g].size(); ++f)
      if (state.crack[g][f]) crack_keys.insert(sortedKey(state.elements[g][f]));
  for (int e : affected)
    if (!deleted[e] && !flat.in_group[e])
      for (size_t f = 0; f < state.elements[e].size(); ++f)
        if (!state.elements[e][f].empty() && crack_keys.count(sortedKey(state.elements[e][f])))
          state.crack[e][f] = 1;
}

// Fan triangulation of a bent face: apex with the largest smallest fan triangle.
std::vector<Face> bestApexFan(const std::vector<Vec3>& nodes, const Face& face) {
  const Vec3 n = newellNormal(nodes, face);
  const int k = static_cast<int>(face.size());
  int best = 0;
  double best_area = -INFINITY;
  for (int apex = 0; apex < k; ++apex) {
    double smallest = INFINITY;
    for (int j = 1; j + 1 < k; ++j)
      smallest = std::min(smallest, n.dot((nodes[face[(apex + j) % k]] - nodes[face[apex]])
                                              .cross(nodes[face[(apex + j + 1) % k]] - nodes[face[apex]])));
    if (smallest > best_area) {
      best_area = smallest;
      best = apex;
    }
  }
  std::vector<Face> fan;
  for (int j = 1; j + 1 < k; ++j) fan.push_back({face[best], face[(best + j) % k], face[(best + j + 1) % k]});
  return fan;
}

// Faces bent by the projection (non-planar, more than 3 nodes) are fan-triangulated, identically on both
// sides.
void triangulateBentFaces(MeshState& state, const std::vector<int>& affected,
                          const std::vector<char>& deleted, const std::vector<char>& moved, double eps) {
  const std::vector<Vec3>& nodes = state.nodes;
  const bool has_crack = !state.crack.empty();
  std::map<std::vector<int>, std::pair<Face, std::vector<Face>>> triangulated;  // key -> (first copy, fan)
  for (int e : affected) {
    if (deleted[e]) continue;
    ElementFaces next;
    std::vector<char> flags;
    for (size_t fi = 0; fi < state.elements[e].size(); ++fi) {
      Face& face = state.elements[e][fi];
      const char flag = has_crack ? state.crack[e][fi] : 0;
      if (face.empty()) continue;
      bool bent = false;
      if (face.size() > 3 && std::any_of(face.begin(), face.end(), [&](int v) { return moved[v] != 0; })) {
        const Vec3 n = newellNormal(nodes, face).normalized();
        for (int v : face) bent = bent || std::abs(n.dot(nodes[v] - nodes[face[0]])) > eps;
      }
      if (!bent) {
        next.push_back(std::move(face));
        flags.push_back(flag);
        continue;
      }
      const std::vector<int> key = sortedKey(face);
      auto it = triangulated.find(key);
      if (it == triangulated.end()) {
        const std::vector<Face> fan = bestApexFan(nodes, face);
        it = triangulated.emplace(key, std::make_pair(face, fan)).first;
        for (const Face& t : fan) {
          next.push_back(t);
          flags.push_back(flag);
        }
        continue;
      }
      const bool same = face == it->second.first;  // else the opposite copy
      for (Face t : it->second.second) {
        if (!same) std::reverse(t.begin(), t.end());
        next.push_back(t);
        flags.push_back(flag);
      }
    }
    state.elements[e] = std::move(next);
    if (has_crack) state.crack[e] = std::move(flags);
  }
}

// Empties the deleted elements, maps nodes to their merge targets and updates the adjacency of the touched
// elements' old and new nodes (local mode).
void finishRemoval(MeshState& state, const std::vector<int>& affected, const std::vector<char>& deleted,
                   const std::vector<int>& ids, const std::vector<int>& target,
                   const RemovalSettings& settings, const RemovalUndo* undo) {
  const bool has_crack = !state.crack.empty();
  for (int e : affected)
    if (deleted[e]) {
      state.elements[e].clear();
      if (has_crack) state.crack[e].clear();
    }
  for (int& v : state.node_map)
    if (v >= 0) v = target[v];
  if (settings.local)
    for (int v : ids)
      if (target[v] != v) state.replacement[v] = target[v];
  // Adjacency of the touched elements' old and new nodes.
  for (int e : affected) {
    for (int v :
         undo ? undo->element_nodes[std::lower_bound(affected.begin(), affected.end(), e) - affected.begin()]
              : std::vector<int>()) {
      auto& list = state.adjacency[v];
      list.erase(std::remove(list.begin(), list.end(), e), list.end());
    }
  }
  if (undo)
    for (int e : affected)
      for (int v : elementNodes(state.elements[e])) {
        auto& list = state.adjacency[v];
        list.insert(std::lower_bound(list.begin(), list.end(), e), e);
      }
}

// Removes the flat group as in 9.2: projection onto its plane, node merging, re-tessellation of the plane by
// the overlay of its upper and lower faces, and the neighbours' faces replaced by the cells. Returns the
// number of elements removed (not counting collapsed ones).
int removeFlatGroup(MeshState& state, const FlatGroup& flat, const RemovalSettings& settings,
                    RemovalCounts& counts, RemovalUndo* undo) {
  const PlaneFrame frame(flat.plane);
  const std::vector<int> affected = affectedElements(state, flat.ids);
  if (undo) saveUndo(state, affected, flat.ids, undo);
  NodeMerge merge = projectAndMergeNodes(state, flat, frame.center, frame.normal, settings, counts);
  std::vector<char> deleted = applyNodeMerge(state, affected, flat, merge, counts);
  SliverSurface surface = sliverSurface(state, flat, frame);
  findSliverNeighbours(state, affected, deleted, flat, surface);
  SliverPoints points = intersectSliverEdges(state, surface, frame, flat, settings, merge, counts);
  addTJunctions(surface.faces, flat.eps, points);
  const SliverCells cells_of = retessellateSliver(surface, points, flat);
  insertEdgeNodes(state, affected, deleted, flat.in_group, points.on_edge);
  replaceNeighbourFaces(state, surface, cells_of);
  if (!state.crack.empty()) markCrackFacesOfGroup(state, affected, deleted, flat);
  for (int g : flat.group) deleted[g] = 1;
  triangulateBentFaces(state, affected, deleted, merge.moved, flat.eps);
  finishRemoval(state, affected, deleted, flat.ids, merge.target, settings, undo);
  return static_cast<int>(flat.group.size());
}

// Removes element s as in 9.2, together with the neighbours that lie in its sliver plane within thin_distance
// (relative to the sliver's diameter; they would be flattened further). Throws std::runtime_error where the
// construction fails. Returns the number of elements removed (not counting collapsed ones); deleted
// elements are left empty. undo (local mode) receives the touched elements' previous state.
int removeElement(MeshState& state, int s, const RemovalSettings& settings,
                  const std::vector<char>& is_boundary_node, RemovalCounts& counts, RemovalUndo* undo) {
  const FlatGroup flat = findFlatGroup(state, s, settings, is_boundary_node);
  return removeFlatGroup(state, flat, settings, counts, undo);
}

// Drops deleted (empty) elements and unused nodes (global mode, after each removal).
void compactState(MeshState& state) {
  const bool has_disp = !state.displacements.empty();
  MeshState out;
  std::vector<int> new_id(state.nodes.size(), -1);
  for (size_t e = 0; e < state.elements.size(); ++e) {
    if (state.elements[e].empty()) continue;
    for (Face& face : state.elements[e])
      for (int& v : face) {
        if (new_id[v] < 0) {
          new_id[v] = static_cast<int>(out.nodes.size());
          out.nodes.push_back(state.nodes[v]);
          if (has_disp) out.displacements.push_back(state.displacements[v]);
        }
        v = new_id[v];
      }
    out.elements.push_back(std::move(state.elements[e]));
    out.parent.push_back(state.parent[e]);
  }
  for (int& v : state.node_map)
    if (v >= 0) v = new_id[v];
  out.node_map = std::move(state.node_map);
  state = std::move(out);
}

// Relative tolerance that covers the face planarity and convexity deviations of one element.
double requiredRelativeTolerance(const std::vector<Vec3>& nodes, const ElementFaces& faces) {
  double required = 0.0;
  const std::vector<int> ids = elementNodes(faces);
  Vec3 lo = nodes[ids[0]], hi = lo;
  for (int v : ids) {
    lo = lo.cwiseMin(nodes[v]);
    hi = hi.cwiseMax(nodes[v]);
  }
  const double scale = (hi - lo).norm();
  for (const Face& face : faces) {
    const Vec3 n = newellNormal(nodes, face).normalized();
    double offset = 0.0;
    for (int v : face) offset += n.dot(nodes[v]);
    offset /= static_cast<double>(face.size());
    for (int v : face) required = std::max(required, std::abs(n.dot(nodes[v]) - offset) / scale);
    for (int v : ids) required = std::max(required, (n.dot(nodes[v]) - offset) / scale);
  }
  return required;
}

// Same for all elements.
double requiredRelativeTolerance(const MeshState& state) {
  double required = 0.0;
  for (const ElementFaces& faces : state.elements)
    required = std::max(required, requiredRelativeTolerance(state.nodes, faces));
  return required;
}

// Element e as a ConvexPolyhedron (throws std::invalid_argument if invalid).
ConvexPolyhedron makeElement(const MeshState& state, int e, double relative_tolerance) {
  std::vector<int> ids;
  std::map<int, int> local;
  std::vector<ConvexPolyhedron::Face> faces;
  for (const Face& face : state.elements[e]) {
    ConvexPolyhedron::Face local_face;
    for (int v : face) {
      auto it = local.emplace(v, static_cast<int>(ids.size())).first;
      if (it->second == static_cast<int>(ids.size())) ids.push_back(v);
      local_face.push_back(it->second);
    }
    faces.push_back(std::move(local_face));
  }
  std::vector<Vec3> points;
  for (int v : ids) points.push_back(state.nodes[v]);
  return ConvexPolyhedron(std::move(points), std::move(faces), relative_tolerance, std::move(ids));
}

// The touched elements after a local removal: valid convex elements at the tolerance, every face shared by
// at most two elements in opposite orientation, crack faces unshared, and every boundary edge of a touched
// element matched by a reverse boundary edge. Returns the relative tolerance they need; throws otherwise.
double checkTouchedElements(const MeshState& state, const std::vector<int>& touched, double tolerance,
                            double max_tolerance) {
  double required = tolerance;
  for (int e : touched)
    if (!state.elements[e].empty())
      required = std::max(required, 1.5 * requiredRelativeTolerance(state.nodes, state.elements[e]));
  if (required > max_tolerance) throw std::runtime_error("neighbours too far from convex");
  std::map<std::pair<int, int>, int> boundary_edges;
  std::set<int> near;  // the touched elements and their node neighbours (to match boundary edges)
  for (int e : touched) {
    if (state.elements[e].empty()) continue;
    makeElement(state, e, required);
    for (size_t f = 0; f < state.elements[e].size(); ++f) {
      const Face& face = state.elements[e][f];
      const std::vector<std::pair<int, int>> users = faceUsers(state, face);
      if (users.size() > 2) throw std::runtime_error("face used by more than two elements");
      if (users.size() == 2) {
        const auto& other = users[0].first == e ? users[1] : users[0];
        if (isCrack(state, e, int(f)) || isCrack(state, other.first, other.second))
          throw std::runtime_error("crack face shared");
        const Face& b = state.elements[other.first][other.second];
        const Face reversed(face.rbegin(), face.rend());
        const auto start = std::find(b.begin(), b.end(), reversed[0]);
        Face rotated(start, b.end());
        rotated.insert(rotated.end(), b.begin(), start);
        if (rotated != reversed) throw std::runtime_error("shared face not in opposite order");
      }
    }
    for (int v : elementNodes(state.elements[e]))
      near.insert(state.adjacency[v].begin(), state.adjacency[v].end());
  }
  // Boundary edges of the touched elements must be closed by boundary faces around them.
  std::set<int> touched_set(touched.begin(), touched.end());
  for (int e : near)
    for (size_t f = 0; f < state.elements[e].size(); ++f) {
      const Face& face = state.elements[e][f];
      if (faceUsers(state, face).size() == 2 && !isCrack(state, e, int(f))) continue;
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        const int sign = a < b ? 1 : -1;
        boundary_edges[edgeKey(a, b)] += sign;
      }
    }
  for (int e : touched)
    for (const Face& face : state.elements[e])
      for (size_t k = 0; k < face.size(); ++k) {
        const auto it = boundary_edges.find(edgeKey(face[k], face[(k + 1) % face.size()]));
        if (it != boundary_edges.end() && it->second != 0) throw std::runtime_error("boundary not closed");
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
      RemovalSettings settings;
      settings.merge_relative_distance = options.merge_relative_distance;
      settings.thin_relative = options.sliver_relative_thickness;
      next.adjacency = buildAdjacency(next);
      removed = removeElement(next, worst, settings, current.isBoundaryNode(), counts, nullptr);
      compactState(next);
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

CutSliverStats removeCutSlivers(EditableMesh& mesh, const std::vector<int>& candidates, int first_new_node,
                                double relative_tolerance, const CutSliverOptions& options,
                                CutSliverEdits* edits) {
  if (!(options.relative_thickness >= 0.0 && options.relative_thickness < 1.0))
    throw std::invalid_argument("removeCutSlivers: relative_thickness must be in [0, 1), got " +
                                std::to_string(options.relative_thickness));
  if (!(options.merge_relative_distance >= 0.0 && options.merge_relative_distance < 0.5))
    throw std::invalid_argument("removeCutSlivers: merge_relative_distance must be in [0, 0.5)");
  if (!(options.max_relative_tolerance > 0.0 && options.max_relative_tolerance < 1e-2))
    throw std::invalid_argument("removeCutSlivers: max_relative_tolerance must be in (0, 1e-2)");
  CutSliverStats stats;
  stats.relative_tolerance = relative_tolerance;
  const int num_input_nodes = static_cast<int>(mesh.nodes.size());
  const int num_elements = static_cast<int>(mesh.elements.size());
  if (edits) {
    edits->kept_elements.resize(num_elements);
    std::iota(edits->kept_elements.begin(), edits->kept_elements.end(), 0);
    edits->node_replacement.resize(num_input_nodes);
    std::iota(edits->node_replacement.begin(), edits->node_replacement.end(), 0);
    edits->new_node_stencils.clear();
    edits->num_input_nodes = num_input_nodes;
  }
  stats.num_candidates = static_cast<int>(candidates.size());
  if (!options.enabled || candidates.empty()) return stats;

  // Relative thickness of the live candidates (recomputed for the ones a removal touches).
  std::map<int, double> thickness;
  MeshState state;
  auto measure = [&](int e) {
    try {
      thickness[e] = elementQuality(makeElement(state, e, relative_tolerance)).relative_thickness;
    } catch (const std::invalid_argument&) {
      thickness[e] = 0.0;  // degenerate: thinnest
    }
  };
  state.nodes = std::move(mesh.nodes);
  state.displacements = std::move(mesh.displacements);
  state.elements = std::move(mesh.elements);
  state.crack = std::move(mesh.crack_faces);
  for (int e : candidates) measure(e);
  for (const auto& entry : thickness) stats.num_thin += entry.second < options.relative_thickness;
  if (stats.num_thin > 0) {
    state.adjacency = buildAdjacency(state);  // the one pass over the mesh
    state.replacement.resize(state.nodes.size());
    std::iota(state.replacement.begin(), state.replacement.end(), 0);
    state.num_input_nodes = num_input_nodes;
    RemovalSettings settings;
    settings.merge_relative_distance = options.merge_relative_distance;
    settings.thin_relative = options.relative_thickness;
    settings.local = true;
    settings.first_new_node = first_new_node;
    std::set<int> rejected;
    for (;;) {
      int worst = -1;
      double worst_thickness = options.relative_thickness;
      for (const auto& [e, t] : thickness)
        if (t < worst_thickness && !rejected.count(e)) {
          worst = e;
          worst_thickness = t;
        }
      if (worst < 0) break;
      RemovalCounts counts;
      RemovalUndo undo;
      const size_t num_stencils = state.new_stencils.size();
      try {
        const int removed = removeElement(state, worst, settings, {}, counts, &undo);
        stats.relative_tolerance = checkTouchedElements(state, undo.elements, stats.relative_tolerance,
                                                        options.max_relative_tolerance);
        stats.num_removed += removed;
        stats.num_collapsed += counts.collapsed;
        stats.num_new_nodes += counts.new_nodes;
        stats.num_merged_nodes += counts.merged_nodes;
        stats.max_projection_distance = std::max(stats.max_projection_distance, counts.max_projection);
        for (int e : undo.elements) {
          if (state.elements[e].empty()) {
            thickness.erase(e);
          } else if (thickness.count(e)) {
            measure(e);
          }
        }
      } catch (const std::exception&) {  // invalid neighbours or overlay: keep the element as it was
        if (!undo.elements.empty()) {
          for (int e : undo.elements)  // drop the adjacency entries of the changed elements
            for (int v : elementNodes(state.elements[e])) {
              auto& list = state.adjacency[v];
              list.erase(std::remove(list.begin(), list.end(), e), list.end());
            }
          for (size_t k = 0; k < undo.elements.size(); ++k) {
            const int e = undo.elements[k];
            state.elements[e] = undo.faces[k];
            if (!state.crack.empty()) state.crack[e] = undo.crack[k];
            for (int v : undo.element_nodes[k]) {
              auto& list = state.adjacency[v];
              if (!std::binary_search(list.begin(), list.end(), e))
                list.insert(std::lower_bound(list.begin(), list.end(), e), e);
            }
          }
          for (const auto& [v, x] : undo.positions) {
            state.nodes[v] = x;
            state.replacement[v] = v;
          }
          for (const auto& [v, u] : undo.displacements) state.displacements[v] = u;
          state.nodes.resize(undo.num_nodes);
          state.adjacency.resize(undo.num_nodes);
          state.replacement.resize(undo.num_nodes);
          if (!state.displacements.empty()) state.displacements.resize(undo.num_nodes);
          state.new_stencils.resize(num_stencils);
        }
        rejected.insert(worst);
        ++stats.num_rejected;
      }
    }
  }
  // Compact the elements; merged nodes stay (unused).
  std::vector<int> kept;
  for (int e = 0; e < num_elements; ++e)
    if (!state.elements[e].empty()) {
      if (static_cast<int>(kept.size()) != e) {
        state.elements[kept.size()] = std::move(state.elements[e]);
        if (!state.crack.empty()) state.crack[kept.size()] = std::move(state.crack[e]);
      }
      kept.push_back(e);
    }
  state.elements.resize(kept.size());
  if (!state.crack.empty()) state.crack.resize(kept.size());
  if (edits) {
    edits->kept_elements = kept;
    if (!state.replacement.empty()) {
      edits->node_replacement = state.replacement;
      for (int& v : edits->node_replacement)
        while (state.replacement[v] != v) v = state.replacement[v];
    }
    edits->new_node_stencils = std::move(state.new_stencils);
  }
  mesh.nodes = std::move(state.nodes);
  mesh.displacements = std::move(state.displacements);
  mesh.elements = std::move(state.elements);
  mesh.crack_faces = std::move(state.crack);
  return stats;
}

}  // namespace rc
