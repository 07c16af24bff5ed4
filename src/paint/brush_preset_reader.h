// Reading brush presets (config/paint/brushes/*.yaml): unknown keys and bad values fail with
// "<file>:<line>:<column>: <problem>".
#pragma once

#include <string>

#include "relaxed_connectivity/paint/brush_preset.h"

namespace rc {

/// Throws BrushPresetError naming the file, line and problem (also for a preset whose time_step exceeds the
/// skeleton's explicit step limit: the message gives the limit).
BrushPreset readBrushPreset(const std::string& path);
/// The same from YAML text; `source_name` names it in errors.
BrushPreset parseBrushPreset(const std::string& yaml_text, const std::string& source_name);

/// Why the preset's skeleton cannot run (a Verlet time_step above the explicit step limit: the limit and what
/// to change), or "" if it can. The reader and paint_model's dynamic_reconfigure refuse such a preset.
std::string brushStepLimitProblem(const BrushPreset& preset);

}  // namespace rc
