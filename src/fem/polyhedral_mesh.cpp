#include "relaxed_connectivity/fem/polyhedral_mesh.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include "relaxed_connectivity/fem/polygon_geometry.h"

namespace rc {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("PolyhedralMesh: " + what);
}

// +1: b is the same cycle as a, -1: b is a reversed, 0: neither.
int cyclicRelation(const PolyhedralMesh::Face& a, const PolyhedralMesh::Face& b) {
  const int k = static_cast<int>(a.size());
  if (static_cast<int>(b.size()) != k) return 0;
  const int p = static_cast<int>(std::find(b.begin(), b.end(), a[0]) - b.begin());
  if (p == k) return 0;
  bool same = true, reversed = true;
  for (int j = 0; j < k; ++j) {
    same = same && b[(p + j) % k] == a[j];
    reversed = reversed && b[((p - j) % k + k) % k] == a[j];
  }
  return same ? 1 : (reversed ? -1 : 0);
}

std::string faceName(int element, int face) {
  return "element " + std::to_string(element) + " face " + std::to_string(face);
}

// Interiors of two coplanar triangles (2D corners) overlap by more than tol (separating axis test).
bool trianglesOverlap(const std::array<Eigen::Vector2d, 3>& a, const std::array<Eigen::Vector2d, 3>& b,
                      double tol) {
  for (const auto* tri : {&a, &b})
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d edge = (*tri)[(k + 1) % 3] - (*tri)[k];
      const Eigen::Vector2d axis = Eigen::Vector2d(-edge.y(), edge.x()).normalized();
      double lo_a = INFINITY, hi_a = -INFINITY, lo_b = INFINITY, hi_b = -INFINITY;
      for (int v = 0; v < 3; ++v) {
        lo_a = std::min(lo_a, axis.dot(a[v]));
        hi_a = std::max(hi_a, axis.dot(a[v]));
        lo_b = std::min(lo_b, axis.dot(b[v]));
        hi_b = std::max(hi_b, axis.dot(b[v]));
      }
      if (std::min(hi_a, hi_b) - std::max(lo_a, lo_b) <= tol) return false;
    }
  return true;
}

// Whether `built` is the element this mesh would build from `faces` (global ids; local: global -> local
// id of its nodes ids, in order of first use) with the face triangulations `triangles` (global ids): the
// same nodes bitwise, faces and triangles in local ids.
bool sameBuiltElement(const std::vector<Vec3>& nodes, const ConvexPolyhedron& built,
                      const std::vector<int>& ids, const PolyhedralMesh::ElementFaces& faces,
                      const std::vector<PolyhedralMesh::Triangle>* triangles, const std::vector<int>& local) {
  if (built.numNodes() != static_cast<int>(ids.size()) || built.numFaces() != static_cast<int>(faces.size()))
    return false;
  for (size_t k = 0; k < ids.size(); ++k) {
    const Vec3& a = built.node(static_cast<int>(k));
    const Vec3& b = nodes[ids[k]];
    if (std::memcmp(a.data(), b.data(), sizeof(double) * 3) != 0) return false;
  }
  size_t t = 0;
  for (size_t f = 0; f < faces.size(); ++f) {
    const ConvexPolyhedron::Face& built_face = built.faces()[f];
    if (built_face.size() != faces[f].size()) return false;
    for (size_t j = 0; j < built_face.size(); ++j)
      if (built_face[j] != local[faces[f][j]]) return false;
    for (const PolyhedralMesh::Triangle& tri : triangles[f]) {
      if (t >= built.triangles().size() || built.triangleFace()[t] != static_cast<int>(f)) return false;
      const ConvexPolyhedron::Triangle& b = built.triangles()[t++];
      if (b[0] != local[tri[0]] || b[1] != local[tri[1]] || b[2] != local[tri[2]]) return false;
    }
  }
  return t == built.triangles().size();
}

// Sorted node ids of every face in a flat pool: face g has key_pool[key_start[g] .. key_start[g + 1]).
struct FaceKeys {
  std::vector<int> key_start, key_pool;

