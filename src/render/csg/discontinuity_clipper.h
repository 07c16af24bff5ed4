// Discontinuity surfels (thesis 4.3) on a plain surfel cloud, without a CSG tree: invisible discs that cut
// the surface surfels overlapping them to render sharp edges, e.g. the crack discs of a tearing thin shell
// (7.3.2: "two discontinuity surfels with opposing normals", each on its material side, normal pointing away
// from it). A surface surfel whose centre lies behind a disc (n . (p_s - c) <= 0) loses the fragments in
// front of that disc's plane that project inside its radius; surfels on the other side are left to the
// partner disc.
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/splat/fragment_clipper.h"

namespace rc {

class DiscontinuityClipper : public FragmentClipper {
 public:
  /// `surface`: the cloud given to SurfelRenderer::render (positions, radii or tangent axes);
  /// `discontinuities`: disc centres, unit normals and radii (or tangent axes). Both are copied (geometry
  /// only). Throws std::invalid_argument naming the missing channel or the first non-finite disc.
  DiscontinuityClipper(const SurfelCloud& surface, const SurfelCloud& discontinuities);

  bool needsClipping(uint32_t surfel) const override;
  bool keepFragment(uint32_t surfel, const Vec3& x) const override;

  /// Surface surfels that overlap some disc (the ones tested per fragment).
  size_t clippedSurfels() const;

 private:
  std::vector<Vec3> centers_, normals_;  // discs
  std::vector<double> radii_;
  std::vector<uint32_t> offsets_, ids_;  // per surface surfel: the discs with its centre behind them
};

}  // namespace rc
