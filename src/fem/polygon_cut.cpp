#include "relaxed_connectivity/fem/polygon_cut.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "relaxed_connectivity/fem/element_split.h"
#include "relaxed_connectivity/fem/polygon_geometry.h"

namespace rc {
namespace {

using Face = PolyhedralMesh::Face;
using ElementFaces = PolyhedralMesh::ElementFaces;
using Vec2 = Eigen::Vector2d;

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("ProgressiveCutMesh: " + what);
}

// Weights of the interpolant at x on a face: the mean value interpolant is linear on the face's boundary
// triangles (barycentric weights in the triangle containing x best).
NodeStencil faceStencil(const std::vector<Vec3>& nodes, const Face& face, const Vec3& x) {
  double best = -INFINITY;
  NodeStencil stencil;
  for (const auto& t : bestFanTriangulation(nodes, face)) {
    const Vec3 v0 = nodes[t[1]] - nodes[t[0]], v1 = nodes[t[2]] - nodes[t[0]], v2 = x - nodes[t[0]];
    const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
    const double denom = d00 * d11 - d01 * d01;
    if (!(denom > 0.0)) continue;
    const double b1 = (d11 * d20 - d01 * d21) / denom, b2 = (d00 * d21 - d01 * d20) / denom;
    const double b0 = 1.0 - b1 - b2;
    const double worst = std::min({b0, b1, b2});
    if (worst > best) {
      best = worst;
      stencil = {{t[0], b0}, {t[1], b1}, {t[2], b2}};
    }
  }
  return stencil;
}

// Union-find over 0..n-1.
struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Element faces grouped by node set: groups in lexicographic order of their sorted node ids (the order of
// a std::map keyed by the sorted ids), each group's (element, face) users in element order. Flat arrays
// sorted once (a 64-bit prefix of the first three ids decides most comparisons).
class FaceGroups {
 public:
  /// keep(e, f): whether face f of element e takes part (null: all faces); groups of the kept faces come
  /// in the same order as among all faces.
  explicit FaceGroups(const std::vector<ElementFaces>& elements,
                      const std::function<bool(int, int)>& keep = nullptr) {
    int num_faces = 0;
    for (size_t e = 0; e < elements.size(); ++e)
      for (size_t f = 0; f < elements[e].size(); ++f)
        num_faces += !keep || keep(static_cast<int>(e), static_cast<int>(f));
    std::vector<int> key_start(num_faces + 1, 0), key_pool;
    std::vector<std::pair<int, int>> refs(num_faces);
    std::vector<uint64_t> prefix(num_faces);
    key_pool.reserve(4 * static_cast<size_t>(num_faces));
    bool packable = true;
    int g = 0;
    for (size_t e = 0; e < elements.size(); ++e)
      for (size_t f = 0; f < elements[e].size(); ++f) {
        if (keep && !keep(static_cast<int>(e), static_cast<int>(f))) continue;
        const Face& face = elements[e][f];
        key_pool.insert(key_pool.end(), face.begin(), face.end());
        std::sort(key_pool.end() - face.size(), key_pool.end());
        key_start[g + 1] = static_cast<int>(key_pool.size());
        refs[g] = {static_cast<int>(e), static_cast<int>(f)};
        uint64_t packed = 0;
        for (size_t k = 0; k < 3; ++k) {
          const int v = k < face.size() ? key_pool[key_start[g] + k] + 1 : 0;  // 0: no id (shorter key)
          packable = packable && v >= 0 && v < (1 << 21);
          packed = (packed << 21) | static_cast<uint64_t>(v & ((1 << 21) - 1));
        }
        prefix[g++] = packed;
      }
    if (!packable) std::fill(prefix.begin(), prefix.end(), 0);
    // Sort by (prefix, face), then runs of equal prefix by the whole key (ties in element order).
    std::vector<std::pair<uint64_t, int>> sorted(num_faces);
    for (int x = 0; x < num_faces; ++x) sorted[x] = {prefix[x], x};
    std::sort(sorted.begin(), sorted.end());
    auto keyLess = [&](const std::pair<uint64_t, int>& p, const std::pair<uint64_t, int>& q) {
      const int x = p.second, y = q.second;
      const int *bx = key_pool.data() + key_start[x], *ex = key_pool.data() + key_start[x + 1],
                *by = key_pool.data() + key_start[y], *ey = key_pool.data() + key_start[y + 1];
      if (std::lexicographical_compare(bx, ex, by, ey)) return true;
      if (std::lexicographical_compare(by, ey, bx, ex)) return false;
      return x < y;  // equal keys in element order
    };
    std::vector<int> order(num_faces);
    for (int k = 0; k < num_faces;) {
      int end = k + 1;
      while (end < num_faces && sorted[end].first == sorted[k].first) ++end;
      if (end - k > 1 &&
          !(end - k == 2 && key_start[sorted[k].second + 1] - key_start[sorted[k].second] == 3 &&
            key_start[sorted[k + 1].second + 1] - key_start[sorted[k + 1].second] == 3))
        std::sort(sorted.begin() + k, sorted.begin() + end, keyLess);  // two triangles: already in order
      for (; k < end; ++k) order[k] = sorted[k].second;
    }
    users_.reserve(num_faces);
    keys_.reserve(key_pool.size());
    group_start_.reserve(num_faces / 2 + 2);
    key_start_.reserve(num_faces / 2 + 2);
    for (int k = 0; k < num_faces; ++k) {
      const int x = order[k];
      const bool same = k > 0 && prefix[x] == prefix[order[k - 1]] &&
                        std::equal(key_pool.begin() + key_start[x], key_pool.begin() + key_start[x + 1],
                                   key_pool.begin() + key_start[order[k - 1]],
                                   key_pool.begin() + key_start[order[k - 1] + 1]);
      if (!same) {
        group_start_.push_back(static_cast<int>(users_.size()));
        key_start_.push_back(static_cast<int>(keys_.size()));
        keys_.insert(keys_.end(), key_pool.begin() + key_start[x], key_pool.begin() + key_start[x + 1]);
      }
      users_.push_back(refs[x]);
    }
    group_start_.push_back(static_cast<int>(users_.size()));
    key_start_.push_back(static_cast<int>(keys_.size()));
  }

  int size() const { return static_cast<int>(group_start_.size()) - 1; }
  int numUsers(int g) const { return group_start_[g + 1] - group_start_[g]; }
  const std::pair<int, int>& user(int g, int k) const { return users_[group_start_[g] + k]; }
  const int* keyBegin(int g) const { return keys_.data() + key_start_[g]; }
  const int* keyEnd(int g) const { return keys_.data() + key_start_[g + 1]; }

 private:
  std::vector<std::pair<int, int>> users_;
  std::vector<int> group_start_, keys_, key_start_;
};

}  // namespace

ProgressiveCutMesh::ProgressiveCutMesh(const PolyhedralMesh& mesh, std::vector<Vec3> displacements,
                                       const PolygonCutOptions& options)
    : nodes_(mesh.nodes()),
      displacements_(std::move(displacements)),
      num_initial_nodes_(mesh.numNodes()),
      slivers_(options.slivers) {
  if (!displacements_.empty() && static_cast<int>(displacements_.size()) != mesh.numNodes())
    fail("displacements has " + std::to_string(displacements_.size()) + " entries, the mesh has " +
         std::to_string(mesh.numNodes()) + " nodes");
  if (!(options.snap_relative_distance >= 0.0) || !std::isfinite(options.snap_relative_distance))
    fail("snap_relative_distance must be finite and >= 0");
  for (int e = 0; e < mesh.numElements(); ++e) {
    elements_.push_back(mesh.elementFaces(e));
    crack_.emplace_back(elements_.back().size(), 0);
    for (size_t f = 0; f < elements_.back().size(); ++f)
      crack_.back()[f] = mesh.isCrackFace(e, int(f)) ? 1 : 0;
    const ConvexPolyhedron& element = mesh.element(e);
    relative_tolerance_ = std::max(relative_tolerance_, element.tolerance() / element.scale());
  }
  duplicate_of_.assign(nodes_.size(), -1);
  num_input_elements_ = mesh.numElements();
  input_element_.resize(num_input_elements_);
  std::iota(input_element_.begin(), input_element_.end(), 0);
  snap_distance_ = options.snap_relative_distance * boundingDiagonal(nodes_);
}

int ProgressiveCutMesh::addNode(const Vec3& x, NodeStencil stencil) {
  nodes_.push_back(x);
  if (!displacements_.empty()) {
    Vec3 u = Vec3::Zero();
    for (const auto& [v, w] : stencil) u += w * displacements_[v];
    displacements_.push_back(u);
  }
  stencils_.push_back(std::move(stencil));
  duplicate_of_.push_back(-1);
  return static_cast<int>(nodes_.size()) - 1;
}

std::vector<Vec3> ProgressiveCutMesh::interpolateNodeValues(const std::vector<Vec3>& initial_values) const {
  if (static_cast<int>(initial_values.size()) != num_initial_nodes_)
    fail("interpolateNodeValues: " + std::to_string(initial_values.size()) + " values for " +
         std::to_string(num_initial_nodes_) + " initial nodes");
  std::vector<Vec3> values(initial_values);
  values.reserve(nodes_.size());
  for (const NodeStencil& stencil : stencils_) {
    Vec3 x = Vec3::Zero();
    for (const auto& [v, w] : stencil) x += w * values[v];
    values.push_back(x);
  }
  return values;
}

std::vector<PolygonCutStats> ProgressiveCutMesh::cutSurface(const std::vector<std::vector<Vec3>>& polygons) {
  std::vector<PolygonCutStats> stats;
  for (const auto& polygon : polygons) stats.push_back(cut(polygon));
  return stats;
}

namespace {

// The cut shape: plane, in-plane frame (e1, e2, normal right-handed) and counter-clockwise 2D polygon.
struct CutPolygon {
  Vec3 normal = Vec3::Zero(), center = Vec3::Zero(), e1, e2;
  std::vector<Vec2> shape;

