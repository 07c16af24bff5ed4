// A conforming volume mesh of convex polyhedral elements (thesis 9.1): global nodes, elements referencing
// them, and faces shared by neighbouring elements with one common triangulation (the mean value coordinates
// depend on it, so identical triangulations keep the shape functions C0 across elements).
#pragma once

#include <array>
#include <utility>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/fem/convex_polyhedron.h"

namespace rc {

/// Elements are given as closed polygon surfaces over global node ids (faces counter-clockwise seen from
/// outside). The constructor builds one ConvexPolyhedron per element (local nodes in order of first use,
/// globalNodeIds() = mesh node ids) and checks the mesh, throwing std::invalid_argument naming the element,
/// face or node: node index out of range or unused, invalid element (the ConvexPolyhedron message), a face
/// used by more than two elements or twice with the same orientation, two faces with the same nodes in a
/// different cyclic order, a boundary surface that is not closed (hanging nodes, non-conforming faces), and
/// element volumes that do not add up to the volume enclosed by the boundary (overlapping elements).
///
/// Crack faces (thesis 9.3.2, partial cuts): faces listed in `crack_faces` as (element, face) are boundary
/// faces that may coincide with other listed crack faces of opposite orientation (the two sides of an
/// internal crack, ProgressiveCutMesh). Only pairs of listed faces are exempt from the non-conforming-face
/// check; a listed face must be used by one element (else std::invalid_argument: it still connects two
/// elements).
class PolyhedralMesh {
 public:
  using Face = std::vector<int>;                // global node ids, counter-clockwise seen from outside
  using ElementFaces = std::vector<Face>;       // closed surface of one element
  using Triangle = std::array<int, 3>;          // global node ids
  enum class TetrahedronSplit { kFive, kSix };  // 5 tets (alternating by cell parity) or 6 (Kuhn)
  using FaceRef = std::pair<int, int>;          // (element, face of the element)

  PolyhedralMesh(std::vector<Vec3> nodes, std::vector<ElementFaces> elements,
                 double relative_tolerance = ConvexPolyhedron::kDefaultRelativeTolerance,
                 std::vector<FaceRef> crack_faces = {});
  /// The same, taking over prebuilt elements (e.g. elements a cut left whole; empty: none): prebuilt[e]
  /// (null: none) becomes element e, relabelled to this mesh's node ids and tolerance
  /// (ConvexPolyhedron::relabelled) without validating it again, when its nodes (bitwise, in local order of
  /// first use), faces and face triangulation are exactly those this constructor would build; otherwise
  /// element e is built and validated. The mesh checks run as above. Throws std::invalid_argument also for
  /// a prebuilt list whose size is not the element count.
  PolyhedralMesh(std::vector<Vec3> nodes, std::vector<ElementFaces> elements, double relative_tolerance,
                 std::vector<FaceRef> crack_faces, const std::vector<const ConvexPolyhedron*>& prebuilt);

  /// Given face triangulations: face_triangles[e][f] (global ids, counter-clockwise seen from outside element
  /// e) tiles face f of element e; an empty list (for an element or a face) leaves the best fan. A face
  /// shared by two elements takes the triangulation one of them gives, and the other must give the same
  /// triangles (reversed) or none; throws std::invalid_argument naming the element and face otherwise, or
  /// when the triangles do not tile the face (ConvexPolyhedron). Cuts build their meshes with fans again.
  PolyhedralMesh(std::vector<Vec3> nodes, std::vector<ElementFaces> elements,
                 std::vector<std::vector<std::vector<Triangle>>> face_triangles,
                 double relative_tolerance = ConvexPolyhedron::kDefaultRelativeTolerance,
                 std::vector<FaceRef> crack_faces = {});

