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
  /// Imprints (5.6.3) are carved while the brush moves along its skeleton: |cos| of the angle between the
  /// device's velocity and the bristles' direction in the buffer plane at least this, at least this speed.
  double imprint_min_alignment = 0.7;
  double imprint_min_speed = 2e-3;  ///< [m/s]

  /// Throws std::invalid_argument naming the bad option.
  void validate() const;
};

struct PaintEventStats {
  int buffers = 0;
  int penetrated_pixels = 0;
  size_t originals_disabled = 0, children_removed = 0, children_added = 0;
  size_t children_imprinted = 0;
  bool imprint_aliased = false;  ///< imprints skipped: the pattern's spacing is below two buffer pixels
  /// Wall time of the stages [s]: the buffer (plane fit, gathering and splatting the samples), the exchange
  /// (5.9-5.11), the resampling (gather to the skin, pixel surfels, the surface's lists).
  double buffer_seconds = 0, exchange_seconds = 0, resample_seconds = 0;
  double moved_to_surface = 0, moved_to_brush = 0;  ///< wet volume
};

/// The paint buffer's pixel [m]: options.pixel_size, or the brush's skin spacing when that is 0 (5.5).
double paintBufferPixel(const PaintTransferOptions& options, const BrushPreset& brush);
/// Whether `paint`'s imprint pattern is finer than two buffer pixels (it would alias; transferPaint skips
/// it).
bool imprintAliases(const PaintType& paint, double pixel);

/// Transfers paint between `brush` (after its advance() for this event) and `surface` for `dt` seconds with
/// the rates of `paint`. Wet volume summed over the brush skin and the surface's active surfels is conserved.
/// The eraser (paint.eraser) deposits nothing: it takes wet paint up at transfer_to_brush and moves the dry
/// colour of the surfels it presses on towards the object's own colour at transfer_to_surface (the (5.9)
/// rate). Viscous paint (imprint_depth > 0) raises the new surfels by the bristle pattern of 5.6.3:
/// depth (1 + cos(2 pi u / spacing)) / 2 above the father's tangent plane, u across the stroke; not when the
/// spacing is below two buffer pixels (the pattern would alias: imprint_aliased is set instead).
PaintEventStats transferPaint(Brush& brush, PaintSurface& surface, const PaintType& paint, double dt,
                              const PaintTransferOptions& options = {});

/// Sum of the wet volume on the surface's active surfels (enabled originals and children).
double surfaceWetVolume(const PaintSurface& surface);

}  // namespace rc