  Vec2 planar(const Vec3& x) const { return Vec2(e1.dot(x - center), e2.dot(x - center)); }
  int numLines() const { return static_cast<int>(shape.size()); }
  // Signed distance to polygon edge line k, positive inside.
  double lineDistance(int k, const Vec2& x) const {
    const Vec2 d = (shape[(k + 1) % numLines()] - shape[k]).normalized();
    return cross2(d, x - shape[k]);
  }
};

Vec2 alreadyPlanar(const Vec2& offset) {
  return offset;
}

// Checks the polygon (>= 3 finite, coplanar points, convex) and builds its plane and 2D shape.
CutPolygon makeCutPolygon(const std::vector<Vec3>& polygon) {
  if (polygon.size() < 3)
    fail("the cut polygon needs at least 3 points, got " + std::to_string(polygon.size()));
  CutPolygon cut;
  Vec3& normal = cut.normal;
  Vec3& center = cut.center;
  for (size_t k = 0; k < polygon.size(); ++k) {
    if (!polygon[k].allFinite()) fail("cut polygon point " + std::to_string(k) + " is not finite");
    normal += polygon[k].cross(polygon[(k + 1) % polygon.size()]);  // Newell
    center += polygon[k];
  }
  center /= static_cast<double>(polygon.size());
  const double polygon_scale = boundingDiagonal(polygon);
  if (!(normal.norm() > 1e-12 * polygon_scale * polygon_scale)) fail("the cut polygon has zero area");
  normal.normalize();
  for (size_t k = 0; k < polygon.size(); ++k)
    if (std::abs(normal.dot(polygon[k] - center)) > 1e-9 * polygon_scale)
      fail("cut polygon point " + std::to_string(k) + " is not in the polygon's plane");
  cut.e1 = normal.unitOrthogonal();
  cut.e2 = normal.cross(cut.e1);
  for (const Vec3& p : polygon) cut.shape.push_back(cut.planar(p));
  const double area_tolerance = 1e-12 * polygon_scale * polygon_scale;
  if (!isConvexPolygon(cut.shape, area_tolerance, area_tolerance)) fail("the cut polygon is not convex");
  if (signedArea(cut.shape) < 0.0) std::reverse(cut.shape.begin(), cut.shape.end());
  return cut;
}

// Element pieces of a face in the cutting plane (face's orientation; 1: inside the polygon, a crack face).
using FacePieces = std::vector<std::pair<Face, char>>;

// Earlier pieces get the nodes later lines put on their edges (no T-junctions inside the face).
void refinePieces(const std::map<std::pair<int, int>, int>& split_segment, FacePieces& pieces) {
  std::function<void(int, int, Face&)> appendSplits = [&](int a, int b, Face& out) {
    auto it = split_segment.find({std::min(a, b), std::max(a, b)});
    if (it == split_segment.end()) return;
    const int m = it->second;
    appendSplits(a, m, out);
    out.push_back(m);
    appendSplits(m, b, out);
  };
  for (auto& piece : pieces) {
    Face refined;
    for (size_t k = 0; k < piece.first.size(); ++k) {
      refined.push_back(piece.first[k]);
      appendSplits(piece.first[k], piece.first[(k + 1) % piece.first.size()], refined);
    }
    piece.first = std::move(refined);
  }
}

}  // namespace

// State of one cut shared by its phases.
struct ProgressiveCutMesh::CutState {
  CutPolygon polygon;
  int first_new_node = 0;
  std::vector<double> distance;         // per node: signed distance to the cutting plane
  std::vector<int> side;                // per node: -1, 0 (within the snap distance), +1
  std::vector<char> crossed, selected;  // per element before the split: crossed, split
  std::vector<int> parent;              // per element after the split: its element before
  // New nodes on mesh edges (a < b), inserted into every face using the edge.
  std::map<std::pair<int, int>, std::vector<int>> edge_refinement;
  std::map<std::tuple<int, int, int>, int> clip_node;  // (segment end, segment end, line) -> node
  PolygonCutStats stats;
};

// Elements after the plane split, before they replace elements_.
struct ProgressiveCutMesh::CutElements {
  std::vector<ElementFaces> elements;
  std::vector<std::vector<char>> crack;
  std::vector<int> input_element;
  std::set<std::vector<int>> split_faces;  // sorted node ids of the faces the plane split
  double max_snapped_distance = 0.0, min_part_scale = INFINITY;
};

PolygonCutStats ProgressiveCutMesh::cut(const std::vector<Vec3>& polygon) {
  components_.clear();
  CutState cut;
  cut.polygon = makeCutPolygon(polygon);
  cut.first_new_node = numNodes();
  selectCrossedElements(cut);
  splitByPlane(cut);
  splitFacesInPlane(cut);
  insertEdgeNodes(cut);

  // Duplicate nodes the crack separates; crack faces that cannot open get a centroid node (pocket).
  PolygonCutStats& stats = cut.stats;
  duplicateSeparatedNodes(stats);
  stats.num_pocket_nodes = openClosedCracks();
  if (stats.num_pocket_nodes > 0) duplicateSeparatedNodes(stats);

  removeSliversOfCut(cut);
  return stats;
}

// 9.3.1 split of every element crossed by the plane whose section overlaps the cut shape: marks them.
void ProgressiveCutMesh::selectCrossedElements(CutState& cut) const {
  const CutPolygon& shape = cut.polygon;
  const double snap = snap_distance_;
  std::vector<double>& distance = cut.distance;
  std::vector<int>& side = cut.side;
  distance.resize(nodes_.size());
  side.resize(nodes_.size());
  for (size_t i = 0; i < nodes_.size(); ++i) {
    distance[i] = shape.normal.dot(nodes_[i] - shape.center);
    side[i] = std::abs(distance[i]) <= snap ? 0 : (distance[i] > 0.0 ? 1 : -1);
  }
  const int num_elements = numElements();
  cut.crossed.assign(num_elements, 0);
  cut.selected.assign(num_elements, 0);
  for (int e = 0; e < num_elements; ++e) {
    const ElementSides sides = elementSides(elements_[e], side);
    if (!sides.positive && !sides.negative)
      throw std::runtime_error("ProgressiveCutMesh: element " + std::to_string(e) +
                               " lies within the snap distance of the cutting plane");
    cut.crossed[e] = sides.crossed();
    if (!cut.crossed[e]) continue;
    std::vector<Vec2> points;  // element section
    for (const Vec3& x : planeSectionPoints(elements_[e], side, distance, nodes_))
      points.push_back(shape.planar(x));
    std::vector<Vec2> section;
    for (int k : counterClockwiseOrder(points, alreadyPlanar)) section.push_back(points[k]);
    cut.selected[e] = convexPolygonsOverlap(section, shape.shape, snap);
  }
}

// The selected elements split into their two parts (9.3.1); crossed elements left whole split their faces
// shared with split elements alike.
void ProgressiveCutMesh::splitByPlane(CutState& cut) {
  // New nodes on mesh edges (plane crossings and polygon edges in the plane), inserted into every face
  // using the edge (T-junctions, 9.3.1).
  EdgeCrossingNodes plane_crossing(cut.distance, [&](int a, int b, double t) {
    const int id = addNode((1.0 - t) * nodes_[a] + t * nodes_[b], {{a, 1.0 - t}, {b, t}});
    cut.distance.push_back(0.0);
    cut.side.push_back(0);
    cut.edge_refinement[{a, b}].push_back(id);
    ++cut.stats.num_new_nodes;
    return id;
  });
  CutElements split = splitSelectedElements(cut, plane_crossing);
  splitSharedFacesOfWholeElements(cut, plane_crossing, split);
  elements_ = std::move(split.elements);
  crack_ = std::move(split.crack);
  input_element_ = std::move(split.input_element);
  if (split.max_snapped_distance > 0.0 && std::isfinite(split.min_part_scale))
    relative_tolerance_ =
        std::max(relative_tolerance_, 4.0 * split.max_snapped_distance / split.min_part_scale);
}

ProgressiveCutMesh::CutElements ProgressiveCutMesh::splitSelectedElements(CutState& cut,
                                                                          EdgeCrossingNodes& plane_crossing) {
  auto sectionOrder = [&](const std::vector<int>& section_nodes) {
    std::vector<Vec2> points;
    for (int v : section_nodes) points.push_back(cut.polygon.planar(nodes_[v]));
    return counterClockwiseOrder(points, alreadyPlanar);
  };
  CutElements out;
  for (int e = 0; e < static_cast<int>(cut.selected.size()); ++e) {
    if (!cut.selected[e]) {
      out.elements.push_back(std::move(elements_[e]));
      out.crack.push_back(std::move(crack_[e]));
      cut.parent.push_back(e);
      out.input_element.push_back(input_element_[e]);
      continue;
    }
    ++cut.stats.num_split_elements;
    const ElementFaces& faces = elements_[e];
    ElementSplit split = splitElement(faces, cut.side, plane_crossing, sectionOrder);
    if (split.face_in_plane >= 0)
      throw std::runtime_error("ProgressiveCutMesh: face " + std::to_string(split.face_in_plane) +
                               " of element " + std::to_string(e) +
                               " lies in the cutting plane but the element is crossed");
    for (int v : split.section)
      out.max_snapped_distance = std::max(out.max_snapped_distance, std::abs(cut.distance[v]));
    for (int f : split.split_faces) out.split_faces.insert(sortedFaceKey(faces[f]));
    // Crack flags follow the faces; the section is no crack face.
    auto crackFlags = [&](const std::vector<int>& source) {
      std::vector<char> flags;
      for (int f : source) flags.push_back(f >= 0 ? crack_[e][f] : 0);
      return flags;
    };
    std::vector<char> negative_crack = crackFlags(split.negative_source),
                      positive_crack = crackFlags(split.positive_source);
    for (const ElementFaces* part : {&split.negative, &split.positive}) {
      std::vector<Vec3> points;
      for (const Face& face : *part)
        for (int v : face) points.push_back(nodes_[v]);
      out.min_part_scale = std::min(out.min_part_scale, boundingDiagonal(points));
    }
    out.elements.push_back(std::move(split.negative));
    out.crack.push_back(std::move(negative_crack));
    out.elements.push_back(std::move(split.positive));
    out.crack.push_back(std::move(positive_crack));
    cut.parent.push_back(e);
    cut.parent.push_back(e);
    out.input_element.push_back(-1);
    out.input_element.push_back(-1);
  }
  return out;
}

// Crossed elements left whole split their faces shared with split elements alike (coplanar faces).
void ProgressiveCutMesh::splitSharedFacesOfWholeElements(const CutState& cut,
                                                         EdgeCrossingNodes& plane_crossing,
                                                         CutElements& split) const {
  for (size_t e = 0; e < split.elements.size(); ++e) {
    const int p = cut.parent[e];
    if (cut.selected[p] || !cut.crossed[p]) continue;
    ElementFaces faces;
    std::vector<char> flags;
    for (size_t f = 0; f < split.elements[e].size(); ++f) {
      const Face& face = split.elements[e][f];
      if (!split.split_faces.count(sortedFaceKey(face))) {
        faces.push_back(face);
        flags.push_back(split.crack[e][f]);
        continue;
      }
      split.input_element[e] = -1;
      FaceSplit halves = splitFace(face, cut.side, plane_crossing);
      faces.push_back(std::move(halves.positive));
      faces.push_back(std::move(halves.negative));
      flags.push_back(split.crack[e][f]);
      flags.push_back(split.crack[e][f]);
    }
    split.elements[e] = std::move(faces);
    split.crack[e] = std::move(flags);
  }
}

// 9.3.2: faces in the cutting plane shared by two elements are split along the polygon edges into convex
// pieces (sequential clipping by the edge lines); pieces inside the polygon become crack faces.
void ProgressiveCutMesh::splitFacesInPlane(CutState& cut) {
  std::map<std::pair<int, int>, FacePieces> replacement;  // (element, face)
  const std::vector<int>& side = cut.side;
  const FaceGroups groups = FaceGroups(elements_, [&](int e, int f) {
    for (int v : elements_[e][f])
      if (side[v] != 0) return false;
    return true;
  });  // faces in the plane only
  for (int g = 0; g < groups.size(); ++g) {
    if (groups.numUsers(g) != 2) continue;
    const auto [e0, f0] = groups.user(g, 0);
    const auto [e1, f1] = groups.user(g, 1);
    const Face face = elements_[e0][f0];
    bool in_plane = true;
    for (int v : face) in_plane = in_plane && side[v] == 0;
    if (!in_plane || crack_[e0][f0] || crack_[e1][f1]) continue;
    std::vector<Vec2> face2;
    for (int v : face) face2.push_back(cut.polygon.planar(nodes_[v]));
    if (!convexPolygonsOverlap(face2, cut.polygon.shape, snap_distance_)) continue;
    const FacePieces pieces = clipFaceByPolygon(cut, face);
    FacePieces reversed;
    for (const auto& piece : pieces) {
      reversed.emplace_back(Face(piece.first.rbegin(), piece.first.rend()), piece.second);
      cut.stats.num_new_crack_faces += 2 * piece.second;
    }
    // Pieces are in face's (element e0's) orientation; e1 uses the face reversed.
    replacement[{e0, f0}] = pieces;
    replacement[{e1, f1}] = reversed;
  }
  for (int e = 0; e < numElements(); ++e) {
    bool changed = false;
    for (size_t f = 0; f < elements_[e].size() && !changed; ++f) changed = replacement.count({e, int(f)}) > 0;
    if (!changed) continue;
    input_element_[e] = -1;
    ElementFaces faces;
    std::vector<char> flags;
    for (size_t f = 0; f < elements_[e].size(); ++f) {
      auto it = replacement.find({e, int(f)});
      if (it == replacement.end()) {
        faces.push_back(elements_[e][f]);
        flags.push_back(crack_[e][f]);
        continue;
      }
      for (const auto& piece : it->second) {
        faces.push_back(piece.first);
        flags.push_back(piece.second);
      }
    }
    elements_[e] = std::move(faces);
    crack_[e] = std::move(flags);
  }
}

// Clips a face in the plane by the polygon's edge lines in turn: the part outside each line is a piece, the
// part inside all of them the crack piece. New nodes on the face's edges are recorded for all faces using
// the edge.
std::vector<std::pair<PolyhedralMesh::Face, char>> ProgressiveCutMesh::clipFaceByPolygon(CutState& cut,
                                                                                         const Face& face) {
  const double snap = snap_distance_;
  // Original face edges each node lies on (to insert polygon-edge nodes into all faces using the edge).
  std::map<int, std::vector<int>> on_edges;
  const int num_corners = static_cast<int>(face.size());
  for (int i = 0; i < num_corners; ++i) {
    on_edges[face[i]] = {(i + num_corners - 1) % num_corners, i};
    std::sort(on_edges[face[i]].begin(), on_edges[face[i]].end());
  }
  FacePieces pieces;
  std::map<std::pair<int, int>, int> split_segment;  // segment of a piece -> node splitting it
  Face remaining = face;
  for (int k = 0; k < cut.polygon.numLines() && !remaining.empty(); ++k) {
    std::vector<double> d;
    std::vector<int> s;
    bool any_inside = false, any_outside = false;
    for (int v : remaining) {
      d.push_back(cut.polygon.lineDistance(k, cut.polygon.planar(nodes_[v])));
      s.push_back(d.back() > snap ? 1 : (d.back() < -snap ? -1 : 0));
      any_inside = any_inside || s.back() > 0;
      any_outside = any_outside || s.back() < 0;
    }
    if (!any_outside) continue;
    if (!any_inside) {
      pieces.emplace_back(remaining, 0);
      remaining.clear();
      break;
    }
    Face inside, outside;
    for (size_t j = 0; j < remaining.size(); ++j) {
      const size_t jn = (j + 1) % remaining.size();
      const int a = remaining[j], b = remaining[jn];
      if (s[j] >= 0) inside.push_back(a);
      if (s[j] <= 0) outside.push_back(a);
      if (s[j] * s[jn] >= 0) continue;
      const auto key = std::make_tuple(std::min(a, b), std::max(a, b), k);
      auto it = cut.clip_node.find(key);
      int m;
      std::vector<int> edges;
      std::set_intersection(on_edges[a].begin(), on_edges[a].end(), on_edges[b].begin(), on_edges[b].end(),
                            std::back_inserter(edges));
      if (it != cut.clip_node.end()) {
        m = it->second;
      } else {
        const double t = d[j] / (d[j] - d[jn]);
        const Vec3 x = (1.0 - t) * nodes_[a] + t * nodes_[b];
        m = addNode(x, edges.empty() ? faceStencil(nodes_, face, x) : NodeStencil{{a, 1.0 - t}, {b, t}});
        cut.distance.push_back(0.0);
        cut.side.push_back(0);
        cut.clip_node.emplace(key, m);
        ++cut.stats.num_new_nodes;
      }
      split_segment[{std::min(a, b), std::max(a, b)}] = m;
      on_edges[m] = edges;
      for (int i : edges) {
        const int u0 = face[i], u1 = face[(i + 1) % num_corners];
        cut.edge_refinement[std::make_pair(std::min(u0, u1), std::max(u0, u1))].push_back(m);
      }
      inside.push_back(m);
      outside.push_back(m);
    }
    pieces.emplace_back(outside, 0);
    remaining = inside;
  }
  if (!remaining.empty()) pieces.emplace_back(remaining, 1);
  refinePieces(split_segment, pieces);
  return pieces;
}

// New edge nodes go into every face that still uses the whole edge.
void ProgressiveCutMesh::insertEdgeNodes(CutState& cut) {
  std::map<std::pair<int, int>, std::vector<int>>& edge_refinement = cut.edge_refinement;
  for (auto& entry : edge_refinement) {
    auto& ids = entry.second;
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  }
  std::vector<char> refined_edge_end(nodes_.size(), 0);  // faces without such a node keep their edges
  for (const auto& entry : edge_refinement) {
    refined_edge_end[entry.first.first] = 1;
    refined_edge_end[entry.first.second] = 1;
  }
  Face refined;
  std::vector<std::pair<double, int>> along;
  for (int e = 0; e < numElements(); ++e)
    for (Face& face : elements_[e]) {
      int ends = 0;
      for (int v : face) ends += refined_edge_end[v];
      if (ends < 2) continue;
      refined.clear();
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        refined.push_back(a);
        if (!refined_edge_end[a] || !refined_edge_end[b]) continue;
        auto it = edge_refinement.find({std::min(a, b), std::max(a, b)});
        if (it == edge_refinement.end()) continue;
        along.clear();
        for (int m : it->second)
          if (m != a && m != b) along.emplace_back((nodes_[m] - nodes_[a]).dot(nodes_[b] - nodes_[a]), m);
        std::sort(along.begin(), along.end());
        for (const auto& entry : along) refined.push_back(entry.second);
      }
      if (refined.size() == face.size()) continue;
      face = refined;
      input_element_[e] = -1;
    }
}

