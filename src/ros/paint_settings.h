// paint_model's dynamic_reconfigure settings (config/dynamic_reconfigure/Paint.cfg): the brush's physical
// parameters and the paint type's rates, to and from the core's BrushPreset and PaintType.
#pragma once

#include <relaxed_connectivity/PaintConfig.h>  // generated from config/dynamic_reconfigure/Paint.cfg

#include "relaxed_connectivity/paint/brush_preset.h"
#include "relaxed_connectivity/paint/paint_type.h"

namespace rc {

/// The reconfigurable fields of `config` into `preset` and, if not null, `paint` (other fields kept).
void applyPaintReconfigure(const relaxed_connectivity::PaintConfig& config, BrushPreset* preset,
                           PaintType* paint);
/// The settings of `preset` and, if not null, `paint` into `config` (what the node answers and shows).
void writePaintReconfigure(const BrushPreset& preset, const PaintType* paint,
                           relaxed_connectivity::PaintConfig* config);
/// True if the reconfigurable brush fields of `a` and `b` are equal.
bool sameBrushSettings(const BrushPreset& a, const BrushPreset& b);
/// True if the reconfigurable paint fields of `a` and `b` are equal.
bool samePaintSettings(const PaintType& a, const PaintType& b);

}  // namespace rc