  // Shorter keys first, then lexicographic; equal keys in element order.
  bool less(int x, int y) const {
    const int nx = key_start[x + 1] - key_start[x], ny = key_start[y + 1] - key_start[y];
    if (nx != ny) return nx < ny;
    const int cmp =
        std::memcmp(key_pool.data() + key_start[x], key_pool.data() + key_start[y], sizeof(int) * nx);
    return cmp != 0 ? cmp < 0 : x < y;  // equal keys in element order
  }
  bool same(int x, int y) const {
    const int nx = key_start[x + 1] - key_start[x];
    return nx == key_start[y + 1] - key_start[y] &&
           std::equal(key_pool.begin() + key_start[x], key_pool.begin() + key_start[x + 1],
                      key_pool.begin() + key_start[y]);
  }

  // Equal keys adjacent, in element order: sorted by a 64-bit prefix of the first three ids (decides most
  // comparisons), runs of equal prefix by the whole key.
  std::vector<int> sortedOrder() const {
    const int num_faces = static_cast<int>(key_start.size()) - 1;
    std::vector<std::pair<uint64_t, int>> prefixed(num_faces);
    bool packable = true;
    for (int g = 0; g < num_faces; ++g) {
      uint64_t packed = 0;
      for (int k = 0; k < 3; ++k) {
        const int v = key_pool[key_start[g] + k] + 1;  // faces have >= 3 nodes
        packable = packable && v < (1 << 21);
        packed = (packed << 21) | static_cast<uint64_t>(v & ((1 << 21) - 1));
      }
      prefixed[g] = {packed, g};
    }
    if (!packable)
      for (auto& entry : prefixed) entry.first = 0;
    std::sort(prefixed.begin(), prefixed.end());
    std::vector<int> order(num_faces);
    for (int k = 0; k < num_faces;) {
      int end = k + 1;
      while (end < num_faces && prefixed[end].first == prefixed[k].first) ++end;
      for (int j = k; j < end; ++j) order[j] = prefixed[j].second;
      if (end - k > 1)
        std::sort(order.begin() + k, order.begin() + end, [this](int x, int y) { return less(x, y); });
      k = end;
    }
    return order;
  }
};

// The same triangles (each up to a cyclic rotation of its nodes), in any order.
bool sameTriangles(const std::vector<PolyhedralMesh::Triangle>& a,
                   const std::vector<PolyhedralMesh::Triangle>& b) {
  auto canonical = [](std::vector<PolyhedralMesh::Triangle> list) {
    for (auto& t : list) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    std::sort(list.begin(), list.end());
    return list;
  };
  return a.size() == b.size() && canonical(a) == canonical(b);
}

}  // namespace

// Faces of all elements by global index g = face_start[e] + f: the element, the face of the element and,
// for an interior face, the other element face using its node set (-1: boundary face).
struct PolyhedralMesh::FaceAdjacency {
  std::vector<int> face_start;  // global face index of (e, 0); one past the last face at the end
  std::vector<int> face_element, face_local, other_user;
};

PolyhedralMesh::PolyhedralMesh(std::vector<Vec3> nodes, std::vector<ElementFaces> elements,
                               double relative_tolerance, std::vector<FaceRef> crack_faces)
    : PolyhedralMesh(std::move(nodes), std::move(elements), relative_tolerance, std::move(crack_faces), {}) {}

PolyhedralMesh::PolyhedralMesh(std::vector<Vec3> nodes, std::vector<ElementFaces> elements,
                               double relative_tolerance, std::vector<FaceRef> crack_faces,
                               const std::vector<const ConvexPolyhedron*>& prebuilt)
    : nodes_(std::move(nodes)), element_faces_(std::move(elements)), crack_faces_(std::move(crack_faces)) {
  build(relative_tolerance, prebuilt);
}

PolyhedralMesh::PolyhedralMesh(std::vector<Vec3> nodes, std::vector<ElementFaces> elements,
                               std::vector<std::vector<std::vector<Triangle>>> face_triangles,
                               double relative_tolerance, std::vector<FaceRef> crack_faces)
    : nodes_(std::move(nodes)),
      element_faces_(std::move(elements)),
      crack_faces_(std::move(crack_faces)),
      given_triangles_(std::move(face_triangles)) {
  if (given_triangles_.size() != element_faces_.size())
    fail("given triangulations for " + std::to_string(given_triangles_.size()) + " elements of " +
         std::to_string(element_faces_.size()));
  for (size_t e = 0; e < given_triangles_.size(); ++e)
    if (!given_triangles_[e].empty() && given_triangles_[e].size() != element_faces_[e].size())
      fail("element " + std::to_string(e) + ": given triangulations for " +
           std::to_string(given_triangles_[e].size()) + " of its " +
           std::to_string(element_faces_[e].size()) + " faces");
  build(relative_tolerance, {});
  given_triangles_ = {};
}

