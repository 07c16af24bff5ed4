#include "relaxed_connectivity/fem/plane_cut.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include "relaxed_connectivity/fem/element_split.h"
#include "relaxed_connectivity/fem/polygon_geometry.h"

namespace rc {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("cutMeshByPlane: " + what);
}

// Merges the thin elements among the split parts (removeCutSlivers) and drops the merged nodes; node sides
// follow the nodes (a node that absorbed one on the plane lies on it: the cut snapped to it, 9.3.1).
void mergeCutSlivers(std::vector<Vec3>& nodes, std::vector<Vec3>& disp,
                     std::vector<PolyhedralMesh::ElementFaces>& elements, PlaneCutResult& result,
                     const std::vector<int>& split_parts, int num_input_nodes, const Vec3& plane_point,
                     const Vec3& normal, double snap, double relative_tolerance,
                     const CutSliverOptions& options) {
  EditableMesh edit{std::move(nodes), std::move(disp), std::move(elements), {}};
  CutSliverEdits edits;
  const int num_cut_nodes = static_cast<int>(edit.nodes.size());
  result.slivers = removeCutSlivers(edit, split_parts, num_input_nodes, relative_tolerance, options, &edits);
  nodes = std::move(edit.nodes);
  disp = std::move(edit.displacements);
  elements = std::move(edit.elements);
  if (result.slivers.num_removed == 0) return;
  std::vector<int> parent, element_side;
  for (int e : edits.kept_elements) {
    parent.push_back(result.parent_element[e]);
    element_side.push_back(result.element_side[e]);
  }
  result.parent_element = std::move(parent);
  result.element_side = std::move(element_side);
  // Sides and stencils of all nodes (appended ones: from their stencils over earlier nodes).
  std::vector<int>& side = result.node_side;
  std::vector<NodeStencil>& stencils = result.node_stencils;
  for (const NodeStencil& local : edits.new_node_stencils) {
    std::map<int, double> combined;
    for (const auto& [v, w] : local)
      for (const auto& [u, x] : stencils[v]) combined[u] += w * x;
    stencils.emplace_back(combined.begin(), combined.end());
  }
  side.resize(nodes.size());
  for (size_t v = num_cut_nodes; v < nodes.size(); ++v) {
    const double d = normal.dot(nodes[v] - plane_point);
    side[v] = std::abs(d) <= snap ? 0 : (d > 0.0 ? 1 : -1);
  }
  for (int v = 0; v < num_cut_nodes; ++v) {
    const int kept = edits.node_replacement[v];
    if (kept != v && side[v] == 0) side[kept] = 0;
  }
  for (int v = 0; v < num_cut_nodes; ++v)
    if (edits.node_replacement[v] == v && side[v] != 0) {
      const double d = normal.dot(nodes[v] - plane_point);
      if (std::abs(d) <= snap) side[v] = 0;
    }
  // Drop the nodes no element uses any more (the others keep their order).
  std::vector<int> new_id(nodes.size(), -1);
  for (const auto& faces : elements)
    for (const auto& face : faces)
      for (int v : face) new_id[v] = 0;
  std::vector<Vec3> used_nodes, used_disp;
  std::vector<int> used_side;
  std::vector<NodeStencil> used_stencils;
  for (size_t v = 0; v < nodes.size(); ++v) {
    if (new_id[v] < 0) continue;
    new_id[v] = static_cast<int>(used_nodes.size());
    used_nodes.push_back(nodes[v]);
    if (!disp.empty()) used_disp.push_back(disp[v]);
    used_side.push_back(side[v]);
    used_stencils.push_back(std::move(stencils[v]));
  }
  for (auto& faces : elements)
    for (auto& face : faces)
      for (int& v : face) v = new_id[v];
  nodes = std::move(used_nodes);
  disp = std::move(used_disp);
  side = std::move(used_side);
  stencils = std::move(used_stencils);
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

  PlaneCutResult result{mesh, {}, {}, {}, {}, 0, 0, 0, {}, {}};
  std::vector<NodeStencil>& stencils = result.node_stencils;
  for (int v = 0; v < mesh.numNodes(); ++v) stencils.push_back({{v, 1.0}});
  std::vector<double> distance(nodes.size());
  std::vector<int>& side = result.node_side;
  side.resize(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    distance[i] = normal.dot(nodes[i] - plane_point);
    side[i] = std::abs(distance[i]) <= snap ? 0 : (distance[i] > 0.0 ? 1 : -1);
    if (side[i] == 0 && distance[i] != 0.0) ++result.num_snapped_nodes;
  }

  EdgeCrossingNodes crossing(distance, [&](int a, int b, double t) {
    nodes.push_back((1.0 - t) * nodes[a] + t * nodes[b]);
    if (has_disp) disp.push_back((1.0 - t) * disp[a] + t * disp[b]);
    distance.push_back(0.0);
    side.push_back(0);
    stencils.push_back({{a, 1.0 - t}, {b, t}});
    return static_cast<int>(nodes.size()) - 1;
  });

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
    const double area_tolerance = 1e-12 * diagonal * diagonal;
    if (!isConvexPolygon(region, area_tolerance, 0.5 * area_tolerance))
      fail("region is not a convex polygon");
  }

  // Crossed elements and the ones to split (crossed, and their cut polygon overlaps the region).
  const int num_elements = mesh.numElements();
  std::vector<char> crossed(num_elements, 0), selected(num_elements, 0);
  for (int e = 0; e < num_elements; ++e) {
    const ElementSides sides = elementSides(mesh.elementFaces(e), side);
    if (!sides.positive && !sides.negative)
      throw std::runtime_error("cutMeshByPlane: element " + std::to_string(e) +
                               " lies within the snap distance of the plane (lower snap_relative_distance)");
    crossed[e] = sides.crossed();
    if (!crossed[e]) continue;
    if (region.empty()) {
      selected[e] = 1;
      continue;
    }
    const std::vector<Vec3> points = planeSectionPoints(mesh.elementFaces(e), side, distance, nodes);
    std::vector<Eigen::Vector2d> section;
    for (int k : counterClockwiseOrder(points, planeCoordinates))
      section.push_back(planeCoordinates(points[k]));
    selected[e] = convexPolygonsOverlap(section, region, 1e-9 * diagonal);
  }
  // Faces of split elements that get split (shared neighbours must split them identically: T-junctions).
  std::set<std::vector<int>> split_faces;

  auto sectionOrder = [&](const std::vector<int>& section_nodes) {
    std::vector<Vec3> points;
    for (int v : section_nodes) points.push_back(nodes[v]);
    return counterClockwiseOrder(points, planeCoordinates);
  };
  std::vector<std::vector<PolyhedralMesh::ElementFaces>> parts(num_elements);
  double max_snapped_distance = 0.0, min_part_scale = INFINITY;
  for (int e = 0; e < num_elements; ++e) {
    if (!selected[e]) continue;
    const PolyhedralMesh::ElementFaces& faces = mesh.elementFaces(e);
    ++result.num_split_elements;
    ElementSplit split = splitElement(faces, side, crossing, sectionOrder);
    if (split.face_in_plane >= 0)
      throw std::runtime_error("cutMeshByPlane: face " + std::to_string(split.face_in_plane) +
                               " of element " + std::to_string(e) +
                               " lies in the cut plane but the element is crossed (lower "
                               "snap_relative_distance)");
    for (int v : split.section) max_snapped_distance = std::max(max_snapped_distance, std::abs(distance[v]));
    for (int f : split.split_faces) split_faces.insert(sortedFaceKey(faces[f]));
    for (const auto* part : {&split.negative, &split.positive}) {
      std::vector<Vec3> points;
      for (const auto& face : *part)
        for (int v : face) points.push_back(nodes[v]);
      min_part_scale = std::min(min_part_scale, boundingDiagonal(points));
    }
    parts[e] = {std::move(split.negative), std::move(split.positive)};
  }
  // Crossed elements left whole: faces shared with a split element are split alike (two coplanar faces),
  // other faces get the new nodes on their edges (T-junctions, 9.3.1).
  for (int e = 0; e < num_elements; ++e) {
    if (!crossed[e] || selected[e]) continue;
    PolyhedralMesh::ElementFaces whole;
    for (const auto& face : mesh.elementFaces(e)) {
      if (split_faces.count(sortedFaceKey(face)) > 0) {
        FaceSplit halves = splitFace(face, side, crossing);
        whole.push_back(std::move(halves.positive));
        whole.push_back(std::move(halves.negative));
        continue;
      }
      PolyhedralMesh::Face all;
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        all.push_back(a);
        const int m = side[a] * side[b] < 0 ? crossing.find(a, b) : -1;
        if (m >= 0) all.push_back(m);
      }
      whole.push_back(std::move(all));
    }
    parts[e] = {std::move(whole)};
  }

  std::vector<PolyhedralMesh::ElementFaces> elements;
  std::vector<int> split_parts;  // elements the split created (sliver candidates)
  for (int e = 0; e < num_elements; ++e) {
    if (parts[e].size() == 2)
      for (int k = 0; k < 2; ++k) split_parts.push_back(static_cast<int>(elements.size()) + k);
    if (parts[e].empty()) {
      elements.push_back(mesh.elementFaces(e));
      result.parent_element.push_back(e);
      result.element_side.push_back(elementSides(mesh.elementFaces(e), side).positive ? 1 : -1);
      continue;
    }
    for (size_t k = 0; k < parts[e].size(); ++k) {
      elements.push_back(std::move(parts[e][k]));
      result.parent_element.push_back(e);
      result.element_side.push_back(parts[e].size() == 1 ? 0 : (k == 0 ? -1 : 1));
    }
  }
  result.num_new_nodes = crossing.size();

  // Keep the input tolerance; widen it to cover cut faces bent through snapped nodes.
  double relative_tolerance = ConvexPolyhedron::kDefaultRelativeTolerance;
  for (const ConvexPolyhedron& element : mesh.elements())
    relative_tolerance = std::max(relative_tolerance, element.tolerance() / element.scale());
  if (max_snapped_distance > 0.0)
    relative_tolerance = std::max(relative_tolerance, 4.0 * max_snapped_distance / min_part_scale);
  if (options.slivers.enabled && !split_parts.empty()) {
    mergeCutSlivers(nodes, disp, elements, result, split_parts, mesh.numNodes(), plane_point, normal, snap,
                    relative_tolerance, options.slivers);
    if (result.slivers.num_removed > 0) {
      try {
        result.mesh = PolyhedralMesh(std::move(nodes), std::move(elements),
                                     std::max(relative_tolerance, result.slivers.relative_tolerance));
        result.displacements = std::move(disp);
        return result;
      } catch (const std::invalid_argument&) {  // validity first: the cut as split, slivers kept
        PlaneCutOptions split_only = options;
        split_only.slivers.enabled = false;
        PlaneCutResult split = cutMeshByPlane(mesh, displacements, plane_point, plane_normal, split_only);
        split.slivers.num_candidates = result.slivers.num_candidates;
        split.slivers.num_thin = split.slivers.num_rejected = result.slivers.num_thin;
        return split;
      }
    }
  }
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

