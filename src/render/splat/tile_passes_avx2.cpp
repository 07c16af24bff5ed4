#include "relaxed_connectivity/render/splat/tile_passes_avx2.h"

#include <algorithm>
#include <stdexcept>

// GCC: every function defined between push_options and pop_options, lambdas included, is compiled for AVX2;
// they run only after avx2TilePassesAvailable().
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define RC_AVX2_TILE_PASSES 1
#include <immintrin.h>
#endif

namespace rc {
namespace splat_tile {

#if defined(RC_AVX2_TILE_PASSES)

bool avx2TilePassesAvailable() {
  static const bool available = __builtin_cpu_supports("avx2");
  return available;
}

#pragma GCC push_options
#pragma GCC target("avx2")

namespace {

/// Boxes narrower than this are visited whole per row (at most two groups of eight).
constexpr int kWideSpanMinWidth = 16;

/// Calls visit(index, x, y, r2, z, mask) for every group of eight pixels of the splat in the tile with at
/// least one inside the cut-off; the same arithmetic as rasterizeSplat4.
template <class Visit>
inline void rasterizeSplat8(const SplatRaster& s, const TileRect& tile, Visit&& visit) {
  const int xb = std::max(int(s.x0), tile.x0), xe = std::min(int(s.x1), tile.x1);
  const int yb = std::max(int(s.y0), tile.y0), ye = std::min(int(s.y1), tile.y1);
  const float b = s.conic_b, c = s.conic_c;
  const __m256 lane = _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7), one = _mm256_set1_ps(1.0f);
  const __m256 a = _mm256_set1_ps(s.conic_a), center_u = _mm256_set1_ps(s.center_u);
  const __m256 n1 = _mm256_set1_ps(s.depth_num[1]), d1 = _mm256_set1_ps(s.depth_den[0]);
  const __m256 z_lo = _mm256_set1_ps(s.z_lo), z_hi = _mm256_set1_ps(s.z_hi);
  const bool solve_span = xe - xb + 1 >= kWideSpanMinWidth;
  for (int y = yb; y <= ye; ++y) {
    const float dv = float(y) - s.center_v;
    const float r2_row = c * dv * dv, r2_cross = 2.0f * b * dv;
    int x_begin = xb, x_end = xe;
    if (solve_span && !rowSpan(s, dv, r2_row, &x_begin, &x_end)) continue;
    const __m256 row = _mm256_set1_ps(r2_row), cross = _mm256_set1_ps(r2_cross);
    const __m256 num_row = _mm256_set1_ps(s.depth_num[0] + s.depth_num[2] * dv);
    const __m256 den_row = _mm256_set1_ps(1.0f + s.depth_den[1] * dv);
    const __m256 last = _mm256_set1_ps(float(x_end));
    const int base = (y - tile.y0) * kTileStride - tile.x0;
    for (int x = x_begin; x <= x_end; x += 8) {
      const __m256 xs = _mm256_add_ps(_mm256_set1_ps(float(x)), lane);
      const __m256 du = _mm256_sub_ps(xs, center_u);
      const __m256 r2 = _mm256_add_ps(_mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(a, du), cross), du), row);
      const __m256 mask =
          _mm256_and_ps(_mm256_cmp_ps(r2, one, _CMP_LE_OQ), _mm256_cmp_ps(xs, last, _CMP_LE_OQ));
      if (!_mm256_movemask_ps(mask)) continue;
      __m256 z = _mm256_div_ps(_mm256_add_ps(num_row, _mm256_mul_ps(n1, du)),
                               _mm256_add_ps(den_row, _mm256_mul_ps(d1, du)));
      z = _mm256_min_ps(_mm256_max_ps(z, z_lo), z_hi);  // max(NaN, lo) = lo
      visit(base + x, x, y, r2, z, mask);
    }
  }
}

/// coversPixel for the eight pixels (x..x+7, y).
inline __m256 coversPixels8(const SplatRaster& s, int x, int y) {
  const float dv = float(y) - s.center_v;
  const __m256 row = _mm256_set1_ps(s.conic_c * dv * dv), cross = _mm256_set1_ps(2.0f * s.conic_b * dv);
  const __m256 du =
      _mm256_sub_ps(_mm256_add_ps(_mm256_set1_ps(float(x)), _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7)),
                    _mm256_set1_ps(s.center_u));
  const __m256 r2 = _mm256_add_ps(
      _mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(s.conic_a), du), cross), du), row);
  return _mm256_cmp_ps(r2, _mm256_set1_ps(1.0f), _CMP_LE_OQ);
}

inline void addTo(float* buffer, __m256 value) {
  _mm256_storeu_ps(buffer, _mm256_add_ps(_mm256_loadu_ps(buffer), value));
}

}  // namespace

