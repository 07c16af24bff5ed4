// Rasterization of one EWA splat inside one screen tile (thesis 3.2): the pixels inside the cut-off ellipse
// with their conic value r2 and the exact plane depth z, one pixel or four pixels (SSE2) at a time. Both
// variants use the same arithmetic, so coverage and depth agree between the renderer's passes.
#pragma once

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>

#include "relaxed_connectivity/render/splat/ewa_splat.h"

namespace rc {
namespace splat_tile {

constexpr int kTileSize = 32;
/// Splats whose box is at least this wide inside a tile solve each row's span; narrower ones test the
/// conic at every pixel of their box (no square root or division per row).
constexpr int kSpanMinWidth = 8;
constexpr int kTileStride = kTileSize + 8;  ///< row stride of the tile buffers: room for an 8-wide overrun
constexpr int kTileBufferSize = kTileSize * kTileStride;  ///< floats of one tile buffer

constexpr int kWeightTableSteps = 1024;  ///< Gaussian weight table over r2 in [0, 1]
using WeightTable = std::array<float, kWeightTableSteps + 1>;

/// Gaussian weight over r2 in [0, 1] (the kernel cut off at cutoff_radius, in units of the surfel radius),
/// times `sign` (-1: the table that un-splats, 5.7).
inline WeightTable makeWeightTable(double cutoff_radius, float sign = 1.0f) {
  WeightTable weight_table;
  const double cutoff_sigmas = cutoff_radius / kKernelSigmaPerRadius;
  for (int k = 0; k <= kWeightTableSteps; ++k)
    weight_table[k] = sign * float(std::exp(-0.5 * cutoff_sigmas * cutoff_sigmas * k / kWeightTableSteps));
  return weight_table;
}

struct TileRect {
  int x0, y0, x1, y1;  ///< inclusive pixel range
};

/// Narrows [*x_begin, *x_end] (the splat's box in the tile) to the pixels of row offset dv that can lie
/// inside the cut-off: the roots of a du^2 + 2 b dv du + c dv^2 = 1, widened by a pixel (the r2 test
/// decides). r2_row = c dv^2. False if the row misses the ellipse.
inline bool rowSpan(const SplatRaster& s, float dv, float r2_row, int* x_begin, int* x_end) {
  const float b_dv = s.conic_b * dv;
  const float discriminant = b_dv * b_dv - s.conic_a * (r2_row - 1.0f);
  if (!(discriminant >= 0)) return false;
  const float root = std::sqrt(discriminant), inv_a = 1.0f / s.conic_a;
  const float u_lo = s.center_u + (-b_dv - root) * inv_a, u_hi = s.center_u + (-b_dv + root) * inv_a;
  const int xb = *x_begin, xe = *x_end;
  *x_begin = std::max(xb, int(std::max(u_lo, float(xb))) - 1);
  *x_end = std::min(xe, int(std::min(u_hi, float(xe))) + 1);
  return true;
}

/// Calls visit(x, y, r2, z) for every pixel of the tile inside the cut-off ellipse of `s` (r2 <= 1), with
/// the clamped plane depth z. Coverage depends only on the splat and the tile, so both passes agree.
template <class Visit>
inline void rasterizeSplat(const SplatRaster& s, const TileRect& tile, Visit&& visit) {
  const int xb = std::max(int(s.x0), tile.x0), xe = std::min(int(s.x1), tile.x1);
  const int yb = std::max(int(s.y0), tile.y0), ye = std::min(int(s.y1), tile.y1);
  const float a = s.conic_a, b = s.conic_b, c = s.conic_c;
  const float n1 = s.depth_num[1], d1 = s.depth_den[0];
  const float z_lo = s.z_lo, z_hi = s.z_hi;
  const bool solve_span = xe - xb + 1 >= kSpanMinWidth;
  for (int y = yb; y <= ye; ++y) {
    const float dv = float(y) - s.center_v;
    const float r2_row = c * dv * dv, r2_cross = 2.0f * b * dv;
    int x_begin = xb, x_end = xe;
    if (solve_span && !rowSpan(s, dv, r2_row, &x_begin, &x_end)) continue;
    const float num_row = s.depth_num[0] + s.depth_num[2] * dv;
    const float den_row = 1.0f + s.depth_den[1] * dv;
    for (int x = x_begin; x <= x_end; ++x) {
      const float du = float(x) - s.center_u;
      const float r2 = (a * du + r2_cross) * du + r2_row;
      if (r2 > 1.0f) continue;
      float z = (num_row + n1 * du) / (den_row + d1 * du);
      z = z > z_lo ? z : z_lo;  // also maps +-inf and NaN into the range
      z = z < z_hi ? z : z_hi;
      visit(x, y, r2, z);
    }
  }
}

/// True if the centre of pixel (x, y) lies inside the cut-off ellipse of `s` (rasterizeSplat's arithmetic).
inline bool coversPixel(const SplatRaster& s, int x, int y) {
  const float dv = float(y) - s.center_v, du = float(x) - s.center_u;
  const float r2_row = s.conic_c * dv * dv, r2_cross = 2.0f * s.conic_b * dv;
  return (s.conic_a * du + r2_cross) * du + r2_row <= 1.0f;
}

/// Pass 2 with SplatConfig::exact_silhouettes: a fragment nearer than the pixel's front by more than its
/// depth tolerance lies outside the footprints that cover the pixel; it blends only where its own splat
/// covers the pixel (possible only for the differential renderer's later surfels, 5.7; a full render has
/// none). The unfiltered footprint is derived on first need (such fragments are rare).
class NearerFragmentTest {
 public:
  /// filter_variance: unfilteredFootprint's for this splat (0: the splat is unfiltered); < 0: no test.
  NearerFragmentTest(const SplatRaster& s, double filter_variance) : s_(s), filter_(filter_variance) {}
  bool active() const { return filter_ >= 0; }
  /// The splat's own footprint, or null if it covers no pixel centre.
  const SplatRaster* footprint() {
    if (state_ == kUnknown) state_ = unfilteredFootprint(s_, filter_, &footprint_) ? kCovers : kEmpty;
    return state_ == kCovers ? &footprint_ : nullptr;
  }
  bool covers(int x, int y) {
    const SplatRaster* f = footprint();
    return f && coversPixel(*f, x, y);
  }

