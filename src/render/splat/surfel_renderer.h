// Software EWA surface splatting (thesis 3.2, Zwicker et al. 2001): elliptical/circular surfels, perspective
// and orthographic cameras, EWA screen-space low-pass filter, extended (fuzzy) depth test with a per-fragment
// tolerance (3.2.1), weight-normalised accumulation of colour, normal and depth, deferred Phong shading, and
// per-fragment CSG clipping through a FragmentClipper (4.2.2). Multi-threaded and deterministic.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/splat/camera.h"
#include "relaxed_connectivity/render/splat/fragment_clipper.h"
#include "relaxed_connectivity/render/splat/splat_accumulation.h"
#include "relaxed_connectivity/render/splat/splat_config.h"
#include "relaxed_connectivity/render/splat/splat_workspace.h"

namespace rc {

class SurfelRenderer {
 public:
  explicit SurfelRenderer(const SplatConfig& config = {});
  const SplatConfig& config() const { return config_; }

  /// Renders `cloud` (needs normals and radii or axes; patch ids from the attribute "patch_id" if present,
  /// else 0). Throws std::invalid_argument naming what is missing. The caller calls clipper->prepare() for
  /// this camera before render(); render() uses only the const, thread-safe clipper methods. Fragments that
  /// the clipper rejects are dropped in both passes (they do not occlude), except for colour-only clipping.
  /// stats.splats counts rasterized surfels, stats.fragments the fragments accumulated in the second pass,
  /// stats.clipped_fragments the fragments (inside the cut-off and the image) that the clipper rejected
  /// among those it tested: fragments of geometry-clipped surfels are tested once in the visibility pass
  /// unless already behind the depth bound there, colour-only clipped ones where they blend.
  /// Images may be at most 65535 pixels wide and high. Scratch memory is kept in the renderer between
  /// frames; concurrent calls on one renderer are safe (all but one use temporary scratch memory).
  /// With `keep`, the per-pixel bounds and weight-sums of the frame are kept there for differential
  /// updates (DifferentialSurfelRenderer, 5.7); not with a clipper or the patch id image.
  void render(const SurfelCloud& cloud, const Camera& camera, RenderImages* out,
              const FragmentClipper* clipper = nullptr, RenderStats* stats = nullptr,
              SplatAccumulation* keep = nullptr) const;

 private:
  SplatConfig config_;
  mutable SplatWorkspaceSlot workspace_;
};

}  // namespace rc
