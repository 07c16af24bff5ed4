// Reads a paint type preset (config/paint/paints/*.yaml): unknown keys and bad values are errors naming the
// file, line and column.
#pragma once

#include <string>

#include "relaxed_connectivity/paint/paint_type.h"

namespace rc {

/// Throws PaintTypeError "<file>:<line>:<column>: <problem>".
PaintType readPaintType(const std::string& path);
PaintType parsePaintType(const std::string& yaml_text, const std::string& source_name);

}  // namespace rc
