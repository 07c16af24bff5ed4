#include "relaxed_connectivity/paint/paint_exchange.h"

#include <cmath>
#include <stdexcept>

namespace rc {

void exchangePaint(PaintState& i, PaintState& j, double tau_ij, double tau_ji, double pressure, double dt) {
  if (!(tau_ij >= 0) || !(tau_ji >= 0) || !(pressure >= 0) || !(dt >= 0))
    throw std::invalid_argument("exchangePaint: transfer rates, pressure and dt must be >= 0");
  const double given_i = -std::expm1(-tau_ij * pressure * dt) * i.wet_volume;  // (5.9)
  const double given_j = -std::expm1(-tau_ji * pressure * dt) * j.wet_volume;  // (5.10)
  // (5.11): each keeps what it did not give and receives what the other gave.
  const PaintState from_i = i, from_j = j;
  i.wet_volume -= given_i;
  j.wet_volume -= given_j;
  addWetPaint(i, from_j, given_j);
  addWetPaint(j, from_i, given_i);
}

}  // namespace rc
