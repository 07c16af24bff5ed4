// Differential rendering of a surface that changes in small parts (thesis 5.7, Fig. 5.11): after a full
// render the unnormalised colour, normal and depth sums and the weights are kept (SplatAccumulation); a delta
// (surfels removed, surfels added; a recoloured surfel is both) is un-splatted and splatted into them with
// the visibility bounds of the full render, and only the touched tiles are normalised and shaded again. A
// full update is made when the camera moved, when a delta is larger than partial updates pay for, or when a
// tile was updated so often that float rounding could have drifted (the thesis' per-surfel update counter for
// its 8-bit framebuffer; here per tile, the unit that is renormalised).
//
// As in the thesis a partial update does not change the visibility bounds: added surfels blend where they lie
// within the depth tolerance of what the full render saw (resampled children and paint layers, 5.5, 5.6.3),
// and pixels the full render left empty take any surfel. Large geometric changes need a full update.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/splat/camera.h"
#include "relaxed_connectivity/render/splat/splat_accumulation.h"
#include "relaxed_connectivity/render/splat/splat_config.h"
#include "relaxed_connectivity/render/splat/surfel_renderer.h"

namespace rc {

struct CameraFrame;

struct DifferentialRenderConfig {
  DifferentialRenderConfig() { splat.outputs = kOutputColor | kOutputDepth; }
  SplatConfig splat;  ///< outputs (colour and depth here) may not include kOutputPatchId (a maximum cannot
                      ///< be un-splatted)
  /// Removed plus added surfels above which an update renders the whole cloud instead (partial updates stop
  /// paying; bench_paint_rendering measures the crossover).
  size_t max_delta_surfels = 100000;
  /// Splats un-splatted or splatted into one tile since the last full render before a full update. The sums
  /// are floats: each update rounds by about 6e-8 of a sum, a random walk of 1e6 updates by about 6e-5 of it
  /// (0.06 of a colour level), far below the 8-bit output's half level.
  uint32_t max_tile_updates = 1000000;
  /// Camera motion [m, rad] above which the next update is a full one; 0: any change.
  double pose_tolerance = 0;

  /// Throws std::invalid_argument naming the bad field.
  void validate() const;
};

enum class RenderUpdate { kNone, kDifferential, kFull };
enum class FullUpdateReason {
  kNone,
  kFirstFrame,
  kRequested,
  kCameraMoved,
  kLargeDelta,
  kPrecision,
  kSettings
};
const char* fullUpdateReasonName(FullUpdateReason reason);

struct DifferentialStats {
  RenderUpdate update = RenderUpdate::kNone;
  FullUpdateReason reason = FullUpdateReason::kNone;
  size_t removed_splats = 0, added_splats = 0;  ///< drawn (not culled or invalid) surfels of the delta
  size_t invalid_surfels = 0;                   ///< of the delta: non-finite or degenerate, skipped
  size_t tiles = 0;                             ///< tiles splatted and normalised again
  size_t fragments = 0;                         ///< fragments un-splatted plus splatted
  double setup_ms = 0, accumulate_ms = 0, total_ms = 0;  ///< accumulate: splatting and shading the tiles
  RenderStats full;                                      ///< of a full update
};

class DifferentialSurfelRenderer {
 public:
  explicit DifferentialSurfelRenderer(const DifferentialRenderConfig& config = {});
  ~DifferentialSurfelRenderer();
  const DifferentialRenderConfig& config() const { return config_; }

  /// Renders `cloud` whole and keeps its sums (the images of SurfelRenderer::render).
  void renderFull(const SurfelCloud& cloud, const Camera& camera, DifferentialStats* stats = nullptr,
                  FullUpdateReason reason = FullUpdateReason::kRequested);
  /// Applies a delta: `removed` are surfels exactly as they were drawn before (same geometry and colour),
  /// `added` the new ones; `cloud` is the whole state after the delta, rendered when a full update is due.
  /// All three need the same channels as a render (normals and radii, or tangent axes).
  void update(const SurfelCloud& cloud, const SurfelCloud& removed, const SurfelCloud& added,
              const Camera& camera, DifferentialStats* stats = nullptr);
  /// The next update renders in full.
  void invalidate() { valid_ = false; }
  /// New splat settings (outputs and environment kept); the next update renders in full (reason kSettings).
  /// Throws std::invalid_argument for settings the renderer refuses, keeping the old ones.
  void setSplatConfig(SplatConfig splat);
  bool valid() const { return valid_; }

  const RenderImages& images() const { return images_; }
  /// Memory of the kept sums [bytes].
  size_t accumulationBytes() const { return accumulation_.bytes(); }

 private:
  bool cameraMoved(const Camera& camera) const;

  DifferentialRenderConfig config_;
  SurfelRenderer renderer_;
  RenderImages images_;
  SplatAccumulation accumulation_;
  Camera camera_;
  std::unique_ptr<CameraFrame> frame_;
  std::vector<uint32_t> tile_updates_;  ///< splats into each tile since the last full render
  bool valid_ = false;
  bool settings_changed_ = false;  ///< the next full update is for new settings
};

}  // namespace rc
