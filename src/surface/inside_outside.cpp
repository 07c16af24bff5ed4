#include "relaxed_connectivity/surface/inside_outside.h"

#include <stdexcept>

namespace rc {

namespace {

void requireNormals(const MlsSurface& surface) {
  if (!surface.cloud().hasNormals() && !surface.cloud().empty())
    throw std::invalid_argument("classifyPoint: the surface's cloud has no (outward) normals");
}

Containment classifyUnchecked(const MlsSurface& surface, const Vec3& x) {
  const MlsProjection proj = surface.project(x);
  if (!proj.valid) return Containment::kUnknown;
  const Vec3 offset = x - proj.point;
  if (offset.norm() <= 1e-12 * surface.supportRadius()) return Containment::kUnknown;
  const double side = offset.dot(proj.normal);  // (3.9)
  if (side > 0) return Containment::kOutside;
  if (side < 0) return Containment::kInside;
  return Containment::kUnknown;
}

}  // namespace

const char* containmentName(Containment c) {
  switch (c) {
    case Containment::kInside:
      return "inside";
    case Containment::kOutside:
      return "outside";
    case Containment::kUnknown:
      return "unknown";
  }
  return "?";
}

Containment classifyPoint(const MlsSurface& surface, const Vec3& x) {
  requireNormals(surface);
  return classifyUnchecked(surface, x);
}

void classifyPoints(const MlsSurface& surface, const std::vector<Vec3>& xs, std::vector<Containment>& out) {
  requireNormals(surface);
  out.resize(xs.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (long i = 0; i < static_cast<long>(xs.size()); ++i) out[i] = classifyUnchecked(surface, xs[i]);
}

}  // namespace rc
