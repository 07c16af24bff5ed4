#include "relaxed_connectivity/render/splat/circular_setup_avx2.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "relaxed_connectivity/render/splat/tile_passes_avx2.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define RC_AVX2_SETUP 1
#include <immintrin.h>
#endif

namespace rc {

#if defined(RC_AVX2_SETUP)

bool circularSetupAvx2Available() {
  return splat_tile::avx2TilePassesAvailable();
}

#pragma GCC push_options
#pragma GCC target("avx2")

namespace {

using V = __m256d;
inline V set1(double value) {
  return _mm256_set1_pd(value);
}
inline V add(V a, V b) {
  return _mm256_add_pd(a, b);
}
inline V sub(V a, V b) {
  return _mm256_sub_pd(a, b);
}
inline V mul(V a, V b) {
  return _mm256_mul_pd(a, b);
}
inline V div(V a, V b) {
  return _mm256_div_pd(a, b);
}
/// std::min / std::max operand order: min(a, b) = b < a ? b : a.
inline V minOf(V a, V b) {
  return _mm256_blendv_pd(a, b, _mm256_cmp_pd(b, a, _CMP_LT_OQ));
}
inline V maxOf(V a, V b) {
  return _mm256_blendv_pd(a, b, _mm256_cmp_pd(a, b, _CMP_LT_OQ));
}
inline V lane(const Vec3* v, int axis) {
  return _mm256_setr_pd(v[0][axis], v[1][axis], v[2][axis], v[3][axis]);
}
/// Eigen's fixed 3x3 matrix-vector product, row r: (m(r,0) x + m(r,1) y) + m(r,2) z.
inline V row(const Eigen::Matrix3d& m, int r, V x, V y, V z) {
  return add(add(mul(set1(m(r, 0)), x), mul(set1(m(r, 1)), y)), mul(set1(m(r, 2)), z));
}
/// ceilToPixel / floorToPixel of ewa_splat.cpp.
inline __m128i ceilToPixel(V value, double size) {
  const V clamped = minOf(maxOf(value, set1(-1.0)), set1(size));  // std::clamp for finite values
  const __m128i truncated = _mm256_cvttpd_epi32(clamped);
  const V below = _mm256_cmp_pd(_mm256_cvtepi32_pd(truncated), clamped, _CMP_LT_OQ);
  return _mm_sub_epi32(truncated, _mm256_cvtpd_epi32(_mm256_and_pd(below, set1(-1.0))));
}
inline __m128i floorToPixel(V value, double size) {
  const V clamped = minOf(maxOf(value, set1(-1.0)), set1(size));
  const __m128i truncated = _mm256_cvttpd_epi32(clamped);
  const V above = _mm256_cmp_pd(_mm256_cvtepi32_pd(truncated), clamped, _CMP_GT_OQ);
  return _mm_add_epi32(truncated, _mm256_cvtpd_epi32(_mm256_and_pd(above, set1(-1.0))));
}

/// Four surfels in the camera frame: the unit normal u = n / |n|, c = R p + t, n_c = R u, n_c . c and the
/// first test of setupCircularCommonCase (near/far clip, back-face).
struct CameraLanes {
  CameraLanes(const Vec3* centers, const Vec3* normals, const CameraFrame& camera, const EwaParams& params) {
    nx_in = lane(normals, 0), ny_in = lane(normals, 1), nz_in = lane(normals, 2);
    normal_length = _mm256_sqrt_pd(add(add(mul(nx_in, nx_in), mul(ny_in, ny_in)), mul(nz_in, nz_in)));
    const V inv_length = div(set1(1.0), normal_length);
    ux = mul(nx_in, inv_length), uy = mul(ny_in, inv_length), uz = mul(nz_in, inv_length);
    const Eigen::Matrix3d& R = camera.camera_R_world;
    px = lane(centers, 0), py = lane(centers, 1), pz = lane(centers, 2);
    cx = add(row(R, 0, px, py, pz), set1(camera.camera_t_world.x()));
    cy = add(row(R, 1, px, py, pz), set1(camera.camera_t_world.y()));
    cz = add(row(R, 2, px, py, pz), set1(camera.camera_t_world.z()));
    nx = row(R, 0, ux, uy, uz), ny = row(R, 1, ux, uy, uz), nz = row(R, 2, ux, uy, uz);
    n_dot_view = add(add(mul(nx, cx), mul(ny, cy)), mul(nz, cz));
    culled = _mm256_or_pd(_mm256_cmp_pd(cz, set1(camera.near_clip), _CMP_NGE_UQ),
                          _mm256_cmp_pd(cz, set1(camera.far_clip), _CMP_NLE_UQ));
    if (params.backface_culling)
      culled = _mm256_or_pd(culled, _mm256_cmp_pd(n_dot_view, set1(0.0), _CMP_GT_OQ));
  }
  V nx_in, ny_in, nz_in, normal_length, ux, uy, uz, px, py, pz, cx, cy, cz, nx, ny, nz, n_dot_view, culled;
};

}  // namespace

void setupCircularEwaSplats4(const Vec3* centers, const Vec3* normals, const double* radii,
                             const CameraFrame& camera, const EwaParams& params, SplatRaster rasters[4],
                             float unit_normals[4][3], SplatSetup results[4]) {
  // Lanes decided here: 0 undecided, else the result; 'fallback' lanes go to the scalar set-up.
  bool fallback[4] = {false, false, false, false};
  bool decided[4] = {false, false, false, false};
  for (int k = 0; k < 4; ++k) {
    if (!centers[k].allFinite() || !normals[k].allFinite() || !std::isfinite(radii[k])) {
      results[k] = SplatSetup::kInvalid;
      decided[k] = true;
    }
  }
  const CameraLanes l(centers, normals, camera, params);
  const V radius = _mm256_andnot_pd(set1(-0.0), _mm256_loadu_pd(radii));  // |radius|
  alignas(32) double lengths[4], radius_lanes[4];
  _mm256_store_pd(lengths, l.normal_length);
  _mm256_store_pd(radius_lanes, radius);
  for (int k = 0; k < 4; ++k) {
    if (!decided[k] && (!(lengths[k] > 0) || !(radius_lanes[k] > 0))) {
      results[k] = SplatSetup::kInvalid;
      decided[k] = true;
    }
  }
  alignas(32) double unit[3][4];
  _mm256_store_pd(unit[0], l.ux);
  _mm256_store_pd(unit[1], l.uy);
  _mm256_store_pd(unit[2], l.uz);
  for (int k = 0; k < 4; ++k)
    for (int a = 0; a < 3; ++a) unit_normals[k][a] = float(unit[a][k]);

  // setupCircularCommonCase, perspective.
  const V cx = l.cx, cy = l.cy, cz = l.cz, nx = l.nx, ny = l.ny, nz = l.nz, n_dot_view = l.n_dot_view;
  const V culled = l.culled;
  const V r2 = mul(radius, radius);
  const V inv_z = div(set1(1.0), cz);
  const V j00 = mul(set1(camera.fx), inv_z), j02 = mul(mul(mul(set1(-camera.fx), cx), inv_z), inv_z);
  const V j11 = mul(set1(camera.fy), inv_z), j12 = mul(mul(mul(set1(-camera.fy), cy), inv_z), inv_z);
  const V jn0 = add(mul(j00, nx), mul(j02, nz)), jn1 = add(mul(j11, ny), mul(j12, nz));
  const V f00 = mul(r2, sub(add(mul(j00, j00), mul(j02, j02)), mul(jn0, jn0)));
  const V f01 = mul(r2, sub(mul(j02, j12), mul(jn0, jn1)));
  const V f11 = mul(r2, sub(add(mul(j11, j11), mul(j12, j12)), mul(jn1, jn1)));
  const V center_u = add(set1(camera.cx), mul(mul(set1(camera.fx), cx), inv_z));
  const V center_v = add(set1(camera.cy), mul(mul(set1(camera.fy), cy), inv_z));
  const V view_length2 = add(add(mul(cx, cx), mul(cy, cy)), mul(cz, cz));
  const V scale2 = add(f00, f11), det2 = sub(mul(f00, f11), mul(f01, f01));
  const V edge_on =
      _mm256_or_pd(_mm256_cmp_pd(mul(n_dot_view, n_dot_view),
                                 mul(set1(kEdgeOnCosine * kEdgeOnCosine), view_length2), _CMP_LT_OQ),
                   _mm256_cmp_pd(det2, mul(mul(set1(1e-18), scale2), scale2), _CMP_NGT_UQ));
  const double sigma2 = kKernelSigmaPerRadius * kKernelSigmaPerRadius;
  V c00 = mul(set1(sigma2), f00), c01 = mul(set1(sigma2), f01), c11 = mul(set1(sigma2), f11);
  if (params.ewa_filter) {
    c00 = add(c00, set1(params.lowpass_variance));
    c11 = add(c11, set1(params.lowpass_variance));
  }
  c00 = add(c00, set1(1e-6));
  c11 = add(c11, set1(1e-6));
  const double cutoff_sigmas = params.cutoff_radius / kKernelSigmaPerRadius;
  const V det = sub(mul(c00, c11), mul(c01, c01));
  const V bad_det = _mm256_or_pd(_mm256_cmp_pd(det, set1(0.0), _CMP_NGT_UQ),
                                 _mm256_cmp_pd(_mm256_andnot_pd(set1(-0.0), det),
                                               set1(std::numeric_limits<double>::infinity()), _CMP_NLT_UQ));
  const V conic_scale = div(set1(1.0), mul(mul(det, set1(cutoff_sigmas)), set1(cutoff_sigmas)));
  const V half_u = mul(set1(cutoff_sigmas), _mm256_sqrt_pd(c00));
  const V half_v = mul(set1(cutoff_sigmas), _mm256_sqrt_pd(c11));
  // pixelBox
  const __m128i x0 = _mm_max_epi32(_mm_setzero_si128(), ceilToPixel(sub(center_u, half_u), camera.width));
  const __m128i x1 = _mm_min_epi32(_mm_set1_epi32(int32_t(camera.width) - 1),
                                   floorToPixel(add(center_u, half_u), camera.width));
  const __m128i y0 = _mm_max_epi32(_mm_setzero_si128(), ceilToPixel(sub(center_v, half_v), camera.height));
  const __m128i y1 = _mm_min_epi32(_mm_set1_epi32(int32_t(camera.height) - 1),
                                   floorToPixel(add(center_v, half_v), camera.height));
  const __m128i empty = _mm_or_si128(_mm_cmpgt_epi32(x0, x1), _mm_cmpgt_epi32(y0, y1));
  // Depth range of the cut-off disc and the plane along the pixel rays (planeDepth, perspective).
  const V z_half_extent = mul(mul(set1(params.cutoff_radius), radius),
                              _mm256_sqrt_pd(maxOf(set1(0.0), sub(set1(1.0), mul(nz, nz)))));
  const V z_lo_disc = sub(cz, z_half_extent), z_hi_disc = add(cz, z_half_extent);
  const V d1 = div(nx, set1(camera.fx)), d2 = div(ny, set1(camera.fy));
  const V d0 = add(add(mul(d1, sub(center_u, set1(camera.cx))), mul(d2, sub(center_v, set1(camera.cy)))), nz);
  const V du_lo = sub(_mm256_cvtepi32_pd(x0), center_u), du_hi = sub(_mm256_cvtepi32_pd(x1), center_u);
  const V dv_lo = sub(_mm256_cvtepi32_pd(y0), center_v), dv_hi = sub(_mm256_cvtepi32_pd(y1), center_v);
  const V d_min = add(add(d0, minOf(mul(d1, du_lo), mul(d1, du_hi))), minOf(mul(d2, dv_lo), mul(d2, dv_hi)));
  const V d_max = add(add(d0, maxOf(mul(d1, du_lo), mul(d1, du_hi))), maxOf(mul(d2, dv_lo), mul(d2, dv_hi)));
  const V plane_undefined = _mm256_cmp_pd(mul(d_min, d_max), set1(0.0), _CMP_NGT_UQ);
  const V numerator = n_dot_view;  // n.dot(c)
  const V z_a = div(numerator, d_min), z_b = div(numerator, d_max);
  const V z_lo_float = _mm256_cvtps_pd(_mm256_cvtpd_ps(z_lo_disc));  // double(float(z_lo))
  const V z_hi_float = _mm256_cvtps_pd(_mm256_cvtpd_ps(z_hi_disc));
  const V z_lo = minOf(minOf(z_lo_float, z_a), z_b), z_hi = maxOf(maxOf(z_hi_float, z_a), z_b);
  const V inv_d0 = div(set1(1.0), d0);
  const V cos_view = div(_mm256_andnot_pd(set1(-0.0), n_dot_view), _mm256_sqrt_pd(view_length2));
  const V tolerance = add(div(mul(set1(params.depth_tolerance_scale * kFacingDepthTolerance),
                                  mul(set1(params.cutoff_radius), radius)),
                              maxOf(cos_view, set1(kMinToleranceCosine))),
                          mul(set1(1e-5), _mm256_andnot_pd(set1(-0.0), cz)));

  alignas(32) double out[16][4];
  int culled_mask = _mm256_movemask_pd(culled), edge_mask = _mm256_movemask_pd(edge_on);
  // Large splats: the exact footprint of the scalar set-up (kExactFootprintRatio).
  const int large_mask =
      params.exact_footprint
          ? _mm256_movemask_pd(_mm256_cmp_pd(mul(set1(params.cutoff_radius), radius),
                                             mul(set1(kExactFootprintRatio), cz), _CMP_GT_OQ))
          : 0;
  const int bad_det_mask = _mm256_movemask_pd(bad_det), empty_mask = _mm_movemask_ps(_mm_castsi128_ps(empty));
  const int undefined_mask = _mm256_movemask_pd(plane_undefined);
  _mm256_store_pd(out[0], center_u);
  _mm256_store_pd(out[1], center_v);
  _mm256_store_pd(out[2], mul(c11, conic_scale));
  _mm256_store_pd(out[3], mul(sub(set1(0.0), c01), conic_scale));
  _mm256_store_pd(out[4], mul(c00, conic_scale));
  _mm256_store_pd(out[5], z_lo);
  _mm256_store_pd(out[6], z_hi);
  _mm256_store_pd(out[7], mul(numerator, inv_d0));
  _mm256_store_pd(out[8], mul(d1, inv_d0));
  _mm256_store_pd(out[9], mul(d2, inv_d0));
  _mm256_store_pd(out[10], tolerance);
  _mm256_store_pd(out[11], n_dot_view);
  alignas(16) int32_t box[4][4];
  _mm_store_si128(reinterpret_cast<__m128i*>(box[0]), x0);
  _mm_store_si128(reinterpret_cast<__m128i*>(box[1]), x1);
  _mm_store_si128(reinterpret_cast<__m128i*>(box[2]), y0);
  _mm_store_si128(reinterpret_cast<__m128i*>(box[3]), y1);
  for (int k = 0; k < 4; ++k) {
    if (decided[k]) continue;
    const int bit = 1 << k;
    if (culled_mask & bit) {
      results[k] = SplatSetup::kCulled;
    } else if ((edge_mask | large_mask) & bit) {
      fallback[k] = true;
    } else if (bad_det_mask & bit) {
      results[k] = SplatSetup::kInvalid;
    } else if (empty_mask & bit) {
      results[k] = SplatSetup::kCulled;
    } else if (undefined_mask & bit) {
      fallback[k] = true;
    } else {
      SplatRaster& raster = rasters[k];
      raster.x0 = uint16_t(box[0][k]);
      raster.x1 = uint16_t(box[1][k]);
      raster.y0 = uint16_t(box[2][k]);
      raster.y1 = uint16_t(box[3][k]);
      raster.center_u = float(out[0][k]);
      raster.center_v = float(out[1][k]);
      raster.conic_a = float(out[2][k]);
      raster.conic_b = float(out[3][k]);
      raster.conic_c = float(out[4][k]);
      raster.depth_num[0] = float(out[7][k]);
      raster.depth_num[1] = raster.depth_num[2] = 0;
      raster.depth_den[0] = float(out[8][k]);
      raster.depth_den[1] = float(out[9][k]);
      raster.z_lo = float(out[5][k]);
      raster.z_hi = float(out[6][k]);
      raster.depth_tolerance = float(out[10][k]);
      raster.flags = out[11][k] > 0 ? SplatRaster::kBackFacing : 0;
      results[k] = SplatSetup::kDrawn;
    }
  }
  for (int k = 0; k < 4; ++k)
    if (fallback[k])
      results[k] = setupCircularEwaSplat(centers[k], normals[k], radii[k], camera, params, &rasters[k]);
}

size_t unculledCircularSurfels(const Vec3* centers, const Vec3* normals, const double* radii, size_t count,
                               const CameraFrame& camera, const EwaParams& params, uint32_t* kept) {
  size_t n = 0, i = 0;
  for (; i + 4 <= count; i += 4) {
    const CameraLanes l(centers + i, normals + i, camera, params);
    // Valid input (finite, a normal of positive length, a positive radius); the others are kept.
    const V radius = _mm256_andnot_pd(set1(-0.0), _mm256_loadu_pd(radii + i));
    const V finite_max = set1(std::numeric_limits<double>::max());
    V valid = _mm256_and_pd(_mm256_cmp_pd(l.normal_length, set1(0.0), _CMP_GT_OQ),
                            _mm256_cmp_pd(radius, set1(0.0), _CMP_GT_OQ));
    valid = _mm256_and_pd(valid, _mm256_cmp_pd(radius, finite_max, _CMP_LE_OQ));
    for (const V v : {l.px, l.py, l.pz, l.nx_in, l.ny_in, l.nz_in})
      valid = _mm256_and_pd(valid, _mm256_cmp_pd(_mm256_andnot_pd(set1(-0.0), v), finite_max, _CMP_LE_OQ));
    const int culled_mask = _mm256_movemask_pd(_mm256_and_pd(l.culled, valid));
    for (int k = 0; k < 4; ++k)
      if (!(culled_mask & (1 << k))) kept[n++] = uint32_t(i + k);
  }
  for (; i < count; ++i) kept[n++] = uint32_t(i);  // the set-up decides
  return n;
}

#pragma GCC pop_options

#else

bool circularSetupAvx2Available() {
  return false;
}

void setupCircularEwaSplats4(const Vec3*, const Vec3*, const double*, const CameraFrame&, const EwaParams&,
                             SplatRaster*, float (*)[3], SplatSetup*) {
  throw std::logic_error("setupCircularEwaSplats4: this build has no AVX2 set-up");
}

size_t unculledCircularSurfels(const Vec3*, const Vec3*, const double*, size_t, const CameraFrame&,
                               const EwaParams&, uint32_t*) {
  throw std::logic_error("unculledCircularSurfels: this build has no AVX2 set-up");
}

#endif

}  // namespace rc
