// Renders a CSG scene (scene.h) frame by frame: moves dynamic patches, keeps the CsgClipper's classification
// and per-frame clipping partners up to date (thesis 4.2.1) and splats with the SurfelRenderer; reports the
// timings and edge counts of Table 4.1.
#pragma once

#include <memory>

#include "relaxed_connectivity/render/csg/csg_clipper.h"
#include "relaxed_connectivity/render/scene/csg_scene.h"
#include "relaxed_connectivity/render/splat/surfel_renderer.h"

namespace rc {

struct CsgSceneRenderOptions {
  bool csg =
      true;  ///< false: plain splatting of the visible surfels (no clipping, discontinuity surfels dropped)
  CsgClipperOptions clipper;  ///< partner search (4.2.1; spatial index by default) and compiled clipping
  SplatConfig splat;
};

struct CsgSceneFrameStats {
  size_t surfels = 0;       ///< surfels in the scene
  size_t edge_surfels = 0;  ///< surfels with clipping partners (4.1.2)
  size_t edge_pixels = 0;   ///< visible pixels covered by an edge surfel (countEdgePixels; needs depth)
  double classify_ms = 0;   ///< dynamic scenes: re-classification after the motion
  double partners_ms = 0;   ///< per-frame clipping partners
  double visibility_ms = 0, accumulate_ms = 0, shade_ms = 0;
  double total_ms = 0;  ///< whole frame (motion, classification, partners, splatting)
  RenderStats render;
};

class CsgSceneRenderer {
 public:
  /// `scene` must outlive the renderer. Throws std::invalid_argument for an inconsistent scene.
  explicit CsgSceneRenderer(const CsgScene& scene, const CsgSceneRenderOptions& options = {});
  ~CsgSceneRenderer();

  /// Renders the scene at time t (static scenes ignore t) for `camera`.
  void render(const Camera& camera, double t, RenderImages* out, CsgSceneFrameStats* stats = nullptr);

  /// The surfels of the last frame (moved for dynamic scenes).
  const SurfelCloud& surfels() const { return moved_; }
  /// Null without CSG.
  const CsgClipper* clipper() const { return clipper_.get(); }

 private:
  const CsgScene& scene_;
  CsgSceneRenderOptions options_;
  SurfelCloud moved_;    ///< scene surfels at the current time
  SurfelCloud visible_;  ///< without CSG: the role-0 surfels only
  std::unique_ptr<CsgClipper> clipper_;
  SurfelRenderer renderer_;
  double time_ = 0;
};

/// Visible pixels covered by the screen footprint (bounding circle of the projected disc) of an edge surfel
/// (clipper->needsClipping) whose depth there is within its radius of the rendered depth: the pixels the edge
/// renderer works on, the "edge pixels" of Table 4.1.
size_t countEdgePixels(const SurfelCloud& cloud, const CsgClipper& clipper, const Camera& camera,
                       const RenderImages& images);

}  // namespace rc
