// Tetrahedral meshes for the polyhedral FEM (thesis 9.1): a closed triangle surface tetrahedralised by TetGen
// (quality "pq<ratio>/<dihedral>a<volume>" meshing), TetGen's .node/.ele file pair (the `tetgen` program's
// output) read and written, and the conversion of tetrahedra to a PolyhedralMesh.
// TetGen is optional (RC_HAVE_TETGEN); without it tetrahedralizeSurface() throws std::runtime_error. The file
// reader and the conversion work in every build.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {

struct TetgenOptions {
  /// Upper bound on circumradius / shortest edge ("q"); <= 0 disables quality refinement. TetGen's
  /// termination guarantee needs >= 2 for arbitrary input; 1.414 works on surfaces without small angles.
  double max_radius_edge_ratio = 1.414;
  /// Lower bound on the dihedral angle in degrees ("q<ratio>/<angle>"); 0 leaves TetGen's default. Only used
  /// with quality refinement.
  double min_dihedral_degrees = 0.0;
  /// Upper bound on tetrahedron volume ("a"); <= 0: none.
  double max_volume = 0.0;
  /// Keep the input surface triangles unsplit ("Y"): no Steiner points on the boundary. Without it TetGen may
  /// also re-triangulate nearly coplanar neighbours (its 1e-8 coplanarity tolerance): on the 25k-triangle Max
  /// Planck bust the enclosed volume moved by 4.8e-9 relative; with it, by 5e-15.
  bool preserve_surface = false;
  /// Suppress TetGen's console output ("Q").
  bool quiet = true;
};

/// Nodes and tetrahedra (4 node ids each, any orientation).
struct TetrahedralMesh {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 4>> tetrahedra;
};

/// Whether this build links TetGen (RC_HAVE_TETGEN).
bool tetgenAvailable();

/// TetGen's command line switches for the options, e.g. "pzq1.414a0.01Q" (always "p": PLC input, "z":
/// zero-based indices).
std::string tetgenSwitches(const TetgenOptions& options);

/// Tetrahedralises the volume enclosed by a closed triangle surface. Throws std::invalid_argument naming the
/// problem for an empty surface, a face index out of range, a degenerate face (repeated vertex) or an open
/// surface (an edge used by an odd number of triangles; the message counts them), std::runtime_error when
/// TetGen fails (its error code explained: self-intersection, tiny features, ...) or the build lacks TetGen.
/// Unused nodes are removed.
TetrahedralMesh tetrahedralizeSurface(const TriangleMesh& surface, const TetgenOptions& options = {});

/// Drops nodes no tetrahedron uses (renumbering the rest in order) and returns the count dropped.
int removeUnusedNodes(TetrahedralMesh& mesh);

/// Each tetrahedron as a closed element surface (faces counter-clockwise seen from outside, whatever the
/// input orientation); unused nodes are removed first. Throws std::invalid_argument for a node id out of
/// range or a flat tetrahedron (naming it), and whatever PolyhedralMesh's checks find.
PolyhedralMesh toPolyhedralMesh(TetrahedralMesh mesh);

/// Circumradius over shortest edge of a tetrahedron (sqrt(6)/4 ~ 0.612 for the regular one).
double radiusEdgeRatio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Reads TetGen's .node (count, dimension 3, attributes, boundary marker; then index x y z [attributes]
/// [marker]) and .ele (count, 4 nodes per tetrahedron, region attribute flag; then index n0 n1 n2 n3
/// [attribute]) files; '#' starts a comment. Indices may start at 0 or 1 (the .node file's first index sets
/// the base). Throws IoError naming the file and line (bad header, missing or non-numeric field, wrong point
/// count, node index out of range, second-order elements, ...).
TetrahedralMesh readTetgenMesh(const std::string& node_path, const std::string& ele_path);
/// Writes `<basename>.node` and `<basename>.ele` (zero-based, no attributes or markers, 17 digits).
void writeTetgenMesh(const std::string& basename, const TetrahedralMesh& mesh);

}  // namespace rc
