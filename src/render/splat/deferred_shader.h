// Normalisation and deferred Phong shading of the splatting renderer (thesis 3.2): the accumulated
// weight-sums of depth, normal and colour of a pixel are divided by the weight, and the pixel is lit with
// the blended normal (two-sided: turned towards the viewer), four pixels at a time, or eight with AVX2
// where the CPU has it (deferred_shader_avx2.cpp: the same arithmetic, bitwise the same images).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/splat/ewa_splat.h"
#include "relaxed_connectivity/render/splat/splat_config.h"

namespace rc {

/// Accumulated sums of one pixel span (structure of arrays, index 0 = first pixel of the span).
struct AccumulatedSpan {
  const float* weight;
  const float* color_weight;  ///< weight of the fragments that kept their colour (texture clipping, 4.3)
  const float* depth;         ///< sum of w z
  const float* color[3];      ///< sums of w rgb
  const float* normal[3];     ///< sums of w n (world frame)
  const int32_t* patch_id;    ///< patch of the largest weight
};

class DeferredShader {
 public:
  DeferredShader(const SplatConfig& config, const CameraFrame& camera);
  /// Writes pixels (x .. x + count - 1, y) of all output images from `span`.
  void shadeSpan(const AccumulatedSpan& span, int count, int x, int y, RenderImages* out) const;
  /// Writes background pixels (x .. x + count - 1, y).
  void clearSpan(int count, int x, int y, RenderImages* out) const;
  /// Each thread that shaded calls this once at the end (image writes bypass the caches).
  void finish() const;

 private:
  static constexpr int kSpecularTableSteps = 1024;  ///< cos^shininess over [0, 1], interpolated
  void shadePixel(const AccumulatedSpan& span, int k, int x, int y, size_t p, RenderImages* out) const;
  /// Pixels k .. k + 7 of the span, all with positive weight (AVX2).
  void shadeEight(const AccumulatedSpan& span, int k, int x, int y, size_t p, RenderImages* out) const;
  float highlight(float cosine) const;

  const SplatConfig& config_;
  bool perspective_;
  float cx_, cy_, inv_fx_, inv_fy_;
  uint32_t width_;
  uint32_t outputs_;  ///< RenderOutput flags
  bool wide_;         ///< shadeEight where eight pixels in a row are covered
  Eigen::Matrix3f camera_R_world_;
  Eigen::Vector3f to_light_;  ///< camera frame
  float ambient_, diffuse_, specular_;
  std::array<float, kSpecularTableSteps + 2> specular_table_;
};

}  // namespace rc