// Thin parts of the split elements are merged into their neighbours (9.2, local to the cut).
void ProgressiveCutMesh::removeSliversOfCut(CutState& cut) {
  PolygonCutStats& stats = cut.stats;
  if (!slivers_.enabled || stats.num_split_elements == 0) return;
  std::vector<int> candidates;
  for (size_t e = 0; e < cut.parent.size(); ++e)
    if (cut.selected[cut.parent[e]]) candidates.push_back(static_cast<int>(e));
  EditableMesh edit{std::move(nodes_), std::move(displacements_), std::move(elements_), std::move(crack_)};
  CutSliverEdits edits;
  stats.slivers =
      removeCutSlivers(edit, candidates, cut.first_new_node, relative_tolerance_, slivers_, &edits);
  nodes_ = std::move(edit.nodes);
  displacements_ = std::move(edit.displacements);
  elements_ = std::move(edit.elements);
  crack_ = std::move(edit.crack_faces);
  std::vector<int> input_element(edits.kept_elements.size());
  for (size_t e = 0; e < edits.kept_elements.size(); ++e)
    input_element[e] = input_element_[edits.kept_elements[e]];
  input_element_ = std::move(input_element);
  for (NodeStencil& stencil : edits.new_node_stencils) {
    stencils_.push_back(std::move(stencil));
    duplicate_of_.push_back(-1);
  }
  relative_tolerance_ = std::max(relative_tolerance_, stats.slivers.relative_tolerance);
}

