// Inside/outside classification of points against an MLS surface with oriented normals (thesis 3.1.4, (3.9)).
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/surface/mls_surface.h"

namespace rc {

enum class Containment : uint8_t { kInside, kOutside, kUnknown };
const char* containmentName(Containment c);

/// (3.9) as the text states it: x is outside when the normal at Psi(x) points towards x, (x - Psi(x)).N > 0
/// (the printed formula has the opposite sign with outward normals). kUnknown when the projection is invalid
/// or x lies on the surface (|x - Psi(x)| <= 1e-12 support). Only reliable close to the surface. Requires a
/// cloud with outward normals (throws std::invalid_argument otherwise).
Containment classifyPoint(const MlsSurface& surface, const Vec3& x);

/// Multi-threaded classification of many points.
void classifyPoints(const MlsSurface& surface, const std::vector<Vec3>& xs, std::vector<Containment>& out);

}  // namespace rc
