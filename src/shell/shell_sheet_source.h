// A flat sheet of surfels for shell scenes (`source.sheet`): a jittered grid of cell-centred surfels in z = 0
// whose cells tile [-w/2, w/2] x [-h/2, h/2], normal +z, optionally coloured like a printed poster.
#pragma once

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

enum class SheetColors { kNone, kChecker, kRings };

struct SheetSource {
  double width = 1.0, height = 1.0;  ///< w, h (> 0)
  double spacing = 0.01;             ///< grid spacing (> 0; at least 2 cells per side)
  double jitter = 0.0;               ///< 0..1 of a cell, uniform (seeded: the same sheet every time)
  SheetColors colors = SheetColors::kNone;
  double tile = 0.0;  ///< checker square or ring width; 0: a tenth of the shorter side
};

/// Grid cells along each side for the spacing (rounded); throws std::invalid_argument if fewer than 2 per
/// side or more than 5e7 cells in all.
void sheetCells(const SheetSource& sheet, long* nx, long* ny);

/// The surfels (radius 0.75 x the larger cell side, so neighbours overlap).
SurfelCloud sheetSurfels(const SheetSource& sheet);

}  // namespace rc
