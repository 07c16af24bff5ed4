#include "relaxed_connectivity/render/splat/deferred_shader.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "relaxed_connectivity/render/splat/tile_passes_avx2.h"

namespace rc {

namespace {

uint8_t toChannel(float value) {
  return uint8_t(std::min(255.0f, std::max(0.0f, value)) + 0.5f);
}

}  // namespace

DeferredShader::DeferredShader(const SplatConfig& config, const CameraFrame& camera)
    : config_(config),
      perspective_(camera.perspective),
      cx_(float(camera.cx)),
      cy_(float(camera.cy)),
      inv_fx_(float(1.0 / camera.fx)),
      inv_fy_(float(1.0 / camera.fy)),
      width_(camera.width),
      outputs_(config.outputs),
      wide_(config.wide_simd && splat_tile::avx2TilePassesAvailable()),
      camera_R_world_(camera.camera_R_world.cast<float>()),
      to_light_((-config.light_direction_camera.normalized()).cast<float>()),
      ambient_(float(config.ambient)),
      diffuse_(float(config.diffuse)),
      specular_(float(config.specular)) {
  for (int k = 0; k <= kSpecularTableSteps + 1; ++k)
    specular_table_[k] = float(std::pow(std::min(1.0, double(k) / kSpecularTableSteps), config.shininess));
}

float DeferredShader::highlight(float cosine) const {
  const float t = std::min(1.0f, std::max(0.0f, cosine)) * kSpecularTableSteps;
  const int step = std::min(int(t), kSpecularTableSteps - 1);
  return specular_table_[step] + (t - float(step)) * (specular_table_[step + 1] - specular_table_[step]);
}

#if defined(__SSE2__)
namespace {
/// Four output values. Plain stores: streaming (non-temporal) ones took twice the shading time at 1280x720
/// on this 2-core VM (the images' short tile rows in several outputs at once; bench_paint_rendering).
inline void store(float* address, __m128 value) {
  _mm_storeu_ps(address, value);
}
}  // namespace
#endif

void DeferredShader::clearSpan(int count, int x, int y, RenderImages* out) const {
  const size_t p = size_t(y) * width_ + x;
  int k = 0;
#if defined(__SSE2__)
  const __m128 zero = _mm_setzero_ps(), infinity = _mm_set1_ps(std::numeric_limits<float>::infinity());
  const __m128 no_patch = _mm_castsi128_ps(_mm_set1_epi32(-1));
  uint32_t background;
  std::memcpy(&background, &config_.background, sizeof(background));
  const __m128 background4 = _mm_castsi128_ps(_mm_set1_epi32(int32_t(background)));
  for (; k + 4 <= count; k += 4) {
    if (outputs_ & kOutputWeight) store(out->weight.data() + p + k, zero);
    if (outputs_ & kOutputDepth) store(out->depth.data() + p + k, infinity);
    if (outputs_ & kOutputNormal)
      for (int c = 0; c < 3; ++c) store(out->normal[p + k].data() + 4 * c, zero);
    if (outputs_ & kOutputPatchId) store(reinterpret_cast<float*>(out->patch_id.data() + p + k), no_patch);
    if (outputs_ & kOutputColor) store(reinterpret_cast<float*>(out->color.data() + p + k), background4);
  }
#endif
  const size_t q = p + k, rest = size_t(count - k);
  if (outputs_ & kOutputWeight) std::fill_n(out->weight.begin() + q, rest, 0.0f);
  if (outputs_ & kOutputDepth)
    std::fill_n(out->depth.begin() + q, rest, std::numeric_limits<float>::infinity());
  if (outputs_ & kOutputNormal) std::fill_n(out->normal.begin() + q, rest, Eigen::Vector3f::Zero());
  if (outputs_ & kOutputPatchId) std::fill_n(out->patch_id.begin() + q, rest, -1);
  if (outputs_ & kOutputColor) std::fill_n(out->color.begin() + q, rest, config_.background);
}

void DeferredShader::shadePixel(const AccumulatedSpan& span, int k, int x, int y, size_t p,
                                RenderImages* out) const {
  const float weight = span.weight[k];
  if (!(weight > 0)) {
    clearSpan(1, x, y, out);
    return;
  }
  if (outputs_ & kOutputWeight) out->weight[p] = weight;
  if (outputs_ & kOutputDepth) out->depth[p] = span.depth[k] / weight;
  const Eigen::Vector3f blended(span.normal[0][k], span.normal[1][k], span.normal[2][k]);
  const float length2 = blended.squaredNorm();
  const Eigen::Vector3f normal =
      length2 > 1e-40f ? Eigen::Vector3f(blended * (1.0f / std::sqrt(length2))) : Eigen::Vector3f::Zero();
  if (outputs_ & kOutputNormal) out->normal[p] = normal;
  if (outputs_ & kOutputPatchId) out->patch_id[p] = span.patch_id[k];
  if (!(outputs_ & kOutputColor)) return;
  const float color_weight = span.color_weight[k];
  float base[3];
  for (int c = 0; c < 3; ++c)
    base[c] = color_weight > 0 ? span.color[c][k] * (1.0f / color_weight) : float(config_.default_color[c]);
  const uint8_t alpha = config_.default_color[3];
  if (!config_.shading) {
    out->color[p] = {toChannel(base[0]), toChannel(base[1]), toChannel(base[2]), alpha};
    return;
  }
  Eigen::Vector3f to_eye(0, 0, -1);
  if (perspective_) {
    const float vx = -(float(x) - cx_) * inv_fx_, vy = -(float(y) - cy_) * inv_fy_;
    to_eye = Eigen::Vector3f(vx, vy, -1.0f) * (1.0f / std::sqrt(vx * vx + vy * vy + 1.0f));
  }
  Eigen::Vector3f shading_normal = camera_R_world_ * normal;
  if (shading_normal.dot(to_eye) < 0) shading_normal = -shading_normal;
  const float lambert = std::max(0.0f, shading_normal.dot(to_light_));
  const float shine =
      lambert > 0 ? highlight((2.0f * lambert * shading_normal - to_light_).dot(to_eye)) : 0.0f;
  const float intensity = ambient_ + diffuse_ * lambert, added = 255.0f * specular_ * shine;
  out->color[p] = {toChannel(base[0] * intensity + added), toChannel(base[1] * intensity + added),
                   toChannel(base[2] * intensity + added), alpha};
}

void DeferredShader::finish() const {
#if defined(__SSE2__)
  _mm_sfence();  // (any streamed stores are visible to other threads after this)
#endif
}

void DeferredShader::shadeSpan(const AccumulatedSpan& span, int count, int x, int y,
                               RenderImages* out) const {
  const size_t p0 = size_t(y) * width_ + x;
  int k = 0;
#if defined(__SSE2__)
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
  for (; k + 4 <= count; k += 4) {
    const __m128 w = _mm_loadu_ps(span.weight + k);
    const int valid = _mm_movemask_ps(_mm_cmpgt_ps(w, zero));
    if (wide_ && valid == 0xF && k + 8 <= count &&
        _mm_movemask_ps(_mm_cmpgt_ps(_mm_loadu_ps(span.weight + k + 4), zero)) == 0xF) {
      shadeEight(span, k, x, y, p0 + k, out);
      k += 4;
      continue;
    }
    if (valid == 0) {
      clearSpan(4, x + k, y, out);
      continue;
    }
    if (valid != 0xF) {  // silhouette: per pixel
      for (int l = 0; l < 4; ++l) shadePixel(span, k + l, x + k + l, y, p0 + k + l, out);
      continue;
    }
    const size_t p = p0 + k;
    if (outputs_ & kOutputWeight) store(out->weight.data() + p, w);
    if (outputs_ & kOutputDepth) store(out->depth.data() + p, _mm_div_ps(_mm_loadu_ps(span.depth + k), w));
    if (outputs_ & kOutputPatchId)
      store(reinterpret_cast<float*>(out->patch_id.data() + p),
            _mm_loadu_ps(reinterpret_cast<const float*>(span.patch_id + k)));
    if (!(outputs_ & (kOutputNormal | kOutputColor))) continue;
    // Unit normal (zero where the blended normals cancel).
    __m128 n[3];
    for (int c = 0; c < 3; ++c) n[c] = _mm_loadu_ps(span.normal[c] + k);
    const __m128 length2 =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(n[0], n[0]), _mm_mul_ps(n[1], n[1])), _mm_mul_ps(n[2], n[2]));
    const __m128 inv_length =
        _mm_and_ps(_mm_cmpgt_ps(length2, _mm_set1_ps(1e-40f)), _mm_div_ps(one, _mm_sqrt_ps(length2)));
    for (int c = 0; c < 3; ++c) n[c] = _mm_mul_ps(n[c], inv_length);
    if (outputs_ & kOutputNormal) {  // x y z x | y z x y | z x y z
      const __m128 xy_lo = _mm_unpacklo_ps(n[0], n[1]), xy_hi = _mm_unpackhi_ps(n[0], n[1]);
      const __m128 zx = _mm_shuffle_ps(n[2], n[0], _MM_SHUFFLE(1, 1, 0, 0));
      const __m128 yz = _mm_shuffle_ps(n[1], n[2], _MM_SHUFFLE(1, 1, 1, 1));
      const __m128 zzxy = _mm_shuffle_ps(n[2], xy_hi, _MM_SHUFFLE(3, 2, 2, 2));
      const __m128 xyzz = _mm_shuffle_ps(xy_hi, n[2], _MM_SHUFFLE(3, 3, 3, 2));
      float* normals = out->normal[p].data();
      store(normals, _mm_shuffle_ps(xy_lo, zx, _MM_SHUFFLE(2, 0, 1, 0)));
      store(normals + 4, _mm_shuffle_ps(yz, xy_hi, _MM_SHUFFLE(1, 0, 2, 0)));
      store(normals + 8, _mm_shuffle_ps(zzxy, xyzz, _MM_SHUFFLE(2, 1, 2, 0)));
    }
    if (!(outputs_ & kOutputColor)) continue;
    // Base colour.
    const __m128 color_weight = _mm_loadu_ps(span.color_weight + k);
    const __m128 has_color = _mm_cmpgt_ps(color_weight, zero);
    const __m128 inv_cw =
        _mm_div_ps(one, _mm_or_ps(_mm_and_ps(has_color, color_weight), _mm_andnot_ps(has_color, one)));
    __m128 base[3];
    for (int c = 0; c < 3; ++c)
      base[c] = _mm_or_ps(_mm_and_ps(has_color, _mm_mul_ps(_mm_loadu_ps(span.color[c] + k), inv_cw)),
                          _mm_andnot_ps(has_color, _mm_set1_ps(float(config_.default_color[c]))));
    __m128 rgb[3] = {base[0], base[1], base[2]};
    if (config_.shading) {
      // Direction to the eye (camera frame).
      __m128 e[3];
      if (perspective_) {
        const __m128 xs = _mm_add_ps(_mm_set1_ps(float(x + k)), _mm_setr_ps(0, 1, 2, 3));
        e[0] = _mm_mul_ps(_mm_sub_ps(_mm_set1_ps(cx_), xs), _mm_set1_ps(inv_fx_));
        e[1] = _mm_set1_ps(-(float(y) - cy_) * inv_fy_);
        const __m128 inv_e = _mm_div_ps(
            one, _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(e[0], e[0]), _mm_mul_ps(e[1], e[1])), one)));
        e[0] = _mm_mul_ps(e[0], inv_e);
        e[1] = _mm_mul_ps(e[1], inv_e);
        e[2] = _mm_sub_ps(zero, inv_e);
      } else {
        e[0] = e[1] = zero;
        e[2] = _mm_set1_ps(-1.0f);
      }
      // Shading normal in the camera frame, turned towards the viewer (two-sided).
      __m128 s[3];
      for (int r = 0; r < 3; ++r)
        s[r] = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(camera_R_world_(r, 0)), n[0]),
                                     _mm_mul_ps(_mm_set1_ps(camera_R_world_(r, 1)), n[1])),
                          _mm_mul_ps(_mm_set1_ps(camera_R_world_(r, 2)), n[2]));
      const __m128 facing =
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(s[0], e[0]), _mm_mul_ps(s[1], e[1])), _mm_mul_ps(s[2], e[2]));
      const __m128 flip = _mm_and_ps(_mm_cmplt_ps(facing, zero), _mm_set1_ps(-0.0f));
      for (int r = 0; r < 3; ++r) s[r] = _mm_xor_ps(s[r], flip);
      const __m128 light[3] = {_mm_set1_ps(to_light_[0]), _mm_set1_ps(to_light_[1]),
                               _mm_set1_ps(to_light_[2])};
      const __m128 lambert =
          _mm_max_ps(zero, _mm_add_ps(_mm_add_ps(_mm_mul_ps(s[0], light[0]), _mm_mul_ps(s[1], light[1])),
                                      _mm_mul_ps(s[2], light[2])));
      // Reflected light direction . eye -> cos^shininess from the table.
      const __m128 two_lambert = _mm_add_ps(lambert, lambert);
      __m128 cosine = zero;
      for (int r = 0; r < 3; ++r)
        cosine = _mm_add_ps(cosine, _mm_mul_ps(_mm_sub_ps(_mm_mul_ps(two_lambert, s[r]), light[r]), e[r]));
      // highlight(cosine) four lanes at a time (same arithmetic), zero where the light is behind.
      const __m128 t =
          _mm_mul_ps(_mm_min_ps(_mm_max_ps(cosine, zero), one), _mm_set1_ps(kSpecularTableSteps));
      const __m128i step = _mm_cvttps_epi32(_mm_min_ps(t, _mm_set1_ps(kSpecularTableSteps - 1)));
      alignas(16) int32_t steps[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(steps), step);
      const float* table = specular_table_.data();
      const __m128 below = _mm_setr_ps(table[steps[0]], table[steps[1]], table[steps[2]], table[steps[3]]);
      const __m128 above =
          _mm_setr_ps(table[steps[0] + 1], table[steps[1] + 1], table[steps[2] + 1], table[steps[3] + 1]);
      const __m128 shine = _mm_and_ps(
          _mm_cmpgt_ps(lambert, zero),
          _mm_add_ps(below, _mm_mul_ps(_mm_sub_ps(t, _mm_cvtepi32_ps(step)), _mm_sub_ps(above, below))));
      const __m128 intensity = _mm_add_ps(_mm_set1_ps(ambient_), _mm_mul_ps(_mm_set1_ps(diffuse_), lambert));
      const __m128 added = _mm_mul_ps(_mm_set1_ps(255.0f * specular_), shine);
      for (int c = 0; c < 3; ++c) rgb[c] = _mm_add_ps(_mm_mul_ps(base[c], intensity), added);
    }
    // Round to bytes and interleave r, g, b, a.
    __m128i packed = _mm_set1_epi32(int32_t(uint32_t(config_.default_color[3]) << 24));
    const __m128 lo = zero, hi = _mm_set1_ps(255.0f), half = _mm_set1_ps(0.5f);
    for (int c = 0; c < 3; ++c) {
      const __m128i channel = _mm_cvttps_epi32(_mm_add_ps(_mm_min_ps(hi, _mm_max_ps(lo, rgb[c])), half));
      packed = _mm_or_si128(packed, _mm_slli_epi32(channel, 8 * c));
    }
    static_assert(sizeof(Rgba) == 4, "Rgba is four bytes");
    store(reinterpret_cast<float*>(out->color.data() + p), _mm_castsi128_ps(packed));
  }
#endif
  for (; k < count; ++k) shadePixel(span, k, x + k, y, p0 + k, out);
}

}  // namespace rc