void ProgressiveCutMesh::duplicateSeparatedNodes(PolygonCutStats& stats) {
  const int n = numNodes();
  std::vector<std::vector<int>> incident(n);
  for (int e = 0; e < numElements(); ++e)
    for (const Face& face : elements_[e])
      for (int v : face)
        if (incident[v].empty() || incident[v].back() != e) incident[v].push_back(e);
  for (auto& list : incident) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  // Per node: elements around it joined through shared non-crack faces containing it.
  std::vector<DisjointSets> groups;
  groups.reserve(n);
  for (int v = 0; v < n; ++v) groups.emplace_back(static_cast<int>(incident[v].size()));
  auto position = [&](int v, int e) {
    return static_cast<int>(std::lower_bound(incident[v].begin(), incident[v].end(), e) -
                            incident[v].begin());
  };
  const FaceGroups faces = FaceGroups(elements_);
  for (int g = 0; g < faces.size(); ++g) {
    if (faces.numUsers(g) != 2) continue;
    const auto [e0, f0] = faces.user(g, 0);
    const auto [e1, f1] = faces.user(g, 1);
    if (crack_[e0][f0] || crack_[e1][f1]) continue;
    for (const int* v = faces.keyBegin(g); v != faces.keyEnd(g); ++v)
      groups[*v].unite(position(*v, e0), position(*v, e1));
  }
  for (int v = 0; v < n; ++v) {
    std::map<int, int> copy_of_group;  // group root -> node
    for (size_t i = 0; i < incident[v].size(); ++i) {
      const int root = groups[v].find(static_cast<int>(i));
      if (root == 0) continue;  // the group of the first element keeps v
      auto it = copy_of_group.find(root);
      if (it == copy_of_group.end()) {
        const int copy = addNode(Vec3(nodes_[v]), {{v, 1.0}});
        duplicate_of_[copy] = duplicate_of_[v] >= 0 ? duplicate_of_[v] : v;
        ++stats.num_duplicated_nodes;
        it = copy_of_group.emplace(root, copy).first;
      }
      for (Face& face : elements_[incident[v][i]])
        for (int& w : face)
          if (w == v) w = it->second;
    }
  }
}

