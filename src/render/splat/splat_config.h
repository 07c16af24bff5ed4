// The options, output images and statistics of the splatting renderer (SurfelRenderer, thesis 3.2), shared by
// its passes (set-up, tile passes, deferred shading).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

class EnvironmentMap;

/// Output images of SurfelRenderer::render() (bit flags). Images not asked for are left empty and cost
/// nothing: the per-pixel output writes are a large part of a frame at 1280x720.
enum RenderOutput : uint32_t {
  kOutputColor = 1,
  kOutputDepth = 2,
  kOutputNormal = 4,
  kOutputWeight = 8,
  kOutputPatchId = 16,
  kOutputAll = 31,
};

struct SplatConfig {
  bool ewa_filter = true;  ///< convolve with the screen-space low-pass filter (EWA)
  /// Variance of the screen-space low-pass filter [px^2]. Zwicker et al. use 1; with the 2-sigma cut-off
  /// that widens every splat by 2 px, which dilates silhouettes and CSG edges by 2 px. 0.25 (1 px) keeps
  /// minified surfaces hole-free (test_surfel_renderer) with edges within 1 px (test_csg_rendering).
  double lowpass_variance = 0.25;
  double cutoff_radius = 1.0;          ///< reconstruction kernel cut-off, in units of the surfel radius
  double depth_tolerance_scale = 1.0;  ///< per-fragment fuzzy-depth tolerance multiplier (3.2.1)
  /// Perspective splats larger than kExactFootprintRatio of their depth get the exact projection of their
  /// disc as footprint (ewa_splat.h): a 3x3 inverse per such splat, set up in scalar arithmetic; smaller
  /// splats are set up as before (bitwise the same images, test_large_splats). Off: the affine approximation
  /// at the centre for every splat (EWA as published; large oblique splats fall short of their far side: 43 %
  /// of a grazing floor of nine discs left empty in test_large_splats).
  bool exact_footprint = true;
  /// A pixel counts as covered by a surface only where its centre lies inside a splat's own (unfiltered)
  /// footprint: silhouettes without the low-pass filter's dilation (up to 1 px at the default variance).
  /// The filtered kernels still blend inside the covered pixels (anti-aliasing as EWA). Needs discs that
  /// overlap in object space; off: the filtered footprint covers (EWA as published), which also closes
  /// sub-pixel gaps between discs that do not overlap, at the price of the dilated silhouettes.
  bool exact_silhouettes = true;
  int threads = 0;  ///< 0: all cores
  /// Surfels facing away from the camera are drawn too (two-sided, shaded with the flipped normal) unless
  /// this is set; culling them halves the work for closed models. Refused (std::invalid_argument) with a CSG
  /// clipper that has complemented patches (differences): their rims rendered wrongly.
  bool backface_culling = false;
  // Deferred Phong shading (per pixel, from the blended normals)
  bool shading = true;
  Vec3 light_direction_camera =
      Vec3(0.3, 0.5, 1.0);  ///< direction the light travels (camera optical frame: +z into the scene);
                            ///< default from behind the camera, upper left
  double ambient = 0.25, diffuse = 0.7, specular = 0.25, shininess = 30;
  uint32_t outputs = kOutputAll;  ///< RenderOutput flags: the images render() fills
  /// Rasterize unclipped splats eight pixels at a time (AVX2) where the CPU has it; the images are bitwise
  /// the same as with the four-wide (SSE2) passes. Off: always four-wide (for comparisons).
  bool wide_simd = true;
  Rgba background = {255, 255, 255, 255};
  Rgba default_color = {200, 200, 200, 255};  ///< for clouds without colours
  /// Reflective surfels (a float attribute kReflectivityAttribute, environment_map.h) mirror this environment
  /// (5.7); null or no such attribute: colours as they are. Not owned; must outlive the renders.
  const EnvironmentMap* environment = nullptr;
};

/// Output images, row-major, width * height (empty if not in SplatConfig::outputs). Background pixels:
/// weight 0, depth +inf, normal 0, patch id -1.
struct RenderImages {
  uint32_t width = 0, height = 0;
  std::vector<Rgba> color;              ///< shaded colour
  std::vector<float> depth;             ///< camera-frame z of the visible surface
  std::vector<Eigen::Vector3f> normal;  ///< blended unit normal (world frame)
  std::vector<float> weight;            ///< accumulated reconstruction weight
  std::vector<int32_t> patch_id;        ///< patch of the surfel with the largest weight at the pixel
};

struct RenderStats {
  size_t surfels = 0, splats = 0, fragments = 0, clipped_fragments = 0;
  size_t edge_on_surfels = 0;  ///< surfels seen (almost) edge-on, drawn through the degenerate-ellipse path
  size_t invalid_surfels = 0;  ///< skipped: non-finite position/normal/axes or zero radius
  size_t culled_surfels = 0;   ///< outside the view volume or image, back-facing (if culled) or invisible
  /// Clipped surfels whose fragment test was compiled (clip_program.h); the others are tested per fragment.
  size_t compiled_clip_surfels = 0;
  int simd_width = 0;  ///< pixels per step of the unclipped tile passes: 8 (AVX2), 4 (SSE2) or 1
  /// Wall time of set-up and tile binning; the per-tile passes (visibility, accumulation, normalisation
  /// with shading) run tile by tile, so their times are summed over threads and divided by the thread count.
  double setup_ms = 0, bin_ms = 0;
  double visibility_ms = 0, accumulate_ms = 0, shade_ms = 0, total_ms = 0;
};

}  // namespace rc
