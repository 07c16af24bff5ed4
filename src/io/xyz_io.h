// XYZ point files: one point per line, "x y z" or "x y z nx ny nz", '#' comments.
#pragma once

#include <string>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/io/io_options.h"

namespace rc {

/// Every data line must have the same number of values (3 or 6).
SurfelCloud readXyzCloud(const std::string& path, const ReadOptions& options = {});
/// Writes positions (and normals when present) with round-trip precision.
void writeXyzCloud(const std::string& path, const SurfelCloud& cloud);

}  // namespace rc
