#include "relaxed_connectivity/paint/paint_state.h"

#include <algorithm>
#include <cmath>

namespace rc {

PaintColour PaintColour::mix(const PaintColour& a, double va, const PaintColour& b, double vb) {
  const double total = va + vb;
  if (!(total > 0)) return a;
  const double wa = va / total, wb = vb / total;
  PaintColour c;
  c.rgb = wa * a.rgb + wb * b.rgb;
  c.reflectivity = wa * a.reflectivity + wb * b.reflectivity;
  c.shininess = wa * a.shininess + wb * b.shininess;
  return c;
}

void addWetPaint(PaintState& into, const PaintState& from, double volume) {
  const double total = into.wet_volume + volume;
  into.wet = PaintColour::mix(into.wet, into.wet_volume, from.wet, volume);
  if (total > 0)
    into.optical_density = (into.optical_density * into.wet_volume + from.optical_density * volume) / total;
  into.wet_volume = total;
}

PaintColour visibleColour(const PaintState& s) {
  const double alpha = std::clamp(s.optical_density * s.wet_volume, 0.0, 1.0);  // (5.8)
  return PaintColour::mix(s.wet, alpha, s.dry, 1.0 - alpha);
}

uint8_t colourByte(double channel) {
  return uint8_t(std::lround(255.0 * std::clamp(channel, 0.0, 1.0)));
}

bool lookAlike(const PaintState& a, const PaintState& b) {
  const PaintColour ca = visibleColour(a), cb = visibleColour(b);
  for (int k = 0; k < 3; ++k)
    if (colourByte(ca.rgb[k]) != colourByte(cb.rgb[k])) return false;
  return colourByte(ca.reflectivity) == colourByte(cb.reflectivity);  // (weighs the environment's colour)
}

}  // namespace rc
