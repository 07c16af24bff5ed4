#include "relaxed_connectivity/paint/paint_exchange.h"

#include <cmath>
#include <stdexcept>

namespace rc {

void exchangePaint(PaintState& i, PaintState& j, double tau_ij, double tau_ji, double pressure, double dt) {
  if (!(tau_ij >= 0) || !(tau_ji >= 0) || !(pressure >= 0) || !(dt >= 0))
    throw std::invalid_argument("exchangePaint: transfer rates, pressure and dt must be >= 0");
  const double given_i = -std::expm1(-tau_ij * pressure * dt) * i.wet_volume;  // (5.9)
  const double given_j = -std::expm1(-tau_ji * pressure * dt) * j.wet_volume;  // (5.10)
  const double kept_i = i.wet_volume - given_i, kept_j = j.wet_volume - given_j;
  const PaintColour from_i = i.wet, from_j = j.wet;
  const double density_i = i.optical_density, density_j = j.optical_density;
  i.wet = PaintColour::mix(from_i, kept_i, from_j, given_j);  // (5.11)
  j.wet = PaintColour::mix(from_j, kept_j, from_i, given_i);
  const auto mixDensity = [](double a, double va, double b, double vb) {
    return va + vb > 0 ? (a * va + b * vb) / (va + vb) : a;
  };
  i.optical_density = mixDensity(density_i, kept_i, density_j, given_j);
  j.optical_density = mixDensity(density_j, kept_j, density_i, given_i);
  i.wet_volume = kept_i + given_j;
  j.wet_volume = kept_j + given_i;
}

}  // namespace rc
