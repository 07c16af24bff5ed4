// Outputs of an FEM run (thesis chapter 9): the nodes as a point cloud, VTK XML UnstructuredGrid (.vtu) with
// one VTK_POLYHEDRON cell (type 42, faces / faceoffsets arrays) per convex element, readable by ParaView and
// VTK 9 (io/pvd_io.h lists the frames); the deformed boundary surface as OBJ triangles.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {

/// One simulated body in its current state: the rest mesh and the 3 N position / velocity vectors (node i at
/// 3 i, as WarpedDynamics stores them). velocities may be null (written as zero).
struct FemBodyState {
  const PolyhedralMesh* mesh = nullptr;
  const Eigen::VectorXd* positions = nullptr;
  const Eigen::VectorXd* velocities = nullptr;
};

enum class VtuEncoding { kAscii, kAppendedRaw };

/// All bodies in one piece (their nodes and cells concatenated in order). Points: current positions
/// (Float64). PointData: displacement (x - X) and velocity (Float32 x 3). CellData: body (Int32, index in
/// `bodies`) and nodes (Int32, nodes of the element). Cells: connectivity / offsets / types (42) / faces
/// (per cell: face count, then per face its node count and point ids, counter-clockwise seen from outside) /
/// faceoffsets (end of each cell's face stream). kAppendedRaw stores the arrays as raw bytes after the XML
/// (header_type UInt64). Throws std::invalid_argument for a null mesh or positions of the wrong size, IoError
/// if the file cannot be written.
void writeFemVtu(const std::string& path, const std::vector<FemBodyState>& bodies,
                 VtuEncoding encoding = VtuEncoding::kAppendedRaw);

/// The nodes of all bodies (in body order) at their current positions with the fields velocity and
/// displacement (float32 x 3, x - X) and body (uint32, index of the body).
SurfelCloud femNodesToCloud(const std::vector<FemBodyState>& bodies);

/// The boundary triangles of all bodies at their current positions as one OBJ file ("o body<k>" per body).
/// Throws like writeFemVtu.
void writeFemObj(const std::string& path, const std::vector<FemBodyState>& bodies);

/// The current state in the format of the file's extension (fem_sim's ~save): .vtu (writeFemVtu), .obj
/// (writeFemObj), .ply / .pcd / .xyz (femNodesToCloud). Throws IoError for another extension, naming the
/// supported ones, and like the writers.
void writeFemState(const std::string& path, const std::vector<FemBodyState>& bodies);

}  // namespace rc
