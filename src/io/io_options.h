// Options shared by every reader and writer of the I/O module.
#pragma once

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

struct ReadOptions {
  /// Keep surfels with non-finite positions (the NaN pixels of organised clouds). When false they are dropped
  /// and the cloud becomes unorganised; mesh faces touching a dropped vertex are dropped too.
  bool keep_invalid = true;
};

/// How a writer encodes the data. Text-only formats (OFF, OBJ, XYZ) ignore it; PLY has no compressed form.
enum class Encoding { kAscii, kBinary, kBinaryCompressed };

struct WriteOptions {
  Encoding encoding = Encoding::kBinary;
  /// Positions, normals, radii and tangent axes as float64 instead of float32 (binary and ascii PLY/PCD).
  bool double_precision = false;
  /// PLY only: binary_big_endian instead of binary_little_endian.
  bool big_endian = false;
};

/// Applies `options` to a freshly read cloud (drops non-finite positions unless keep_invalid).
void applyReadOptions(const ReadOptions& options, SurfelCloud* cloud);
/// Same for a mesh: vertices are re-indexed, faces that touch a dropped vertex are removed.
void applyReadOptions(const ReadOptions& options, TriangleMesh* mesh);

}  // namespace rc