int ProgressiveCutMesh::openClosedCracks() {
  int num_pockets = 0;
  const FaceGroups groups = FaceGroups(elements_, [&](int e, int f) { return crack_[e][f] != 0; });
  for (int g = 0; g < groups.size(); ++g) {
    if (groups.numUsers(g) != 2) continue;
    const auto [e0, f0] = groups.user(g, 0);
    const auto [e1, f1] = groups.user(g, 1);
    if (!crack_[e0][f0] || !crack_[e1][f1]) continue;
    const Face face = elements_[e0][f0];
    Vec3 centroid = Vec3::Zero();
    for (int v : face) centroid += nodes_[v];
    centroid /= static_cast<double>(face.size());
    const int c = addNode(centroid, faceStencil(nodes_, face, centroid));
    ++num_pockets;
    for (const auto& [e, f] : {groups.user(g, 0), groups.user(g, 1)}) {
      const Face polygon = elements_[e][f];
      ElementFaces faces;
      std::vector<char> flags;
      for (size_t g = 0; g < elements_[e].size(); ++g)
        if (static_cast<int>(g) != f) {
          faces.push_back(elements_[e][g]);
          flags.push_back(crack_[e][g]);
        }
      for (size_t k = 0; k < polygon.size(); ++k) {
        faces.push_back({c, polygon[k], polygon[(k + 1) % polygon.size()]});
        flags.push_back(1);
      }
      elements_[e] = std::move(faces);
      crack_[e] = std::move(flags);
      input_element_[e] = -1;
    }
  }
  return num_pockets;
}