void PolyhedralMesh::build(double relative_tolerance, const std::vector<const ConvexPolyhedron*>& prebuilt) {
  checkInput(prebuilt.size());
  const FaceAdjacency faces = buildFaceAdjacency();
  const std::vector<std::vector<Triangle>> face_triangles =
      buildElements(faces, relative_tolerance, prebuilt);
  const std::vector<char> boundary_triangle_is_crack = buildBoundary(faces, face_triangles);
  checkConformingBoundary(boundary_triangle_is_crack);
  checkVolumes();
}

// Nodes finite and used, faces with >= 3 valid node ids, crack faces existing and listed once (sorted).
void PolyhedralMesh::checkInput(size_t num_prebuilt) {
  const int n = numNodes();
  if (element_faces_.empty()) fail("the mesh has no elements");
  if (num_prebuilt != 0 && num_prebuilt != element_faces_.size())
    fail("the prebuilt list has " + std::to_string(num_prebuilt) + " entries for " +
         std::to_string(element_faces_.size()) + " elements");
  for (int i = 0; i < n; ++i)
    if (!nodes_[i].allFinite()) fail("node " + std::to_string(i) + " is not finite");
  std::vector<char> used(n, 0);
  for (size_t e = 0; e < element_faces_.size(); ++e)
    for (size_t f = 0; f < element_faces_[e].size(); ++f) {
      if (element_faces_[e][f].size() < 3)
        fail(faceName(int(e), int(f)) + " has " + std::to_string(element_faces_[e][f].size()) + " nodes");
      for (int v : element_faces_[e][f]) {
        if (v < 0 || v >= n)
          fail(faceName(int(e), int(f)) + " references node " + std::to_string(v) + " (mesh has " +
               std::to_string(n) + " nodes)");
        used[v] = 1;
      }
    }
  for (int i = 0; i < n; ++i)
    if (!used[i]) fail("node " + std::to_string(i) + " is used by no element");
  std::sort(crack_faces_.begin(), crack_faces_.end());
  for (size_t c = 0; c < crack_faces_.size(); ++c) {
    const auto [e, f] = crack_faces_[c];
    if (e < 0 || e >= static_cast<int>(element_faces_.size()) || f < 0 ||
        f >= static_cast<int>(element_faces_[e].size()))
      fail("crack face (element " + std::to_string(e) + ", face " + std::to_string(f) + ") does not exist");
    if (c > 0 && crack_faces_[c - 1] == crack_faces_[c])
      fail(faceName(e, f) + " is listed twice as crack face");
  }
}

