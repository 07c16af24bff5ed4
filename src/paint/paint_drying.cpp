#include "relaxed_connectivity/paint/paint_drying.h"

#include <cmath>
#include <stdexcept>

namespace rc {

PaintColour DryingFunction::operator()(const PaintColour& wet) const {
  PaintColour d;
  d.rgb = wet.rgb + brighten * (Vec3::Ones() - wet.rgb);
  d.reflectivity = reflectivity_factor * wet.reflectivity;
  d.shininess = shininess_factor * wet.shininess;
  return d;
}

double dryPaint(PaintState& s, double kappa, double dt, const DryingFunction& drying) {
  if (!(kappa >= 0) || !(dt >= 0)) throw std::invalid_argument("dryPaint: kappa and dt must be >= 0");
  const double dried = -std::expm1(-kappa * dt) * s.wet_volume;  // (5.12)
  if (!(dried > 0)) return 0;
  s.dry = PaintColour::mix(s.dry, s.dry_volume, drying(s.wet), dried);  // (5.13)
  s.dry_volume += dried;
  s.wet_volume -= dried;
  return dried;
}

}  // namespace rc
