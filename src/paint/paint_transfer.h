// One paint event (thesis 5.5, Fig. 5.6): for each tip of the brush (one paint buffer per tip when the brush
// is split, 5.5.1) a buffer in the least-squares plane of the object around the tip; the object's active
// surfels and the brush skin splatted into it; the exchange where the brush penetrates; the penetrated part
// of the object resampled to one child surfel per pixel (assigned to the closest original; replaced
// originals disabled, replaced children deleted); the brush's paint gathered back to its skin.
#pragma once

#include "relaxed_connectivity/paint/brush.h"
#include "relaxed_connectivity/paint/paint_surface.h"
#include "relaxed_connectivity/paint/paint_type.h"

namespace rc {

struct PaintTransferOptions {
  double pixel_size = 0;             ///< paint buffer pixel [m]; 0: the brush's skin spacing (5.5)
  double pressure_per_depth = 2000;  ///< p of (5.9) per metre the brush penetrates
  int margin_pixels = 2;             ///< buffer border around the penetrating part of the brush
  double max_extent = 0.05;          ///< largest buffer side [m] (a bound on the work per event)

  /// Throws std::invalid_argument naming the bad option.
  void validate() const;
};

struct PaintEventStats {
  int buffers = 0;
  int penetrated_pixels = 0;
  size_t originals_disabled = 0, children_removed = 0, children_added = 0;
  double moved_to_surface = 0, moved_to_brush = 0;  ///< wet volume
};

/// Transfers paint between `brush` (after its advance() for this event) and `surface` for `dt` seconds with
/// the rates of `paint`. Wet volume summed over the brush skin and the surface's active surfels is conserved.
PaintEventStats transferPaint(Brush& brush, PaintSurface& surface, const PaintType& paint, double dt,
                              const PaintTransferOptions& options = {});

/// Sum of the wet volume on the surface's active surfels (enabled originals and children).
double surfaceWetVolume(const PaintSurface& surface);

}  // namespace rc
