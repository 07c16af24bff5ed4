// A paint type (thesis 5.6): the paint a brush loads, how it moves between brush and surface, how it dries,
// diffuses and leaves imprints; read from a preset in config/paint/paints/.
#pragma once

#include <stdexcept>
#include <string>

#include "relaxed_connectivity/paint/brush_skin.h"
#include "relaxed_connectivity/paint/paint_drying.h"
#include "relaxed_connectivity/paint/paint_state.h"

namespace rc {

struct PaintType {
  std::string name = "acrylic";
  PaintColour colour;                ///< C_w of freshly loaded paint
  double optical_density = 1.0;      ///< rho [1/volume]: how opaque a wet layer is (5.8)
  double load_volume = 1.0;          ///< wet volume per brush skin surfel when the brush is loaded
  double transfer_to_surface = 5.0;  ///< tau brush -> surface [1/(pressure s)] (5.9)
  double transfer_to_brush = 1.0;    ///< tau surface -> brush (5.10); 0: nothing flows back (Fig. 5.8)
  double drying_rate = 0.05;         ///< kappa [1/s] (5.12)
  DryingFunction drying;             ///< G (5.13)
  double diffusion = 0;              ///< isotropic D [m^2/s] (5.14); > 0 for watercolour
  double imprint_depth = 0;          ///< depth of bristle imprints carved into new surfels [m] (5.6.3)
  double imprint_spacing = 0;        ///< spacing of the imprint pattern across the stroke [m]
  /// The eraser: what the brush transfers is the object's original colour (the surface's own dry colour
  /// under the paint), not paint it carries.
  bool eraser = false;
};

/// Paint as loaded onto the brush: `load_volume` of `colour` with `optical_density` (none for the eraser,
/// which carries no paint).
PaintState freshPaint(const PaintType& paint);
/// Loads every skin surfel with freshPaint (replacing what the brush carried: dipping into a clean pot).
void loadBrush(BrushSkin& skin, const PaintType& paint);

class PaintTypeError : public std::runtime_error {
 public:
  explicit PaintTypeError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace rc