// Faces by node set (sorted node ids in a flat pool): faces sorted by key, equal keys are one face used by
// up to two elements; the first user (element order) triangulates it, the second reverses that.
PolyhedralMesh::FaceAdjacency PolyhedralMesh::buildFaceAdjacency() const {
  FaceAdjacency adjacency;
  std::vector<int>& face_start = adjacency.face_start;
  face_start.assign(element_faces_.size() + 1, 0);
  for (size_t e = 0; e < element_faces_.size(); ++e)
    face_start[e + 1] = face_start[e] + static_cast<int>(element_faces_[e].size());
  const int num_faces = face_start.back();
  std::vector<int>& face_element = adjacency.face_element;
  std::vector<int>& face_local = adjacency.face_local;
  face_element.resize(num_faces);
  face_local.resize(num_faces);
  FaceKeys keys;
  keys.key_start.assign(num_faces + 1, 0);
  for (size_t e = 0; e < element_faces_.size(); ++e)
    for (size_t f = 0; f < element_faces_[e].size(); ++f) {
      const int g = face_start[e] + static_cast<int>(f);
      face_element[g] = static_cast<int>(e);
      face_local[g] = static_cast<int>(f);
      const Face& face = element_faces_[e][f];
      keys.key_pool.insert(keys.key_pool.end(), face.begin(), face.end());
      std::sort(keys.key_pool.end() - face.size(), keys.key_pool.end());
      keys.key_start[g + 1] = static_cast<int>(keys.key_pool.size());
    }
  const std::vector<int> order = keys.sortedOrder();
  std::vector<int>& other_user = adjacency.other_user;  // the other element face of an interior face
  other_user.assign(num_faces, -1);
  // Problems are reported for the first face in element order that shows one (the third user of a face,
  // the second user of a badly oriented pair).
  int error_face = num_faces;
  std::string error;
  auto report = [&](int g, const std::string& message) {
    if (g < error_face) {
      error_face = g;
      error = message;
    }
  };
  auto name = [&](int g) { return faceName(face_element[g], face_local[g]); };
  for (int k = 0; k < num_faces;) {
    int end = k + 1;
    while (end < num_faces && keys.same(order[k], order[end])) ++end;
    const int first = order[k];
    if (end - k > 2) report(order[k + 2], name(order[k + 2]) + " is used by more than two elements");
    if (end - k >= 2) {
      const int second = order[k + 1];
      auto pair = [&]() { return name(second) + " and " + name(first); };
      const int relation = cyclicRelation(element_faces_[face_element[first]][face_local[first]],
                                          element_faces_[face_element[second]][face_local[second]]);
      if (relation == 1)
        report(second, pair() + " have the same orientation (overlapping or inverted elements)");
      if (relation == 0) report(second, pair() + " have the same nodes in a different cyclic order");
      other_user[first] = second;
      other_user[second] = first;
    }
    k = end;
  }
  if (error_face < num_faces) fail(error);
  return adjacency;
}

// One ConvexPolyhedron per element (a matching prebuilt one relabelled, else built and validated). Returns
// per global face its triangles (global ids, in its element's orientation).
std::vector<std::vector<PolyhedralMesh::Triangle>> PolyhedralMesh::buildElements(
    const FaceAdjacency& adjacency, double relative_tolerance,
    const std::vector<const ConvexPolyhedron*>& prebuilt) {
  const std::vector<int>& face_start = adjacency.face_start;
  std::vector<std::vector<Triangle>> face_triangles(face_start.back());
  elements_.reserve(element_faces_.size());
  std::vector<int> local(numNodes(), -1);
  for (size_t e = 0; e < element_faces_.size(); ++e) {
    const ElementFaces& faces = element_faces_[e];
    for (size_t f = 0; f < faces.size(); ++f) {
      const int g = face_start[e] + static_cast<int>(f);
      const int other = adjacency.other_user[g];
      const std::vector<Triangle>* given = givenTriangles(int(e), int(f));
      if (other < 0 || other > g) {
        const std::vector<Triangle>* other_given =
            other < 0 ? nullptr : givenTriangles(adjacency.face_element[other], adjacency.face_local[other]);
        if (given)
          face_triangles[g] = *given;
        else if (other_given)
          for (const Triangle& t : *other_given) face_triangles[g].push_back({t[0], t[2], t[1]});
        else
          face_triangles[g] = bestFanTriangulation(nodes_, faces[f]);
      } else {
        for (const Triangle& t : face_triangles[other]) face_triangles[g].push_back({t[0], t[2], t[1]});
        if (given && !sameTriangles(*given, face_triangles[g]))
          fail("element " + std::to_string(e) + " face " + std::to_string(f) +
               ": its given triangulation differs from the one element " +
               std::to_string(adjacency.face_element[other]) + " gives the shared face");
      }
    }
    // Local nodes in order of first use.
    std::vector<int> ids;
    for (const Face& face : faces)
      for (int v : face)
        if (local[v] < 0) {
          local[v] = static_cast<int>(ids.size());
          ids.push_back(v);
        }
    const ConvexPolyhedron* built = prebuilt.empty() ? nullptr : prebuilt[e];
    if (built && sameBuiltElement(nodes_, *built, ids, faces, face_triangles.data() + face_start[e], local)) {
      for (int v : ids) local[v] = -1;
      elements_.push_back(built->relabelled(std::move(ids), relative_tolerance));
      ++num_prebuilt_elements_;
      continue;
    }
    std::vector<Vec3> element_nodes;
    element_nodes.reserve(ids.size());
    for (int v : ids) element_nodes.push_back(nodes_[v]);
    std::vector<ConvexPolyhedron::Face> local_faces(faces.size());
    std::vector<std::vector<ConvexPolyhedron::Triangle>> local_triangles(faces.size());
    for (size_t f = 0; f < faces.size(); ++f) {
      ConvexPolyhedron::Face& lf = local_faces[f];
      lf.reserve(faces[f].size());
      for (int v : faces[f]) lf.push_back(local[v]);
      std::vector<ConvexPolyhedron::Triangle>& lt = local_triangles[f];
      for (const Triangle& t : face_triangles[face_start[e] + f])
        lt.push_back({local[t[0]], local[t[1]], local[t[2]]});
    }
    for (int v : ids) local[v] = -1;
    try {
      elements_.emplace_back(std::move(element_nodes), std::move(local_faces), std::move(local_triangles),
                             relative_tolerance, ids);
    } catch (const std::invalid_argument& error) {
      fail("element " + std::to_string(e) + ": " + error.what());
    }
  }
  return face_triangles;
}