std::vector<Vec3> interpolateCutValues(const PolyhedralMesh& mesh, const PlaneCutResult& cut,
                                       const std::vector<Vec3>& values) {
  if (static_cast<int>(values.size()) != mesh.numNodes())
    throw std::invalid_argument("interpolateCutValues: " + std::to_string(values.size()) + " values for " +
                                std::to_string(mesh.numNodes()) + " nodes");
  const PolyhedralMesh& out_mesh = cut.mesh;
  if (static_cast<int>(cut.node_stencils.size()) == out_mesh.numNodes()) {
    std::vector<Vec3> out(out_mesh.numNodes(), Vec3::Zero());
    for (int v = 0; v < out_mesh.numNodes(); ++v)
      for (const auto& [u, w] : cut.node_stencils[v]) out[v] += w * values[u];
    return out;
  }
  const int old_nodes = mesh.numNodes();
  std::vector<Vec3> out(out_mesh.numNodes());
  std::copy(values.begin(), values.end(), out.begin());
  if (out_mesh.numNodes() == old_nodes) return out;
  std::vector<int> element_of(out_mesh.numNodes() - old_nodes, -1);
  for (int e = 0; e < out_mesh.numElements(); ++e)
    for (int v : out_mesh.element(e).globalNodeIds())
      if (v >= old_nodes && element_of[v - old_nodes] < 0) element_of[v - old_nodes] = e;
  for (int v = old_nodes; v < out_mesh.numNodes(); ++v) {
    const int e = element_of[v - old_nodes];
    if (e < 0) throw std::logic_error("interpolateCutValues: new node " + std::to_string(v) + " is unused");
    const Vec3& x = out_mesh.node(v);
    double best = INFINITY, best_t = 0.0;
    int best_a = -1, best_b = -1;
    for (const PolyhedralMesh::Face& face : mesh.elementFaces(cut.parent_element[e]))
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        const Vec3 ab = mesh.node(b) - mesh.node(a);
        const double t = std::clamp(ab.dot(x - mesh.node(a)) / ab.squaredNorm(), 0.0, 1.0);
        const double d = (mesh.node(a) + t * ab - x).squaredNorm();
        if (d < best) {
          best = d;
          best_t = t;
          best_a = a;
          best_b = b;
        }
      }
    out[v] = (1.0 - best_t) * values[best_a] + best_t * values[best_b];
  }
  return out;
}

}  // namespace rc
