// PLY reader and writer (ascii, binary_little_endian, binary_big_endian).
//
// Vertex properties x y z, nx ny nz (or normal_x ...), radius, axis1_x..axis2_z (elliptical surfels), red
// green blue [alpha] (uchar), confidence and curvature fill the SurfelCloud channels; every other scalar
// vertex property becomes an attribute column of its type (properties name_0, name_1, ... of one type form a
// column with count > 1). Faces come from a `face` element (`vertex_indices`/`vertex_index` lists, polygons
// triangulated as fans) or a `tristrips` element (-1 restarts a strip; odd triangles are flipped to keep the
// winding; degenerate triangles are skipped). Other elements are skipped.
#pragma once

#include <string>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/io/io_options.h"

namespace rc {

SurfelCloud readPlyCloud(const std::string& path, const ReadOptions& options = {});
TriangleMesh readPlyMesh(const std::string& path, const ReadOptions& options = {});

/// Writes all present channels and attributes; options.encoding kAscii or kBinary (little endian unless
/// options.big_endian); kBinaryCompressed throws IoError (PLY has no compression).
void writePlyCloud(const std::string& path, const SurfelCloud& cloud, const WriteOptions& options = {});
void writePlyMesh(const std::string& path, const TriangleMesh& mesh, const WriteOptions& options = {});

}  // namespace rc