// Boundary nodes and triangles, interior face count, and the check that the boundary is a closed manifold.
// Returns per boundary triangle whether it lies on a crack face.
std::vector<char> PolyhedralMesh::buildBoundary(const FaceAdjacency& adjacency,
                                                const std::vector<std::vector<Triangle>>& face_triangles) {
  is_boundary_node_.assign(numNodes(), 0);
  std::vector<std::pair<int, int>> boundary_edges;  // directed boundary polygon edges
  std::vector<char> boundary_triangle_is_crack;
  for (size_t e = 0; e < element_faces_.size(); ++e)
    for (size_t f = 0; f < element_faces_[e].size(); ++f) {
      const int g = adjacency.face_start[e] + static_cast<int>(f);
      if (adjacency.other_user[g] >= 0) {
        if (isCrackFace(int(e), int(f)))
          fail(faceName(int(e), int(f)) + " is listed as crack face but still connects two elements");
        const int other = adjacency.other_user[g];
        if (other < g) ++num_interior_faces_;  // triangulated by the first user, reversed by the second
        continue;
      }
      const Face& face = element_faces_[e][f];
      for (size_t k = 0; k < face.size(); ++k) {
        is_boundary_node_[face[k]] = 1;
        boundary_edges.emplace_back(face[k], face[(k + 1) % face.size()]);
      }
      const char crack = isCrackFace(int(e), int(f)) ? 1 : 0;
      for (const Triangle& t : face_triangles[g]) {
        boundary_triangles_.push_back(t);
        boundary_triangle_is_crack.push_back(crack);
      }
    }
  std::sort(boundary_edges.begin(), boundary_edges.end());
  for (size_t k = 0; k + 1 < boundary_edges.size(); ++k)
    if (boundary_edges[k] == boundary_edges[k + 1])
      fail(
          "the boundary is not a closed manifold: edge (" + std::to_string(boundary_edges[k].first) + ", " +
          std::to_string(boundary_edges[k].second) +
          ") is used twice in the same direction: hanging node, non-conforming faces or elements touching at "
          "an edge");
  for (const auto& edge : boundary_edges)
    if (!std::binary_search(boundary_edges.begin(), boundary_edges.end(),
                            std::make_pair(edge.second, edge.first)))
      fail("the boundary is not closed at edge (" + std::to_string(edge.first) + ", " +
           std::to_string(edge.second) + "): hanging node or non-conforming faces");
  return boundary_triangle_is_crack;
}