void visibilitySplatAvx2(const SplatRaster& s, const TileRect& tile, float* bound, float* front) {
  const __m256 tolerance = _mm256_set1_ps(s.depth_tolerance);
  rasterizeSplat8(s, tile, [&](int i, int, int, __m256, __m256 z, __m256 mask) {
    const __m256 b = _mm256_loadu_ps(bound + i), f = _mm256_loadu_ps(front + i);
    _mm256_storeu_ps(bound + i, _mm256_blendv_ps(b, _mm256_min_ps(b, _mm256_add_ps(z, tolerance)), mask));
    const __m256 nearer = _mm256_and_ps(mask, _mm256_cmp_ps(z, f, _CMP_LT_OQ));
    _mm256_storeu_ps(front + i, _mm256_blendv_ps(f, z, nearer));
  });
}

size_t accumulateSplatAvx2(const SplatRaster& s, const TileRect& tile, const float* bound, const float* front,
                           const SplatBlend& blend, const float* weight_table, int table_steps,
                           const TileSums& sums, double nearer_filter) {
  NearerFragmentTest nearer(s, nearer_filter);
  const __m256 tolerance = _mm256_set1_ps(s.depth_tolerance);
  const __m256 steps = _mm256_set1_ps(float(table_steps)), half = _mm256_set1_ps(0.5f);
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 normal0 = _mm256_set1_ps(blend.normal[0]), normal1 = _mm256_set1_ps(blend.normal[1]),
               normal2 = _mm256_set1_ps(blend.normal[2]);
  const __m256 color0 = _mm256_set1_ps(blend.color[0]), color1 = _mm256_set1_ps(blend.color[1]),
               color2 = _mm256_set1_ps(blend.color[2]);
  const __m256 patch = _mm256_castsi256_ps(_mm256_set1_epi32(blend.patch_id));
  size_t fragments = 0;
  rasterizeSplat8(s, tile, [&](int i, int x, int y, __m256 r2, __m256 z, __m256 mask) {
    const __m256 f = _mm256_loadu_ps(front + i);
    __m256 pass = _mm256_and_ps(_mm256_and_ps(mask, _mm256_cmp_ps(z, _mm256_loadu_ps(bound + i), _CMP_LE_OQ)),
                                _mm256_cmp_ps(_mm256_sub_ps(z, tolerance), f, _CMP_LE_OQ));
    if (nearer.active()) {
      const __m256 closer = _mm256_and_ps(pass, _mm256_cmp_ps(_mm256_add_ps(z, tolerance), f, _CMP_LT_OQ));
      if (_mm256_movemask_ps(closer)) {
        const SplatRaster* own = nearer.footprint();
        const __m256 covered = own ? coversPixels8(*own, x, y) : _mm256_setzero_ps();
        pass = _mm256_andnot_ps(_mm256_andnot_ps(covered, closer), pass);
      }
    }
    const int bits = _mm256_movemask_ps(pass);
    if (!bits) return;
    fragments += size_t(__builtin_popcount(unsigned(bits)));
    const __m256 clamped = _mm256_min_ps(_mm256_max_ps(r2, zero), one);
    const __m256i step = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(clamped, steps), half));
    const __m256 w = _mm256_and_ps(pass, _mm256_i32gather_ps(weight_table, step, 4));
    addTo(sums.weight + i, w);
    if (sums.depth) addTo(sums.depth + i, _mm256_mul_ps(w, z));
    if (sums.normal[0]) {
      addTo(sums.normal[0] + i, _mm256_mul_ps(w, normal0));
      addTo(sums.normal[1] + i, _mm256_mul_ps(w, normal1));
      addTo(sums.normal[2] + i, _mm256_mul_ps(w, normal2));
    }
    if (sums.color[0]) {
      addTo(sums.color[0] + i, _mm256_mul_ps(w, color0));
      addTo(sums.color[1] + i, _mm256_mul_ps(w, color1));
      addTo(sums.color[2] + i, _mm256_mul_ps(w, color2));
    }
    if (!sums.patch_id) return;
    const __m256 max_weight = _mm256_loadu_ps(sums.max_weight + i);
    const __m256 larger = _mm256_cmp_ps(w, max_weight, _CMP_GT_OQ);
    _mm256_storeu_ps(sums.max_weight + i, _mm256_blendv_ps(max_weight, w, larger));
    float* patch_ids = reinterpret_cast<float*>(sums.patch_id + i);
    _mm256_storeu_ps(patch_ids, _mm256_blendv_ps(_mm256_loadu_ps(patch_ids), patch, larger));
  });
  return fragments;
}

#pragma GCC pop_options

#else  // no AVX2 passes in this build

bool avx2TilePassesAvailable() {
  return false;
}

void visibilitySplatAvx2(const SplatRaster&, const TileRect&, float*, float*) {
  throw std::logic_error("visibilitySplatAvx2: this build has no AVX2 tile passes");
}

size_t accumulateSplatAvx2(const SplatRaster&, const TileRect&, const float*, const float*, const SplatBlend&,
                           const float*, int, const TileSums&, double) {
  throw std::logic_error("accumulateSplatAvx2: this build has no AVX2 tile passes");
}

#endif

}  // namespace splat_tile
}  // namespace rc
