// The hook through which CSG clipping (thesis 4.2.2) enters the splatting rasterizer: for every fragment the
// renderer asks whether the point x on surfel `surfel` is part of the visible surface.
#pragma once

#include <cstdint>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/csg/clip_program.h"

namespace rc {

class FragmentClipper {
 public:
  virtual ~FragmentClipper() = default;
  /// Called once per frame before rasterization (e.g. to find clipping partners for this camera).
  virtual void prepare() {}
  /// True if surfel `surfel` needs per-fragment tests at all (edge surfels); others are drawn unclipped.
  virtual bool needsClipping(uint32_t surfel) const = 0;
  /// True if the fragment at world point x (on the plane of surfel `surfel`) is rendered (Algorithm 4.2).
  /// Must be thread-safe (called concurrently from rasterizer threads).
  virtual bool keepFragment(uint32_t surfel, const Vec3& x) const = 0;
  /// Optional fast path (clip_program.h): compiles the fragment test of `surfel` for this frame into
  /// `program` (screen-space affine tests over the pixel map `frame`). False: the renderer calls
  /// keepFragment() per fragment instead. Must be thread-safe and agree with keepFragment() up to float
  /// rounding at the decision boundaries.
  virtual bool compileClip(uint32_t surfel, const ClipFrame& frame, ClipProgram* program) const {
    return false;
  }
  /// False for surfels that only clip (discontinuity surfels, 4.3): they are never drawn.
  virtual bool isVisible(uint32_t surfel) const { return true; }
  /// True if a rejected fragment of `surfel` loses only its colour contribution (surfels clipped by texture
  /// discontinuity surfels, 4.3): its weight, depth and normal still blend, so shading stays smooth.
  virtual bool clipsColorOnly(uint32_t surfel) const { return false; }
  /// True if the renderer shades `surfel` with its normal reversed (walls of complemented patches, 4.2:
  /// their normals point into the solid they bound). Shading only; clipping uses the original normals.
  virtual bool flipsNormal(uint32_t surfel) const { return false; }
  /// True if flipsNormal() holds for any surfel. Back-face culling is refused then (SurfelRenderer::render):
  /// culled surfels of complemented patches leave the rims of subtracted solids wrong (5.5 % of the pixels of
  /// config/scenes/spikes.yaml, test_csg_rendering).
  virtual bool flipsAnyNormal() const { return false; }
};

}  // namespace rc