 private:
  enum State { kUnknown, kCovers, kEmpty };
  const SplatRaster& s_;
  double filter_;
  State state_ = kUnknown;
  SplatRaster footprint_;
};

#if defined(__SSE2__)
/// coversPixel for the four pixels (x..x+3, y): all-ones lanes where covered.
inline __m128 coversPixels4(const SplatRaster& s, int x, int y) {
  const float dv = float(y) - s.center_v;
  const __m128 row = _mm_set1_ps(s.conic_c * dv * dv), cross = _mm_set1_ps(2.0f * s.conic_b * dv);
  const __m128 du =
      _mm_sub_ps(_mm_add_ps(_mm_set1_ps(float(x)), _mm_setr_ps(0, 1, 2, 3)), _mm_set1_ps(s.center_u));
  const __m128 r2 =
      _mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(s.conic_a), du), cross), du), row);
  return _mm_cmple_ps(r2, _mm_set1_ps(1.0f));
}

inline __m128 select(__m128 mask, __m128 if_true, __m128 if_false) {
  return _mm_or_ps(_mm_and_ps(mask, if_true), _mm_andnot_ps(mask, if_false));
}

/// rasterizeSplat four pixels at a time: visit(index, x, y, r2, z, mask) for each group of four pixels
/// (x..x+3, y) of a row with at least one inside the cut-off (mask), index = tile buffer index of pixel x.
/// Same arithmetic as rasterizeSplat, so both give the same coverage, r2 and z.
template <class Visit>
inline void rasterizeSplat4(const SplatRaster& s, const TileRect& tile, Visit&& visit) {
  const int xb = std::max(int(s.x0), tile.x0), xe = std::min(int(s.x1), tile.x1);
  const int yb = std::max(int(s.y0), tile.y0), ye = std::min(int(s.y1), tile.y1);
  const float b = s.conic_b, c = s.conic_c;
  const __m128 lane = _mm_setr_ps(0, 1, 2, 3), one = _mm_set1_ps(1.0f);
  const __m128 a = _mm_set1_ps(s.conic_a), center_u = _mm_set1_ps(s.center_u);
  const __m128 n1 = _mm_set1_ps(s.depth_num[1]), d1 = _mm_set1_ps(s.depth_den[0]);
  const __m128 z_lo = _mm_set1_ps(s.z_lo), z_hi = _mm_set1_ps(s.z_hi);
  const bool solve_span = xe - xb + 1 >= kSpanMinWidth;
  for (int y = yb; y <= ye; ++y) {
    const float dv = float(y) - s.center_v;
    const float r2_row = c * dv * dv, r2_cross = 2.0f * b * dv;
    int x_begin = xb, x_end = xe;
    if (solve_span && !rowSpan(s, dv, r2_row, &x_begin, &x_end)) continue;
    const __m128 row = _mm_set1_ps(r2_row), cross = _mm_set1_ps(r2_cross);
    const __m128 num_row = _mm_set1_ps(s.depth_num[0] + s.depth_num[2] * dv);
    const __m128 den_row = _mm_set1_ps(1.0f + s.depth_den[1] * dv);
    const __m128 last = _mm_set1_ps(float(x_end));
    const int base = (y - tile.y0) * kTileStride - tile.x0;
    for (int x = x_begin; x <= x_end; x += 4) {
      const __m128 xs = _mm_add_ps(_mm_set1_ps(float(x)), lane);
      const __m128 du = _mm_sub_ps(xs, center_u);
      const __m128 r2 = _mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_mul_ps(a, du), cross), du), row);
      const __m128 mask = _mm_and_ps(_mm_cmple_ps(r2, one), _mm_cmple_ps(xs, last));
      if (!_mm_movemask_ps(mask)) continue;
      __m128 z = _mm_div_ps(_mm_add_ps(num_row, _mm_mul_ps(n1, du)), _mm_add_ps(den_row, _mm_mul_ps(d1, du)));
      z = _mm_min_ps(_mm_max_ps(z, z_lo), z_hi);  // max(NaN, lo) = lo
      visit(base + x, x, y, r2, z, mask);
    }
  }
}
#endif

}  // namespace splat_tile
}  // namespace rc
