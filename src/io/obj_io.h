// Wavefront OBJ reader and writer (geometry only): `v` (optionally followed by r g b in 0..1), `vn`, and `f`
// with v, v/vt, v//vn or v/vt/vn corners and negative (relative) indices; polygons are fan-triangulated.
// Texture coordinates, groups, materials, lines and points are ignored.
#pragma once

#include <string>

#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/io/io_options.h"

namespace rc {

/// Vertex normals come from the `vn` referenced by face corners (the last reference wins); when some vertex
/// is never given one, the i-th `vn` is used for the i-th vertex if the counts agree, otherwise normals are
/// omitted. Colours are kept only when every vertex has them.
TriangleMesh readObjMesh(const std::string& path, const ReadOptions& options = {});

/// Writes `v` (with r g b when colours are present), `vn` when normals are present, and `f` (v//vn corners).
void writeObjMesh(const std::string& path, const TriangleMesh& mesh);

}  // namespace rc
