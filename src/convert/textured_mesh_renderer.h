// A software rasterizer for converted meshes (thesis 6.4): textured triangles with a z-buffer, perspective-
// correct texture coordinates and bilinear lookups, unshaded (the albedo), with the cameras of the splatting
// renderer, so that a textured mesh and the surfels it came from can be compared pixel by pixel.
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/convert/textured_mesh.h"
#include "relaxed_connectivity/render/splat/camera.h"

namespace rc {

struct MeshImage {
  uint32_t width = 0, height = 0;
  std::vector<Rgba> color;   ///< the texture colour (background: `background`)
  std::vector<float> depth;  ///< camera z (+inf: background)
};

/// Renders the textured mesh (both faces) seen by `camera`.
MeshImage renderTexturedMesh(const TexturedMesh& mesh, const Camera& camera,
                             Rgba background = {255, 255, 255, 255});

/// PSNR [dB] of the RGB difference over the pixels where both images show the surface (mask: both foreground,
/// by their depth), and the fraction of the foreground pixels (of either) shown by only one of them.
struct ImageComparison {
  double psnr = 0;
  double mse = 0;       ///< per channel, 8-bit units squared
  size_t compared = 0;  ///< pixels in both
  double silhouette_mismatch = 0;
};
ImageComparison compareImages(const std::vector<Rgba>& a, const std::vector<float>& a_depth,
                              const std::vector<Rgba>& b, const std::vector<float>& b_depth);

}  // namespace rc
