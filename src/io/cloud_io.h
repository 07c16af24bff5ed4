// Format-independent entry points: dispatch on the (case-insensitive) file extension
// .ply, .pcd, .off, .obj, .xyz.
#pragma once

#include <string>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/io/io_options.h"

namespace rc {

/// Reads a point cloud; for mesh files (.ply with faces, .off, .obj) the vertices.
SurfelCloud readCloud(const std::string& path, const ReadOptions& options = {});
/// Reads a mesh; point cloud files (.pcd, .xyz, .ply without faces) give a mesh without triangles.
TriangleMesh readMesh(const std::string& path, const ReadOptions& options = {});
/// Writes a cloud; .off/.obj get vertices only. options.encoding applies to .ply and .pcd.
void writeCloud(const std::string& path, const SurfelCloud& cloud, const WriteOptions& options = {});
/// Writes a mesh; .pcd/.xyz cannot hold faces and throw IoError.
void writeMesh(const std::string& path, const TriangleMesh& mesh, const WriteOptions& options = {});

}  // namespace rc
