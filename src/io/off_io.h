// OFF reader and writer: OFF / COFF / NOFF / CNOFF headers, '#' comments, polygons (fan-triangulated).
#pragma once

#include <string>

#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/io/io_options.h"

namespace rc {

/// Colours may be integers 0..255 or floats 0..1 (3 or 4 components); face colours are ignored.
TriangleMesh readOffMesh(const std::string& path, const ReadOptions& options = {});

/// Writes "OFF", "NOFF", "COFF" or "CNOFF" depending on the present normals and colours (other channels and
/// attributes are not representable in OFF).
void writeOffMesh(const std::string& path, const TriangleMesh& mesh);

}  // namespace rc
