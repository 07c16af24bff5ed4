// PCD (PCL point cloud data) reader and writer: header versions 0.5-0.7, DATA ascii, binary and
// binary_compressed (LZF, field-major).
//
// Fields x y z, normal_x normal_y normal_z, rgb / rgba (packed 4 bytes -> colours; "rgb" gets alpha 255),
// radius, axis1_x..axis2_z, confidence and curvature (and the other names of io/surfel_fields.h) fill the
// SurfelCloud channels; every other field becomes an attribute column (type and COUNT kept); padding fields
// "_" are skipped. Organised clouds (HEIGHT > 1)
// keep width/height and their NaN points unless ReadOptions::keep_invalid is false.
#pragma once

#include <string>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/io/io_options.h"

namespace rc {

SurfelCloud readPcdCloud(const std::string& path, const ReadOptions& options = {});

/// Writes all present channels and attributes (colours as packed "rgba" U4). Organised clouds keep WIDTH and
/// HEIGHT; others are written as WIDTH = size, HEIGHT = 1.
void writePcdCloud(const std::string& path, const SurfelCloud& cloud, const WriteOptions& options = {});

}  // namespace rc
