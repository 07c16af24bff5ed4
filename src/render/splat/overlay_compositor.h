// Draws a small, moving surfel cloud (the brush, thesis 5.7) over a rendered image without touching the
// image's sums: the overlay is splatted alone into the screen rectangle it covers (a cropped camera) and
// composited by depth, and its shadow from a directional light (a shadow map rendered from the light, 5.7:
// "a shadow map is created from the brush to indicate its position relative to the object") darkens the
// surface below it. The cost follows the overlay's screen area, not the image's.
#pragma once

#include <cstddef>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/splat/camera.h"
#include "relaxed_connectivity/render/splat/surfel_renderer.h"

namespace rc {

struct OverlayOptions {
  SplatConfig splat;  ///< of the overlay (its outputs are set to colour and depth)
  bool shadow = true;
  Vec3 light_direction = Vec3(0, 0, -1);  ///< direction the light travels (world frame)
  double shadow_length = 0.05;            ///< [m] along the light below the overlay where shadows can fall
  double shadow_strength = 0.45;          ///< fraction of the colour a shadow takes away
  double shadow_texel = 0;                ///< shadow map texel [m]; 0: the overlay's mean surfel radius
  int max_shadow_map_size = 512;          ///< texels on a side at most (the texel grows beyond)

  /// Throws std::invalid_argument naming the bad field.
  void validate() const;
};

struct OverlayStats {
  size_t overlay_pixels = 0;  ///< pixels where the overlay is in front
  size_t shadow_pixels = 0;   ///< pixels darkened by its shadow
  double ms = 0;
};

class OverlayCompositor {
 public:
  explicit OverlayCompositor(const OverlayOptions& options = {});
  const OverlayOptions& options() const { return options_; }

  /// Writes base.color to *color with `overlay` drawn where it lies in front of base.depth and its shadow on
  /// the surface. `base` needs colour and depth images of `camera` (a perspective or orthographic camera).
  /// An overlay with surfels that cannot be drawn (no normals or radii) throws std::invalid_argument.
  void composite(const SurfelCloud& overlay, const Camera& camera, const RenderImages& base,
                 std::vector<Rgba>* color, OverlayStats* stats = nullptr) const;

 private:
  void castShadow(const SurfelCloud& overlay, const Camera& camera, const RenderImages& base,
                  const std::vector<uint8_t>& covered, std::vector<Rgba>* color, OverlayStats* stats) const;

  OverlayOptions options_;
  SurfelRenderer renderer_;         ///< the overlay in its screen rectangle
  SurfelRenderer shadow_renderer_;  ///< the overlay's depth seen from the light
};

}  // namespace rc
