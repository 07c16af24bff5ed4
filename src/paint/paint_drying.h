// Paint drying (thesis 5.6.1, (5.12), (5.13)): wet paint turns into dry paint at the paint's rate kappa; the
// dry colour mixes in the dried paint's colour as changed by the drying function G.
#pragma once

#include "relaxed_connectivity/paint/paint_state.h"

namespace rc {

/// The drying function G (5.13): dried paint loses reflectivity and shininess and brightens slightly.
struct DryingFunction {
  double brighten = 0.05;            ///< rgb -> rgb + brighten (1 - rgb)
  double reflectivity_factor = 0.5;  ///< reflectivity -> factor * reflectivity
  double shininess_factor = 0.5;     ///< shininess -> factor * shininess

  PaintColour operator()(const PaintColour& wet) const;
};

/// Dries `s` for `dt` seconds at rate `kappa` [1/s]: dV = (1 - exp(-kappa dt)) V_w moves from wet to dry
/// (5.12) and C_d becomes (V_d C_d + dV G(C_w)) / (V_d + dV) (5.13). Any split of an interval into steps
/// gives the same volumes (to rounding). Returns dV. kappa and dt must be >= 0.
double dryPaint(PaintState& s, double kappa, double dt, const DryingFunction& drying);

}  // namespace rc
