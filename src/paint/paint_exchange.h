// Bidirectional paint exchange between two samples in contact (thesis 5.6, (5.9)-(5.11), after Baxter et
// al.): each gives away a share of its wet paint that grows with pressure, time and its transfer rate, and
// the received paint mixes into the kept paint by volume. Only wet paint moves.
#pragma once

#include "relaxed_connectivity/paint/paint_state.h"

namespace rc {

/// Exchanges wet paint between `i` and `j` pressed together with pressure `pressure` for `dt` seconds:
/// i gives dV_i = (1 - exp(-tau_ij p dt)) V_w^i (5.9), j gives dV_j (5.10) with tau_ji; each wet colour and
/// optical density becomes the volume-weighted mix of what it kept and what it received (5.11). The total
/// wet volume is conserved. Rates, pressure and dt must be >= 0 (std::invalid_argument otherwise).
void exchangePaint(PaintState& i, PaintState& j, double tau_ij, double tau_ji, double pressure, double dt);

}  // namespace rc
