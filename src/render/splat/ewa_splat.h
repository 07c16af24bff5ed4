// Per-surfel screen-space set-up for EWA surface splatting (thesis 3.2, Zwicker et al. 2001): the affine
// approximation of the projection at the surfel centre maps the object-space Gaussian to a screen-space
// Gaussian, which is convolved with the low-pass filter and bounded by the cut-off. Depth is exact
// (ray/surfel-plane intersection, 1/z affine in screen space); edge-on surfels take a degenerate-safe path
// (4.2.3: a thick line covering the ellipse instead of an unreliable matrix inverse).
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/splat/camera.h"

namespace rc {

/// Gaussian standard deviation of the reconstruction kernel, in units of the surfel radius (semi-axis).
constexpr double kKernelSigmaPerRadius = 0.5;
/// |cos(normal, view ray)| below which a surfel counts as edge-on (its screen conic degenerates).
constexpr double kEdgeOnCosine = 0.05;
/// Depth tolerance for surfels facing the camera, in units of the surfel radius (curvature, normal noise).
constexpr double kFacingDepthTolerance = 0.1;
/// The fuzzy depth tolerance grows as 1 / cos(view angle) up to this cosine (at most 1 / 0.25 = 4x).
constexpr double kMinToleranceCosine = 0.25;

/// A perspective splat whose cut-off disc is larger than this fraction of its depth gets the exact projection
/// of the disc as its footprint (a conic: the homography of the surfel plane maps the disc's circle to an
/// ellipse whose centre is not the projected surfel centre) instead of the affine approximation at the
/// centre, which falls short of the far side of large oblique splats (gaps, back faces showing through).
/// Below it the affine error is under about 1 % of the splat.
constexpr double kExactFootprintRatio = 0.02;

/// Camera matrices precomputed once per frame.
struct CameraFrame {
  explicit CameraFrame(const Camera& camera);
  bool perspective;
  double fx, fy, cx, cy, ortho_scale, near_clip, far_clip;
  uint32_t width, height;
  Eigen::Matrix3d camera_R_world;
  Vec3 camera_t_world;  ///< p_camera = camera_R_world p_world + camera_t_world
  Eigen::Matrix3d world_R_camera;
  Vec3 eye;  ///< camera origin in the world frame
};

struct EwaParams {
  bool ewa_filter = true;
  double lowpass_variance = 0.25;
  double cutoff_radius = 1.0;
  double depth_tolerance_scale = 1.0;
  bool backface_culling = false;
  bool exact_footprint = true;  ///< SplatConfig::exact_footprint
};

/// Float raster record of one splat: one cache line, plain data (left uninitialised in the renderer's
/// scratch buffers). Pixel offsets du = u - center_u, dv = v - center_v. Images up to 65535 pixels wide/high.
struct alignas(64) SplatRaster {
  uint16_t x0, y0, x1, y1;  ///< inclusive pixel bounding box, clamped to the image
  float center_u, center_v;
  float conic_a, conic_b, conic_c;  ///< r2 = a du^2 + 2 b du dv + c dv^2; cut-off at r2 = 1
  float depth_num[3];               ///< z = (n0 + n1 du + n2 dv) / (1 + d1 du + d2 dv), clamped
  float depth_den[2];               ///< d1, d2
  float z_lo, z_hi;                 ///< depth range of the ellipse (guards the degenerate cases)
  float depth_tolerance;            ///< eps_z of this surfel (3.2.1)
  uint32_t flags;  ///< kBackFacing, kEdgeOn, kClip, kClipColorOnly; the clip slot in the low bits

  /// kBackFacing: the normal points away from the camera (drawn only when back faces are not culled).
  static constexpr uint32_t kBackFacing = 1u << 28, kEdgeOn = 1u << 29, kClip = 1u << 30,
                            kClipColorOnly = 1u << 31;
  static constexpr uint32_t kClipSlotMask = kBackFacing - 1;  ///< index into the clip geometry table
  static constexpr uint32_t kMaxImageSize = 65535;
  uint32_t clipSlot() const { return flags & kClipSlotMask; }