int ProgressiveCutMesh::numCrackFaces() const {
  int count = 0;
  for (const auto& flags : crack_)
    for (char flag : flags) count += flag != 0;
  return count;
}

int ProgressiveCutMesh::numDuplicatedNodes() const {
  return static_cast<int>(
      std::count_if(duplicate_of_.begin(), duplicate_of_.end(), [](int d) { return d >= 0; }));
}

double ProgressiveCutMesh::volume() const {
  double total = 0.0;
  for (const ElementFaces& faces : elements_)
    for (const Face& face : faces)
      for (size_t k = 1; k + 1 < face.size(); ++k)
        total += nodes_[face[0]].dot(nodes_[face[k]].cross(nodes_[face[k + 1]])) / 6.0;
  return total;
}

void ProgressiveCutMesh::validate() const {
  auto error = [](const std::string& what) { throw std::logic_error("ProgressiveCutMesh: " + what); };
  double element_volume = 0.0;
  for (int e = 0; e < numElements(); ++e) {
    std::vector<int> ids, local(nodes_.size(), -1);
    std::vector<ConvexPolyhedron::Face> faces;
    for (const Face& face : elements_[e]) {
      ConvexPolyhedron::Face local_face;
      for (int v : face) {
        if (v < 0 || v >= numNodes())
          error("element " + std::to_string(e) + " references node " + std::to_string(v));
        if (local[v] < 0) {
          local[v] = static_cast<int>(ids.size());
          ids.push_back(v);
        }
        local_face.push_back(local[v]);
      }
      faces.push_back(local_face);
    }
    std::vector<Vec3> points;
    for (int v : ids) points.push_back(nodes_[v]);
    try {
      element_volume += ConvexPolyhedron(points, faces, relative_tolerance_, ids).volume();
    } catch (const std::invalid_argument& problem) {
      error("element " + std::to_string(e) + ": " + problem.what());
    }
  }
  std::map<std::pair<int, int>, int> boundary_edges;
  double enclosed = 0.0;
  const FaceGroups groups = FaceGroups(elements_);
  for (int g = 0; g < groups.size(); ++g) {
    const std::pair<int, int> first = groups.user(g, 0);
    auto name = [&]() {
      return "element " + std::to_string(first.first) + " face " + std::to_string(first.second);
    };
    if (groups.numUsers(g) > 2) error(name() + " is used by more than two elements");
    if (groups.numUsers(g) == 2) {
      const std::pair<int, int> second = groups.user(g, 1);
      const Face& a = elements_[first.first][first.second];
      const Face& b = elements_[second.first][second.second];
      const int p = static_cast<int>(std::find(b.begin(), b.end(), a[0]) - b.begin());
      for (size_t j = 0; j < a.size(); ++j)
        if (b[(p - int(j) + int(b.size()) * 2) % b.size()] != a[j])
          error(name() + " and its neighbour do not use the face in opposite order");
      const bool crack_a = crack_[first.first][first.second], crack_b = crack_[second.first][second.second];
      if (crack_a || crack_b) error(name() + " is a crack face whose two sides still share all nodes");
      continue;
    }
    const Face& face = elements_[first.first][first.second];
    for (size_t k = 0; k < face.size(); ++k) {
      const auto edge = std::make_pair(face[k], face[(k + 1) % face.size()]);
      if (++boundary_edges[edge] > 1)
        error("boundary edge (" + std::to_string(edge.first) + ", " + std::to_string(edge.second) +
              ") is used twice in the same direction");
    }
    for (size_t k = 1; k + 1 < face.size(); ++k)
      enclosed += nodes_[face[0]].dot(nodes_[face[k]].cross(nodes_[face[k + 1]])) / 6.0;
  }
  for (const auto& entry : boundary_edges)
    if (!boundary_edges.count({entry.first.second, entry.first.first}))
      error("the boundary is not closed at edge (" + std::to_string(entry.first.first) + ", " +
            std::to_string(entry.first.second) + ")");
  if (std::abs(enclosed - element_volume) > 1e-9 * element_volume)
    error("element volumes sum to " + std::to_string(element_volume) + " but the boundary encloses " +
          std::to_string(enclosed));
}