// Non-conforming faces that still close the boundary (e.g. a square split along different diagonals by
// the two elements): coplanar, opposite boundary triangles with overlapping interiors.
void PolyhedralMesh::checkConformingBoundary(const std::vector<char>& boundary_triangle_is_crack) const {
  double scale = 0.0;
  for (const Vec3& p : nodes_) scale = std::max(scale, (p - nodes_[0]).norm());
  const double tol = 1e-9 * scale;
  struct PlaneTriangle {
    double offset;
    Vec3 normal;  // canonical sign
    int sign, index;
  };
  std::vector<PlaneTriangle> planes;
  for (size_t t = 0; t < boundary_triangles_.size(); ++t) {
    const auto& tri = boundary_triangles_[t];
    Vec3 normal = (nodes_[tri[1]] - nodes_[tri[0]]).cross(nodes_[tri[2]] - nodes_[tri[0]]);
    if (!(normal.norm() > tol * scale)) continue;  // zero-area triangles cover nothing
    normal.normalize();
    int axis;
    normal.cwiseAbs().maxCoeff(&axis);
    const int sign = normal[axis] > 0.0 ? 1 : -1;
    normal *= sign;
    planes.push_back({normal.dot(nodes_[tri[0]]), normal, sign, static_cast<int>(t)});
  }
  std::sort(planes.begin(), planes.end(),
            [](const PlaneTriangle& a, const PlaneTriangle& b) { return a.offset < b.offset; });
  for (size_t i = 0; i < planes.size(); ++i)
    for (size_t j = i + 1; j < planes.size() && planes[j].offset - planes[i].offset <= tol; ++j) {
      if (planes[i].sign == planes[j].sign || planes[i].normal.dot(planes[j].normal) < 1.0 - 1e-9) continue;
      // The two sides of an internal crack coincide by design.
      if (boundary_triangle_is_crack[planes[i].index] && boundary_triangle_is_crack[planes[j].index])
        continue;
      const Vec3 e1 = planes[i].normal.unitOrthogonal(), e2 = planes[i].normal.cross(e1);
      std::array<Eigen::Vector2d, 3> a, b;
      for (int k = 0; k < 3; ++k) {
        const Vec3& p = nodes_[boundary_triangles_[planes[i].index][k]];
        const Vec3& q = nodes_[boundary_triangles_[planes[j].index][k]];
        a[k] = Eigen::Vector2d(e1.dot(p), e2.dot(p));
        b[k] = Eigen::Vector2d(e1.dot(q), e2.dot(q));
      }
      if (trianglesOverlap(a, b, tol)) {
        const auto& ta = boundary_triangles_[planes[i].index];
        fail("non-conforming faces: boundary triangles (" + std::to_string(ta[0]) + ", " +
             std::to_string(ta[1]) + ", " + std::to_string(ta[2]) +
             ") and another overlap with opposite orientation (faces of neighbouring elements do not "
             "match)");
      }
    }
}

// Overlap check: element volumes add up to the volume enclosed by the boundary.
void PolyhedralMesh::checkVolumes() {
  double element_volume = 0.0, enclosed = 0.0;
  for (const ConvexPolyhedron& element : elements_) element_volume += element.volume();
  const Vec3 origin = nodes_[boundary_triangles_.front()[0]];
  for (const Triangle& t : boundary_triangles_)
    enclosed += (nodes_[t[0]] - origin).dot((nodes_[t[1]] - origin).cross(nodes_[t[2]] - origin)) / 6.0;
  if (std::abs(enclosed - element_volume) > 1e-9 * element_volume)
    fail("element volumes sum to " + std::to_string(element_volume) + " but the boundary encloses " +
         std::to_string(enclosed) + " (overlapping elements)");
  volume_ = element_volume;
}

bool PolyhedralMesh::isCrackFace(int e, int f) const {
  return std::binary_search(crack_faces_.begin(), crack_faces_.end(), FaceRef(e, f));
}

std::vector<std::vector<std::vector<PolyhedralMesh::Triangle>>> PolyhedralMesh::elementFaceTriangles() const {
  std::vector<std::vector<std::vector<Triangle>>> out(elements_.size());
  for (size_t e = 0; e < elements_.size(); ++e) {
    const ConvexPolyhedron& element = elements_[e];
    const std::vector<int>& ids = element.globalNodeIds();
    out[e].resize(size_t(element.numFaces()));
    for (int t = 0; t < element.numTriangles(); ++t) {
      const ConvexPolyhedron::Triangle& local = element.triangles()[size_t(t)];
      out[e][size_t(element.triangleFace()[size_t(t)])].push_back(
          {ids[size_t(local[0])], ids[size_t(local[1])], ids[size_t(local[2])]});
    }
  }
  return out;
}

}  // namespace rc