  float depthAt(float du, float dv) const {
    float z = (depth_num[0] + depth_num[1] * du + depth_num[2] * dv) /
              (1.0f + depth_den[0] * du + depth_den[1] * dv);
    z = z > z_lo ? z : z_lo;  // also maps +-inf and NaN into the range
    return z < z_hi ? z : z_hi;
  }
};
static_assert(sizeof(SplatRaster) == 64, "SplatRaster fills one cache line");

/// Double-precision geometry of one splat, kept for surfels whose fragments are clipped (4.2.2).
struct SplatGeometry {
  Vec3 center_world = Vec3::Zero(), normal_world = Vec3::UnitZ();
  Vec3 axis1_world = Vec3::UnitX(), axis2_world = Vec3::UnitY();  ///< scaled tangent axes
  double center_u = 0, center_v = 0;
  Eigen::Matrix2d screen_to_local = Eigen::Matrix2d::Zero();  ///< regularised inverse of the affine map
  double cutoff = 1;                                          ///< in units of the axes
  bool edge_on = false;
};

enum class SplatSetup { kCulled, kDrawn, kDrawnEdgeOn, kInvalid };

/// Two tangent axes of length `radius` perpendicular to the unit `normal`.
void tangentAxes(const Vec3& normal, double radius, Vec3* axis1, Vec3* axis2);

/// Normal and tangent axes of surfel i as the renderer draws it (axes if present, else normal and radius).
void surfelFrame(const SurfelCloud& cloud, size_t i, Vec3* normal, Vec3* axis1, Vec3* axis2);

/// Screen-space set-up of the surfel (centre, unit normal, scaled tangent axes, all world frame). Fills
/// `raster` (flags: kEdgeOn only) and, if not null, `geometry`. The camera image must be at most
/// SplatRaster::kMaxImageSize pixels wide and high.
SplatSetup setupEwaSplat(const Vec3& center, const Vec3& normal, const Vec3& axis1, const Vec3& axis2,
                         const CameraFrame& camera, const EwaParams& params, SplatRaster* raster,
                         SplatGeometry* geometry);

/// Same for a circular surfel of `radius` (normal of any positive length): the screen footprint comes from
/// J (I - n n^T) J^T r^2 without building tangent axes. Agrees with the axes version to float rounding.
/// Also writes the unit normal to `unit_normal` if not null.
SplatSetup setupCircularEwaSplat(const Vec3& center, const Vec3& normal, double radius,
                                 const CameraFrame& camera, const EwaParams& params, SplatRaster* raster,
                                 float* unit_normal = nullptr);

/// The footprint of a set-up splat without the EWA low-pass filter (SplatConfig::exact_silhouettes): a copy
/// of `filtered` whose conic, (V + v I)^-1 in cut-off units, becomes V^-1 (V the projected reconstruction
/// kernel, v = `filter_variance` = cutoff_sigmas^2 lowpass_variance; v <= 0: a plain copy). False if no area
/// is left (an edge-on disc thinner than float precision resolves): the splat covers no pixel centre.
bool unfilteredFootprint(const SplatRaster& filtered, double filter_variance, SplatRaster* footprint);

/// The filter variance in the conic of `s` for unfilteredFootprint: `filter` (cutoff_sigmas^2
/// lowpass_variance) where the set-up added it (ewa_filter, or an edge-on splat), else 0.
inline double conicFilterVariance(const SplatRaster& s, bool ewa_filter, double filter) {
  return ewa_filter || (s.flags & SplatRaster::kEdgeOn) ? filter : 0.0;
}

/// World point on the surfel plane seen through pixel (u, v): the exact ray/plane intersection (for edge-on
/// surfels clamped to the cut-off ellipse; the regularised affine inverse where the ray misses the plane).
Vec3 fragmentWorldPoint(const SplatGeometry& geometry, const CameraFrame& camera, double u, double v);

}  // namespace rc
