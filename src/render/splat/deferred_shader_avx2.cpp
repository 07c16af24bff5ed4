// DeferredShader::shadeEight: the four-wide shading of deferred_shader.cpp eight pixels at a time (AVX2),
// operation for operation, so the images are bitwise the same. Called only where the CPU has AVX2.
#include <algorithm>
#include <cstdint>
#include <stdexcept>

#include "relaxed_connectivity/render/splat/deferred_shader.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define RC_AVX2_SHADING 1
#include <immintrin.h>
#endif

namespace rc {

#if defined(RC_AVX2_SHADING)
#pragma GCC push_options
#pragma GCC target("avx2")

namespace {

/// Eight output values (plain stores, as the four-wide store()).
inline void store8(float* address, __m256 value) {
  _mm256_storeu_ps(address, value);
}

/// Four unit normals (x y z x | y z x y | z x y z).
inline void storeNormals(float* normals, __m128 nx, __m128 ny, __m128 nz) {
  const __m128 xy_lo = _mm_unpacklo_ps(nx, ny), xy_hi = _mm_unpackhi_ps(nx, ny);
  const __m128 zx = _mm_shuffle_ps(nz, nx, _MM_SHUFFLE(1, 1, 0, 0));
  const __m128 yz = _mm_shuffle_ps(ny, nz, _MM_SHUFFLE(1, 1, 1, 1));
  const __m128 zzxy = _mm_shuffle_ps(nz, xy_hi, _MM_SHUFFLE(3, 2, 2, 2));
  const __m128 xyzz = _mm_shuffle_ps(xy_hi, nz, _MM_SHUFFLE(3, 3, 3, 2));
  const __m128 rows[3] = {_mm_shuffle_ps(xy_lo, zx, _MM_SHUFFLE(2, 0, 1, 0)),
                          _mm_shuffle_ps(yz, xy_hi, _MM_SHUFFLE(1, 0, 2, 0)),
                          _mm_shuffle_ps(zzxy, xyzz, _MM_SHUFFLE(2, 1, 2, 0))};
  for (int r = 0; r < 3; ++r) _mm_storeu_ps(normals + 4 * r, rows[r]);
}

}  // namespace

void DeferredShader::shadeEight(const AccumulatedSpan& span, int k, int x, int y, size_t p,
                                RenderImages* out) const {
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 w = _mm256_loadu_ps(span.weight + k);
  if (outputs_ & kOutputWeight) store8(out->weight.data() + p, w);
  if (outputs_ & kOutputDepth)
    store8(out->depth.data() + p, _mm256_div_ps(_mm256_loadu_ps(span.depth + k), w));
  if (outputs_ & kOutputPatchId)
    store8(reinterpret_cast<float*>(out->patch_id.data() + p),
           _mm256_loadu_ps(reinterpret_cast<const float*>(span.patch_id + k)));
  if (!(outputs_ & (kOutputNormal | kOutputColor))) return;
  // Unit normal (zero where the blended normals cancel).
  __m256 n[3];
  for (int c = 0; c < 3; ++c) n[c] = _mm256_loadu_ps(span.normal[c] + k);
  const __m256 length2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(n[0], n[0]), _mm256_mul_ps(n[1], n[1])),
                                       _mm256_mul_ps(n[2], n[2]));
  const __m256 inv_length = _mm256_and_ps(_mm256_cmp_ps(length2, _mm256_set1_ps(1e-40f), _CMP_GT_OQ),
                                          _mm256_div_ps(one, _mm256_sqrt_ps(length2)));
  for (int c = 0; c < 3; ++c) n[c] = _mm256_mul_ps(n[c], inv_length);
  if (outputs_ & kOutputNormal) {
    float* normals = out->normal[p].data();
    storeNormals(normals, _mm256_castps256_ps128(n[0]), _mm256_castps256_ps128(n[1]),
                 _mm256_castps256_ps128(n[2]));
    storeNormals(normals + 12, _mm256_extractf128_ps(n[0], 1), _mm256_extractf128_ps(n[1], 1),
                 _mm256_extractf128_ps(n[2], 1));
  }
  if (!(outputs_ & kOutputColor)) return;
  // Base colour.
  const __m256 color_weight = _mm256_loadu_ps(span.color_weight + k);
  const __m256 has_color = _mm256_cmp_ps(color_weight, zero, _CMP_GT_OQ);
  const __m256 inv_cw = _mm256_div_ps(one, _mm256_blendv_ps(one, color_weight, has_color));
  __m256 rgb[3];
  for (int c = 0; c < 3; ++c)
    rgb[c] = _mm256_blendv_ps(_mm256_set1_ps(float(config_.default_color[c])),
                              _mm256_mul_ps(_mm256_loadu_ps(span.color[c] + k), inv_cw), has_color);
  if (config_.shading) {
    // Direction to the eye (camera frame).
    __m256 e[3];
    if (perspective_) {
      const __m256 xs = _mm256_add_ps(_mm256_set1_ps(float(x + k)), _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7));
      e[0] = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(cx_), xs), _mm256_set1_ps(inv_fx_));
      e[1] = _mm256_set1_ps(-(float(y) - cy_) * inv_fy_);
      const __m256 inv_e =
          _mm256_div_ps(one, _mm256_sqrt_ps(_mm256_add_ps(
                                 _mm256_add_ps(_mm256_mul_ps(e[0], e[0]), _mm256_mul_ps(e[1], e[1])), one)));
      e[0] = _mm256_mul_ps(e[0], inv_e);
      e[1] = _mm256_mul_ps(e[1], inv_e);
      e[2] = _mm256_sub_ps(zero, inv_e);
    } else {
      e[0] = e[1] = zero;
      e[2] = _mm256_set1_ps(-1.0f);
    }
    // Shading normal in the camera frame, turned towards the viewer (two-sided).
    __m256 s[3];
    for (int r = 0; r < 3; ++r)
      s[r] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(camera_R_world_(r, 0)), n[0]),
                                         _mm256_mul_ps(_mm256_set1_ps(camera_R_world_(r, 1)), n[1])),
                           _mm256_mul_ps(_mm256_set1_ps(camera_R_world_(r, 2)), n[2]));
    const __m256 facing = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(s[0], e[0]), _mm256_mul_ps(s[1], e[1])),
                                        _mm256_mul_ps(s[2], e[2]));
    const __m256 flip = _mm256_and_ps(_mm256_cmp_ps(facing, zero, _CMP_LT_OQ), _mm256_set1_ps(-0.0f));
    for (int r = 0; r < 3; ++r) s[r] = _mm256_xor_ps(s[r], flip);
    const __m256 light[3] = {_mm256_set1_ps(to_light_[0]), _mm256_set1_ps(to_light_[1]),
                             _mm256_set1_ps(to_light_[2])};
    const __m256 lambert = _mm256_max_ps(
        zero, _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(s[0], light[0]), _mm256_mul_ps(s[1], light[1])),
                            _mm256_mul_ps(s[2], light[2])));
    // Reflected light direction . eye -> the interpolated cos^shininess table.
    const __m256 two_lambert = _mm256_add_ps(lambert, lambert);
    __m256 cosine = zero;
    for (int r = 0; r < 3; ++r)
      cosine = _mm256_add_ps(cosine,
                             _mm256_mul_ps(_mm256_sub_ps(_mm256_mul_ps(two_lambert, s[r]), light[r]), e[r]));
    const __m256 t = _mm256_mul_ps(_mm256_min_ps(_mm256_max_ps(cosine, zero), one),
                                   _mm256_set1_ps(float(kSpecularTableSteps)));
    const __m256i step = _mm256_cvttps_epi32(_mm256_min_ps(t, _mm256_set1_ps(kSpecularTableSteps - 1)));
    const __m256 below = _mm256_i32gather_ps(specular_table_.data(), step, 4);
    const __m256 above = _mm256_i32gather_ps(specular_table_.data() + 1, step, 4);
    const __m256 shine = _mm256_and_ps(
        _mm256_cmp_ps(lambert, zero, _CMP_GT_OQ),
        _mm256_add_ps(
            below, _mm256_mul_ps(_mm256_sub_ps(t, _mm256_cvtepi32_ps(step)), _mm256_sub_ps(above, below))));
    const __m256 intensity =
        _mm256_add_ps(_mm256_set1_ps(ambient_), _mm256_mul_ps(_mm256_set1_ps(diffuse_), lambert));
    const __m256 added = _mm256_mul_ps(_mm256_set1_ps(255.0f * specular_), shine);
    for (int c = 0; c < 3; ++c) rgb[c] = _mm256_add_ps(_mm256_mul_ps(rgb[c], intensity), added);
  }
  // Round to bytes and interleave r, g, b, a.
  __m256i packed = _mm256_set1_epi32(int32_t(uint32_t(config_.default_color[3]) << 24));
  const __m256 hi = _mm256_set1_ps(255.0f), half = _mm256_set1_ps(0.5f);
  for (int c = 0; c < 3; ++c) {
    const __m256i channel =
        _mm256_cvttps_epi32(_mm256_add_ps(_mm256_min_ps(hi, _mm256_max_ps(zero, rgb[c])), half));
    packed = _mm256_or_si256(packed, _mm256_slli_epi32(channel, 8 * c));
  }
  store8(reinterpret_cast<float*>(out->color.data() + p), _mm256_castsi256_ps(packed));
}

#pragma GCC pop_options
#else

void DeferredShader::shadeEight(const AccumulatedSpan&, int, int, int, size_t, RenderImages*) const {
  throw std::logic_error("DeferredShader::shadeEight: this build has no AVX2 shading");
}

#endif

}  // namespace rc