std::vector<int> ProgressiveCutMesh::elementComponents(int* num_components) const {
  if (static_cast<int>(components_.size()) == numElements()) {  // unchanged since the last call
    if (num_components) *num_components = num_components_;
    return components_;
  }
  DisjointSets sets(numElements());
  const FaceGroups groups = FaceGroups(elements_);
  for (int g = 0; g < groups.size(); ++g) {
    if (groups.numUsers(g) != 2) continue;
    const auto [e0, f0] = groups.user(g, 0);
    const auto [e1, f1] = groups.user(g, 1);
    if (!crack_[e0][f0] && !crack_[e1][f1]) sets.unite(e0, e1);
  }
  std::map<int, int> label;
  std::vector<int> component(numElements());
  for (int e = 0; e < numElements(); ++e)
    component[e] = label.emplace(sets.find(e), static_cast<int>(label.size())).first->second;
  components_ = component;
  num_components_ = static_cast<int>(label.size());
  if (num_components) *num_components = num_components_;
  return component;
}

int ProgressiveCutMesh::numComponents() const {
  int count = 0;
  elementComponents(&count);
  return count;
}

PolyhedralMesh ProgressiveCutMesh::componentMesh(int c, std::vector<int>* node_ids,
                                                 const PolyhedralMesh* input) const {
  int count = 0;
  const std::vector<int> component = elementComponents(&count);
  if (c < 0 || c >= count)
    throw std::invalid_argument("ProgressiveCutMesh::componentMesh: component " + std::to_string(c) +
                                " out of range (" + std::to_string(count) + " components)");
  if (input && input->numElements() != num_input_elements_)
    throw std::invalid_argument("ProgressiveCutMesh::componentMesh: the input mesh has " +
                                std::to_string(input->numElements()) +
                                " elements, this mesh was built from " + std::to_string(num_input_elements_));
  std::vector<const ConvexPolyhedron*> prebuilt;
  std::vector<int> local(nodes_.size(), -1), ids;
  std::vector<ElementFaces> elements;
  std::vector<PolyhedralMesh::FaceRef> crack_faces;
  for (int e = 0; e < numElements(); ++e) {
    if (component[e] != c) continue;
    for (size_t f = 0; f < crack_[e].size(); ++f)
      if (crack_[e][f]) crack_faces.emplace_back(static_cast<int>(elements.size()), static_cast<int>(f));
    ElementFaces faces = elements_[e];
    for (Face& face : faces)
      for (int& v : face) {
        if (local[v] < 0) {
          local[v] = static_cast<int>(ids.size());
          ids.push_back(v);
        }
        v = local[v];
      }
    elements.push_back(std::move(faces));
    if (input) prebuilt.push_back(input_element_[e] >= 0 ? &input->element(input_element_[e]) : nullptr);
  }
  std::vector<Vec3> points;
  for (int v : ids) points.push_back(nodes_[v]);
  if (node_ids) *node_ids = ids;
  try {
    return PolyhedralMesh(std::move(points), std::move(elements), relative_tolerance_, std::move(crack_faces),
                          prebuilt);
  } catch (const std::invalid_argument& problem) {
    throw std::invalid_argument("ProgressiveCutMesh::componentMesh: component " + std::to_string(c) +
                                " is not a valid PolyhedralMesh: " + problem.what());
  }
}

}  // namespace rc
