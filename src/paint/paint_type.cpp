#include "relaxed_connectivity/paint/paint_type.h"

namespace rc {

PaintState freshPaint(const PaintType& paint) {
  PaintState s;
  s.wet = paint.colour;
  s.wet_volume = paint.eraser ? 0.0 : paint.load_volume;
  s.optical_density = paint.optical_density;
  return s;
}

void loadBrush(BrushSkin& skin, const PaintType& paint) {
  const PaintState fresh = freshPaint(paint);
  for (PaintState& s : skin.paint) {
    s.wet = fresh.wet;
    s.wet_volume = fresh.wet_volume;
    s.optical_density = fresh.optical_density;
  }
}

}  // namespace rc
