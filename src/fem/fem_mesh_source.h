// Where an FEM scene's initial mesh comes from (key mesh.type of config/fem/*.yaml): one convex element,
// grids, a cube split by random planes (Fig. 9.4), TetGen meshes of a surface or of .node / .ele files.
#pragma once

#include <string>
#include <vector>

#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {

/// Where the initial mesh comes from (key mesh.type).
enum class FemMeshType {
  kConvexHull,     ///< one element: the convex hull of `points`
  kHexGrid,        ///< PolyhedralMesh::hexahedralGrid(lo, hi, cells)
  kTetGrid,        ///< PolyhedralMesh::tetrahedralGrid(lo, hi, cells, split)
  kRandomPlanes,   ///< PolyhedralMesh::randomPlaneCut(lo, hi, cells, planes, seed, min_relative_gap)
  kRandomSplits,   ///< randomElementSplits(lo, hi, cells, planes, seed, min_relative_gap) (Fig. 9.4)
  kTetgenSurface,  ///< TetGen mesh of a closed triangle surface (OBJ / OFF / PLY), scaled and centred
  kTetgenFiles,    ///< TetGen's .node / .ele pair
};

struct FemMeshSource {
  FemMeshType type = FemMeshType::kHexGrid;
  std::vector<Vec3> points;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Ones();
  int cells[3] = {1, 1, 1};
  PolyhedralMesh::TetrahedronSplit split = PolyhedralMesh::TetrahedronSplit::kSix;
  /// hex_grid: how square faces are triangulated (kMirrorSymmetric: a mirror-symmetric mesh).
  PolyhedralMesh::FaceDiagonals face_diagonals = PolyhedralMesh::FaceDiagonals::kFan;
  int planes = 0;
  unsigned seed = 1;
  double min_relative_gap = 0.02;
  std::string surface, node_file, ele_file;  ///< resolved against the scene file's folder
  double size = 0.0;  ///< tetgen_surface: bounding-box diagonal after scaling (0: as is)
  double max_volume = 0.0, max_radius_edge_ratio = 2.0;
  double min_dihedral_degrees = 0.0;  ///< tetgen_surface: TetgenOptions::min_dihedral_degrees
  bool close_holes = false;           ///< tetgen_surface: closeSurfaceHoles before meshing (open scans)
  int decimate_vertices = 0;          ///< tetgen_surface: decimateSurface to this many vertices (0: no)
};

/// The mesh of a source (unplaced). Throws std::invalid_argument / std::runtime_error / IoError.
PolyhedralMesh buildFemMesh(const FemMeshSource& source);

/// Fig. 9.4's partition: the nx x ny x nz hexahedral grid of [lo, hi], then `num_splits` times a random
/// element (chosen with probability proportional to its volume) split by a random plane near its centroid
/// (a region-restricted cutMeshByPlane: neighbours only get T-junction nodes). Planes passing closer than
/// min_relative_gap * |hi - lo| to a node of the chosen element are redrawn. Result: nx ny nz + num_splits
/// elements. Throws std::runtime_error if no admissible plane is found in 1000 draws.
PolyhedralMesh randomElementSplits(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz, int num_splits,
                                   unsigned seed, double min_relative_gap = 0.02);

}  // namespace rc
