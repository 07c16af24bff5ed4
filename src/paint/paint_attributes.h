// The paint state of surfels as named attribute columns of a SurfelCloud (float64, so that a PLY or
// PointCloud2 round trip is exact): the painted model is saved, loaded and sent as an ordinary cloud.
#pragma once

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/paint/paint_state.h"

namespace rc {

/// Column names (thesis 5.6 symbols in the comments); the _rgb columns hold 3 values, the rest 1.
constexpr const char* kPaintWetRgb = "paint_wet_rgb";                    ///< C_w
constexpr const char* kPaintWetReflectivity = "paint_wet_reflectivity";  ///< of C_w
constexpr const char* kPaintWetShininess = "paint_wet_shininess";        ///< of C_w
constexpr const char* kPaintDryRgb = "paint_dry_rgb";                    ///< C_d
constexpr const char* kPaintDryReflectivity = "paint_dry_reflectivity";  ///< of C_d
constexpr const char* kPaintDryShininess = "paint_dry_shininess";        ///< of C_d
constexpr const char* kPaintWetVolume = "paint_wet_volume";              ///< V_w
constexpr const char* kPaintDryVolume = "paint_dry_volume";              ///< V_d
constexpr const char* kPaintOpticalDensity = "paint_optical_density";    ///< rho
/// tau of the surfel (PaintState::transfer_rate); optional: without it every surfel reads -1 (not set).
constexpr const char* kPaintTransferRate = "paint_transfer_rate";

/// Whether the cloud carries every paint column (with the right type and size; paint_transfer_rate is
/// optional).
bool hasPaintAttributes(const SurfelCloud& cloud);
/// Adds the paint columns (or overwrites them) with `initial` for every surfel; a surfel's own colour, when
/// the cloud has colours and `dry_from_colours` is set, becomes its dry colour.
void addPaintAttributes(SurfelCloud& cloud, const PaintState& initial, bool dry_from_colours = true);
/// The paint of surfel i (std::invalid_argument if the columns are missing or i is out of range).
PaintState readPaint(const SurfelCloud& cloud, size_t i);
void writePaint(SurfelCloud& cloud, size_t i, const PaintState& paint);

/// The paint columns of a cloud looked up once, for many surfels (readPaint/writePaint look them up per
/// call). Throws std::invalid_argument if a column is missing; valid while no column is added or removed.
class PaintColumns {
 public:
  explicit PaintColumns(SurfelCloud& cloud);
  PaintState read(size_t i) const;
  void write(size_t i, const PaintState& paint);

 private:
  Attribute *wet_rgb_, *wet_reflectivity_, *wet_shininess_, *dry_rgb_, *dry_reflectivity_, *dry_shininess_,
      *wet_volume_, *dry_volume_, *optical_density_, *transfer_rate_;
  size_t size_;
};

}  // namespace rc