  /// How hexahedralGrid splits its square faces: the best fan (the diagonal from the first corner), or the
  /// diagonal mirrored across the box's mid-planes, so that the mesh is mirror-symmetric about each mid-plane
  /// across which its cell count is even (equal diagonals where the two halves meet along an axis are
  /// impossible when the count is odd).
  enum class FaceDiagonals { kFan, kMirrorSymmetric };
  /// nx x ny x nz boxes of the axis-aligned box [lo, hi] as hexahedra.
  static PolyhedralMesh hexahedralGrid(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz,
                                       FaceDiagonals diagonals = FaceDiagonals::kFan);
  /// The same grid with each box split into 5 or 6 tetrahedra (conforming face diagonals).
  static PolyhedralMesh tetrahedralGrid(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz,
                                        TetrahedronSplit split = TetrahedronSplit::kSix);
  /// Irregular convex cells: the hexahedral grid cut by num_planes random planes (each plane splits every
  /// cell it crosses, so the mesh stays conforming; new nodes on cut edges are shared). Planes passing closer
  /// than min_relative_gap * |hi - lo| to an existing node are redrawn, which keeps cells away from slivers.
  static PolyhedralMesh randomPlaneCut(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz, int num_planes,
                                       unsigned seed, double min_relative_gap = 0.02);

  int numNodes() const { return static_cast<int>(nodes_.size()); }
  int numElements() const { return static_cast<int>(elements_.size()); }
  const std::vector<Vec3>& nodes() const { return nodes_; }
  const Vec3& node(int i) const { return nodes_[i]; }
  /// Element e; element(e).globalNodeIds()[local] is the mesh node of a local node.
  const ConvexPolyhedron& element(int e) const { return elements_[e]; }
  const std::vector<ConvexPolyhedron>& elements() const { return elements_; }
  /// The input surface of element e (global ids).
  const ElementFaces& elementFaces(int e) const { return element_faces_[e]; }

  /// The triangulation of every face of every element (global ids), as the constructor taking face_triangles
  /// accepts it: a mesh rebuilt from it (e.g. with moved nodes) keeps its shape functions.
  std::vector<std::vector<std::vector<Triangle>>> elementFaceTriangles() const;

  int numInteriorFaces() const { return num_interior_faces_; }
  /// Boundary faces (used by one element) triangulated as in their element, outward, global ids.
  const std::vector<Triangle>& boundaryTriangles() const { return boundary_triangles_; }
  /// is_boundary_node[i]: node i lies on a boundary face.
  const std::vector<char>& isBoundaryNode() const { return is_boundary_node_; }
  double volume() const { return volume_; }

  /// Listed crack faces, sorted.
  const std::vector<FaceRef>& crackFaces() const { return crack_faces_; }
  int numCrackFaces() const { return static_cast<int>(crack_faces_.size()); }
  bool isCrackFace(int e, int f) const;
  /// Elements taken over from the prebuilt list (not built and validated again).
  int numPrebuiltElements() const { return num_prebuilt_elements_; }

 private:
  struct FaceAdjacency;
  // The constructors' work.
  void build(double relative_tolerance, const std::vector<const ConvexPolyhedron*>& prebuilt);
  // The given triangulation of face f of element e (null: none given).
  const std::vector<Triangle>* givenTriangles(int e, int f) const {
    if (given_triangles_.empty() || given_triangles_[size_t(e)].empty() ||
        given_triangles_[size_t(e)][size_t(f)].empty())
      return nullptr;
    return &given_triangles_[size_t(e)][size_t(f)];
  }
  // Phases of build().
  void checkInput(size_t num_prebuilt);
  FaceAdjacency buildFaceAdjacency() const;
  std::vector<std::vector<Triangle>> buildElements(const FaceAdjacency& adjacency, double relative_tolerance,
                                                   const std::vector<const ConvexPolyhedron*>& prebuilt);
  std::vector<char> buildBoundary(const FaceAdjacency& adjacency,
                                  const std::vector<std::vector<Triangle>>& face_triangles);
  void checkConformingBoundary(const std::vector<char>& boundary_triangle_is_crack) const;
  void checkVolumes();

  std::vector<Vec3> nodes_;
  std::vector<ElementFaces> element_faces_;
  std::vector<ConvexPolyhedron> elements_;
  std::vector<Triangle> boundary_triangles_;
  std::vector<char> is_boundary_node_;
  std::vector<FaceRef> crack_faces_;
  std::vector<std::vector<std::vector<Triangle>>> given_triangles_;  // during construction only
  int num_interior_faces_ = 0, num_prebuilt_elements_ = 0;
  double volume_ = 0.0;
};

}  // namespace rc
