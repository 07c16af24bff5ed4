#include "relaxed_connectivity/render/splat/ewa_splat.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rc {

CameraFrame::CameraFrame(const Camera& camera)
    : perspective(camera.projection == Camera::Projection::kPerspective),
      fx(camera.fx),
      fy(camera.fy),
      cx(camera.cx),
      cy(camera.cy),
      ortho_scale(camera.ortho_scale),
      near_clip(camera.near_clip),
      far_clip(camera.far_clip),
      width(camera.width),
      height(camera.height) {
  world_R_camera = camera.world_T_camera.linear();
  eye = camera.world_T_camera.translation();
  camera_R_world = world_R_camera.transpose();
  camera_t_world = -(camera_R_world * eye);
}

void tangentAxes(const Vec3& normal, double radius, Vec3* axis1, Vec3* axis2) {
  const Vec3 helper = std::abs(normal.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 t1 = normal.cross(helper).normalized();
  const Vec3 t2 = normal.cross(t1);
  *axis1 = radius * t1;
  *axis2 = radius * t2;
}

void surfelFrame(const SurfelCloud& cloud, size_t i, Vec3* normal, Vec3* axis1, Vec3* axis2) {
  if (cloud.hasAxes()) {
    *axis1 = cloud.axes1[i];
    *axis2 = cloud.axes2[i];
    *normal = cloud.hasNormals() ? cloud.normals[i] : Vec3(axis1->cross(*axis2));
  } else {
    *normal = cloud.normals[i];
    const double length = normal->norm();
    if (length > 0 && std::isfinite(length)) {
      tangentAxes(*normal / length, cloud.radii[i], axis1, axis2);
    } else {
      *axis1 = *axis2 = Vec3::Zero();
    }
  }
}

namespace {

/// Jacobian of the projection (camera frame -> pixels) at camera point c.
Eigen::Matrix<double, 2, 3> projectionJacobian(const CameraFrame& camera, const Vec3& c) {
  Eigen::Matrix<double, 2, 3> jacobian = Eigen::Matrix<double, 2, 3>::Zero();
  if (camera.perspective) {
    const double inv_z = 1.0 / c.z();
    jacobian << camera.fx * inv_z, 0, -camera.fx * c.x() * inv_z * inv_z,  //
        0, camera.fy * inv_z, -camera.fy * c.y() * inv_z * inv_z;
  } else {
    jacobian << camera.ortho_scale, 0, 0, 0, camera.ortho_scale, 0;
  }
  return jacobian;
}

/// ceil / floor of `value` clamped to [-1, size] (integer conversion instead of a rounding call).
int32_t ceilToPixel(double value, uint32_t size) {
  const double clamped = std::clamp(value, -1.0, double(size));
  const int32_t truncated = int32_t(clamped);
  return truncated + (double(truncated) < clamped);
}
int32_t floorToPixel(double value, uint32_t size) {
  const double clamped = std::clamp(value, -1.0, double(size));
  const int32_t truncated = int32_t(clamped);
  return truncated - (double(truncated) > clamped);
}

}  // namespace

namespace {

/// A surfel in the camera frame: centre c, unit normal n, and either scaled tangent axes or a radius.
struct CameraSurfel {
  Vec3 c, n;
  bool has_axes;
  Vec3 a1, a2;    ///< scaled tangent axes (has_axes)
  double radius;  ///< circular surfel (!has_axes)
};

/// Affine map local (s, t) in axis units -> pixel offsets, for the given camera-frame axes.
Eigen::Matrix2d localToScreen(const Eigen::Matrix<double, 2, 3>& jacobian, const Vec3& a1, const Vec3& a2) {
  Eigen::Matrix2d local_to_screen;
  local_to_screen.col(0) = jacobian * a1;
  local_to_screen.col(1) = jacobian * a2;
  return local_to_screen;
}

/// Regularised inverse of the affine map (pixel offset -> local axis units): exact inverse for regular
/// surfels, the minimum-norm solution along the visible line for edge-on ones.
Eigen::Matrix2d screenToLocal(const Eigen::Matrix2d& local_to_screen, bool edge_on) {
  const Eigen::Matrix2d normal_matrix = local_to_screen.transpose() * local_to_screen;
  const double regularisation = (edge_on ? 1e-3 : 1e-12) * normal_matrix.trace() + 1e-300;
  return (normal_matrix + regularisation * Eigen::Matrix2d::Identity()).inverse() *
         local_to_screen.transpose();
}

/// Pixel box of a splat with centre (u, v) and half extents, clamped to the image; false if empty.
inline bool pixelBox(double center_u, double center_v, double half_u, double half_v,
                     const CameraFrame& camera, SplatRaster* raster) {
  const int32_t x0 = std::max(0, ceilToPixel(center_u - half_u, camera.width));
  const int32_t x1 = std::min(int32_t(camera.width) - 1, floorToPixel(center_u + half_u, camera.width));
  const int32_t y0 = std::max(0, ceilToPixel(center_v - half_v, camera.height));
  const int32_t y1 = std::min(int32_t(camera.height) - 1, floorToPixel(center_v + half_v, camera.height));
  if (x0 > x1 || y0 > y1) return false;
  raster->x0 = uint16_t(x0);
  raster->x1 = uint16_t(x1);
  raster->y0 = uint16_t(y0);
  raster->y1 = uint16_t(y1);
  return true;
}

/// Per-surfel fuzzy depth tolerance (3.2.1). At one pixel, overlapping surfels of the same sheet differ in
/// depth by about their radius times their normal difference (curvature, noise), stretched along the ray by
/// 1 / cos(view angle): eps = s * k r / max(cos, c_min). The depth span of the whole disc (r sin) is NOT a
/// measure of that: for a large oblique surfel it would reach sheets far behind it (a cube face of one surfel
/// would blend with the faces behind). A relative term absorbs float rounding.
inline float depthTolerance(const EwaParams& params, double radius, double cos_view, double center_z) {
  return float(params.depth_tolerance_scale * kFacingDepthTolerance * radius /
                   std::max(cos_view, kMinToleranceCosine) +
               1e-5 * std::abs(center_z));
}

/// Depth of the surfel plane (centre c, unit normal n, camera frame) along the pixel rays of the raster's
/// box: perspective z = (n.c) / (n.d(u, v)) with d = ((u - cx) / fx, (v - cy) / fy, 1), i.e. 1/z affine in
/// the pixel offset; orthographic z affine. Widens [z_lo, z_hi] to the plane depths at the box corners (the
/// EWA-widened footprint extends beyond the disc). False if the plane is seen edge-on inside the box (the
/// denominator changes sign): then nothing is written.
inline bool planeDepth(const Vec3& c, const Vec3& n, double center_u, double center_v,
                       const CameraFrame& camera, SplatRaster* raster, double* z_lo, double* z_hi) {
  const double x0 = raster->x0, x1 = raster->x1, y0 = raster->y0, y1 = raster->y1;
  if (camera.perspective) {
    const double d1 = n.x() / camera.fx, d2 = n.y() / camera.fy;
    const double d0 = d1 * (center_u - camera.cx) + d2 * (center_v - camera.cy) + n.z();
    const double du_lo = x0 - center_u, du_hi = x1 - center_u;
    const double dv_lo = y0 - center_v, dv_hi = y1 - center_v;
    const double d_min = d0 + std::min(d1 * du_lo, d1 * du_hi) + std::min(d2 * dv_lo, d2 * dv_hi);
    const double d_max = d0 + std::max(d1 * du_lo, d1 * du_hi) + std::max(d2 * dv_lo, d2 * dv_hi);
    if (!(d_min * d_max > 0)) return false;
    const double numerator = n.dot(c);
    const double z_a = numerator / d_min, z_b = numerator / d_max;
    *z_lo = std::min({double(float(*z_lo)), z_a, z_b});
    *z_hi = std::max({double(float(*z_hi)), z_a, z_b});
    const double inv_d0 = 1.0 / d0;
    raster->depth_num[0] = float(numerator * inv_d0);
    raster->depth_num[1] = raster->depth_num[2] = 0;
    raster->depth_den[0] = float(d1 * inv_d0);
    raster->depth_den[1] = float(d2 * inv_d0);
    return true;
  }
  const double inv = -1.0 / (camera.ortho_scale * n.z());
  const double du_extent = std::max(x1 - center_u, center_u - x0);
  const double dv_extent = std::max(y1 - center_v, center_v - y0);
  const double z_extent = std::abs(n.x() * inv) * du_extent + std::abs(n.y() * inv) * dv_extent;
  *z_lo = std::min<double>(float(*z_lo), c.z() - z_extent);
  *z_hi = std::max<double>(float(*z_hi), c.z() + z_extent);
  raster->depth_num[0] = float(c.z());
  raster->depth_num[1] = float(n.x() * inv);
  raster->depth_num[2] = float(n.y() * inv);
  raster->depth_den[0] = raster->depth_den[1] = 0;
  return true;
}

/// The exact screen footprint of a perspective splat (camera frame: centre c, scaled tangent axes a1, a2; the
/// cut-off disc s^2 + t^2 <= rho^2 in axis units): the homography M = K [a1 a2 c] maps the disc's conic
/// diag(1, 1, -rho^2) to the screen conic M^-T diag(1, 1, -rho^2) M^-1, an ellipse while the whole disc lies
/// in front of the camera. Writes its centre and the covariance-equivalent of the kernel, sigma^2 F with F
/// the matrix whose cut-off ellipse it is (what the affine set-up calls sigma^2 J (..) J^T). False where the
/// disc reaches the near plane (the conic is not an ellipse there).
bool exactPerspectiveFootprint(const Vec3& c, const Vec3& a1, const Vec3& a2, double z_half_extent,
                               const CameraFrame& camera, const EwaParams& params, double* center_u,
                               double* center_v, Eigen::Matrix2d* kernel_covariance) {
  if (!(c.z() - z_half_extent > camera.near_clip)) return false;
  Eigen::Matrix3d K;
  K << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1;
  Eigen::Matrix3d M;
  M << K * a1, K * a2, K * c;
  const Eigen::Matrix3d inverse = M.inverse();
  if (!inverse.allFinite()) return false;
  const double rho = params.cutoff_radius;
  const Eigen::Matrix3d D = Eigen::Vector3d(1.0, 1.0, -rho * rho).asDiagonal();
  const Eigen::Matrix3d C = inverse.transpose() * D * inverse;
  const Eigen::Matrix2d A = C.topLeftCorner<2, 2>();
  const Eigen::Vector2d b = C.topRightCorner<2, 1>();
  if (!(A.determinant() > 0) || !(A.trace() > 0)) return false;
  const Eigen::Vector2d centre = -A.inverse() * b;
  const double k = -(b.dot(centre)) - C(2, 2);  // b^T A^-1 b - c
  if (!(k > 0) || !std::isfinite(k) || !centre.allFinite()) return false;
  // (x - centre)^T (A / k) (x - centre) = 1 on the cut-off; at the cut-off the kernel is at cutoff_sigmas.
  const double cutoff_sigmas = params.cutoff_radius / kKernelSigmaPerRadius;
  *kernel_covariance = (A / k).inverse() / (cutoff_sigmas * cutoff_sigmas);
  *center_u = centre.x();
  *center_v = centre.y();
  return kernel_covariance->allFinite();
}

SplatSetup setupCameraSurfel(const CameraSurfel& surfel, const CameraFrame& camera, const EwaParams& params,
                             SplatRaster* raster, Eigen::Matrix2d* screen_to_local_out, double* center_u_out,
                             double* center_v_out, bool* edge_on_out) {
  const Vec3& c = surfel.c;
  const Vec3& n = surfel.n;
  if (!(c.z() >= camera.near_clip && c.z() <= camera.far_clip)) return SplatSetup::kCulled;
  // cos(normal, view ray) = n.c / |c|, compared squared (no square root)
  const double n_dot_view = camera.perspective ? n.dot(c) : n.z();
  const double view_length2 = camera.perspective ? c.squaredNorm() : 1.0;
  if (params.backface_culling && n_dot_view > 0) return SplatSetup::kCulled;

  // Affine approximation of the projection at the centre: local (s, t) in axis units -> pixel offsets.
  // Its Gram matrix L L^T is the screen footprint; for a circular surfel L L^T = r^2 J (I - n n^T) J^T.
  const Eigen::Matrix<double, 2, 3> jacobian = projectionJacobian(camera, c);
  Eigen::Matrix2d footprint;
  double scale2, det2, z_half_extent, radius;  // det2 = det(L)^2
  if (surfel.has_axes) {
    const Eigen::Matrix2d local_to_screen = localToScreen(jacobian, surfel.a1, surfel.a2);
    footprint = local_to_screen * local_to_screen.transpose();
    scale2 = local_to_screen.squaredNorm();
    det2 = local_to_screen.determinant() * local_to_screen.determinant();
    z_half_extent = params.cutoff_radius * std::hypot(surfel.a1.z(), surfel.a2.z());
    radius = params.cutoff_radius * std::max(surfel.a1.norm(), surfel.a2.norm());
  } else {
    const Eigen::Vector2d jn = jacobian * n;
    const double r2 = surfel.radius * surfel.radius;
    footprint = r2 * (jacobian * jacobian.transpose() - jn * jn.transpose());
    scale2 = footprint.trace();
    det2 = footprint.determinant();
    z_half_extent = params.cutoff_radius * surfel.radius * std::sqrt(std::max(0.0, 1.0 - n.z() * n.z()));
    radius = params.cutoff_radius * surfel.radius;
  }
  const bool edge_on = n_dot_view * n_dot_view < kEdgeOnCosine * kEdgeOnCosine * view_length2 ||
                       !(det2 > 1e-18 * scale2 * scale2);

  double center_u, center_v;
  if (camera.perspective) {
    const double inv_z = 1.0 / c.z();
    center_u = camera.cx + camera.fx * c.x() * inv_z;
    center_v = camera.cy + camera.fy * c.y() * inv_z;
  } else {
    center_u = camera.cx + camera.ortho_scale * c.x();
    center_v = camera.cy + camera.ortho_scale * c.y();
  }

  // Screen-space covariance of the object-space Gaussian, plus the EWA low-pass filter. Edge-on surfels
  // always get the filter: their conic is (nearly) singular, the filter widens it to a line of pixel width.
  const double sigma2 = kKernelSigmaPerRadius * kKernelSigmaPerRadius;
  Eigen::Matrix2d covariance = sigma2 * footprint;
  // The raster's centre: the projected surfel centre, or for large splats the centre of the exact conic (the
  // geometry of clipped fragments keeps the projected centre, the reference of its affine inverse).
  double raster_u = center_u, raster_v = center_v;
  if (params.exact_footprint && camera.perspective && !edge_on && radius > kExactFootprintRatio * c.z()) {
    Vec3 a1 = surfel.a1, a2 = surfel.a2;
    if (!surfel.has_axes) tangentAxes(n, surfel.radius, &a1, &a2);
    Eigen::Matrix2d exact;
    if (exactPerspectiveFootprint(c, a1, a2, z_half_extent, camera, params, &raster_u, &raster_v, &exact))
      covariance = exact;
  }
  if (params.ewa_filter || edge_on) covariance.diagonal().array() += params.lowpass_variance;
  covariance.diagonal().array() += 1e-6;  // keeps tiny unfiltered splats invertible
  const double cutoff_sigmas = params.cutoff_radius / kKernelSigmaPerRadius;
  const double cutoff2 = cutoff_sigmas * cutoff_sigmas;
  const double det = covariance.determinant();
  if (!(det > 0) || !std::isfinite(det)) return SplatSetup::kInvalid;
  // Conic scaled so that r2 = 1 is the cut-off ellipse.
  const double conic_scale = 1.0 / (det * cutoff2);
  const Eigen::Array2d half = cutoff_sigmas * covariance.diagonal().array().sqrt();
  if (!pixelBox(raster_u, raster_v, half(0), half(1), camera, raster)) return SplatSetup::kCulled;

  raster->center_u = float(raster_u);
  raster->center_v = float(raster_v);
  raster->conic_a = float(covariance(1, 1) * conic_scale);
  raster->conic_b = float(-covariance(0, 1) * conic_scale);
  raster->conic_c = float(covariance(0, 0) * conic_scale);

  // Depth range of the cut-off ellipse, the fuzzy depth tolerance and the plane depth along the rays.
  double z_lo = c.z() - z_half_extent, z_hi = c.z() + z_half_extent;
  const double cos_view = std::abs(n_dot_view) / std::sqrt(view_length2);
  raster->depth_tolerance = depthTolerance(params, radius, cos_view, c.z());
  const bool affine_depth = edge_on || !planeDepth(c, n, raster_u, raster_v, camera, raster, &z_lo, &z_hi);
  raster->z_lo = float(z_lo);
  raster->z_hi = float(z_hi);

  if (affine_depth || screen_to_local_out) {
    Vec3 a1 = surfel.a1, a2 = surfel.a2;
    if (!surfel.has_axes) tangentAxes(n, surfel.radius, &a1, &a2);  // any orthonormal pair gives the same
    const Eigen::Matrix2d screen_to_local = screenToLocal(localToScreen(jacobian, a1, a2), edge_on);
    if (screen_to_local_out) *screen_to_local_out = screen_to_local;
    if (affine_depth) {  // z = c.z + (a1.z, a2.z) * screen_to_local * (du, dv)
      const Eigen::RowVector2d gradient = Eigen::RowVector2d(a1.z(), a2.z()) * screen_to_local;
      raster->depth_num[0] =
          float(c.z() + gradient.dot(Eigen::Vector2d(raster_u - center_u, raster_v - center_v)));
      raster->depth_num[1] = float(gradient(0));
      raster->depth_num[2] = float(gradient(1));
      raster->depth_den[0] = raster->depth_den[1] = 0;
    }
  }
  raster->flags = (edge_on ? SplatRaster::kEdgeOn : 0) | (n_dot_view > 0 ? SplatRaster::kBackFacing : 0);
  if (center_u_out) *center_u_out = center_u;
  if (center_v_out) *center_v_out = center_v;
  if (edge_on_out) *edge_on_out = edge_on;
  return edge_on ? SplatSetup::kDrawnEdgeOn : SplatSetup::kDrawn;
}

}  // namespace

bool unfilteredFootprint(const SplatRaster& filtered, double filter_variance, SplatRaster* footprint) {
  *footprint = filtered;
  if (!(filter_variance > 0)) return true;  // no filter in the conic: the splat is its own footprint
  const double a = filtered.conic_a, b = filtered.conic_b, c = filtered.conic_c;
  const double det = a * c - b * b;
  if (!(det > 0) || !std::isfinite(det)) return false;
  // The conic's inverse is the filtered covariance (cut-off units); remove the filter and invert back.
  const double inverse_det = 1.0 / det;
  const double v00 = c * inverse_det - filter_variance, v01 = -b * inverse_det,
               v11 = a * inverse_det - filter_variance;
  const double det_unfiltered = v00 * v11 - v01 * v01;
  if (!(v00 > 0) || !(v11 > 0) || !(det_unfiltered > 1e-12 * (v00 + v11) * (v00 + v11))) return false;
  const double inverse_unfiltered = 1.0 / det_unfiltered;
  footprint->conic_a = float(v11 * inverse_unfiltered);
  footprint->conic_b = float(-v01 * inverse_unfiltered);
  footprint->conic_c = float(v00 * inverse_unfiltered);
  return std::isfinite(footprint->conic_a) && std::isfinite(footprint->conic_b) &&
         std::isfinite(footprint->conic_c);
}

SplatSetup setupEwaSplat(const Vec3& center, const Vec3& normal, const Vec3& axis1, const Vec3& axis2,
                         const CameraFrame& camera, const EwaParams& params, SplatRaster* raster,
                         SplatGeometry* geometry) {
  if (!center.allFinite() || !normal.allFinite() || !axis1.allFinite() || !axis2.allFinite())
    return SplatSetup::kInvalid;
  const double normal_length = normal.norm();
  if (!(normal_length > 0) || !(axis1.norm() > 0) || !(axis2.norm() > 0)) return SplatSetup::kInvalid;

  CameraSurfel surfel;
  surfel.c = camera.camera_R_world * center + camera.camera_t_world;
  surfel.n = camera.camera_R_world * normal / normal_length;
  surfel.has_axes = true;
  surfel.a1 = camera.camera_R_world * axis1;
  surfel.a2 = camera.camera_R_world * axis2;
  surfel.radius = 0;
  Eigen::Matrix2d screen_to_local;
  double center_u = 0, center_v = 0;
  bool edge_on = false;
  const SplatSetup result = setupCameraSurfel(
      surfel, camera, params, raster, geometry ? &screen_to_local : nullptr, &center_u, &center_v, &edge_on);
  if (geometry && (result == SplatSetup::kDrawn || result == SplatSetup::kDrawnEdgeOn)) {
    geometry->center_world = center;
    geometry->normal_world = normal / normal_length;
    geometry->axis1_world = axis1;
    geometry->axis2_world = axis2;
    geometry->center_u = center_u;
    geometry->center_v = center_v;
    geometry->screen_to_local = screen_to_local;
    geometry->cutoff = params.cutoff_radius;
    geometry->edge_on = edge_on;
  }
  return result;
}

namespace {

/// The common case of setupCameraSurfel for a circular surfel (camera frame, unit normal), in scalar
/// arithmetic: same formulas, but without the general path's matrices. Returns false where the general path
/// must decide (edge-on surfels, plane depth not defined over the whole box).
bool setupCircularCommonCase(const Vec3& c, const Vec3& n, double radius, const CameraFrame& camera,
                             const EwaParams& params, SplatRaster* raster, SplatSetup* result) {
  const double n_dot_view = camera.perspective ? n.dot(c) : n.z();
  if (!(c.z() >= camera.near_clip && c.z() <= camera.far_clip) ||
      (params.backface_culling && n_dot_view > 0)) {
    *result = SplatSetup::kCulled;
    return true;
  }
  // Large perspective splats get the exact footprint in the general path.
  if (params.exact_footprint && camera.perspective &&
      params.cutoff_radius * radius > kExactFootprintRatio * c.z())
    return false;
  // Screen footprint r^2 J (I - n n^T) J^T of the affine approximation of the projection at the centre.
  const double r2 = radius * radius;
  double view_length2, f00, f01, f11, center_u, center_v;
  if (camera.perspective) {
    const double inv_z = 1.0 / c.z();
    const double j00 = camera.fx * inv_z, j02 = -camera.fx * c.x() * inv_z * inv_z;
    const double j11 = camera.fy * inv_z, j12 = -camera.fy * c.y() * inv_z * inv_z;
    const double jn0 = j00 * n.x() + j02 * n.z(), jn1 = j11 * n.y() + j12 * n.z();
    f00 = r2 * (j00 * j00 + j02 * j02 - jn0 * jn0);
    f01 = r2 * (j02 * j12 - jn0 * jn1);
    f11 = r2 * (j11 * j11 + j12 * j12 - jn1 * jn1);
    center_u = camera.cx + camera.fx * c.x() * inv_z;
    center_v = camera.cy + camera.fy * c.y() * inv_z;
    view_length2 = c.squaredNorm();
  } else {
    const double k = camera.ortho_scale, jn0 = k * n.x(), jn1 = k * n.y();
    f00 = r2 * (k * k - jn0 * jn0);
    f01 = -r2 * jn0 * jn1;
    f11 = r2 * (k * k - jn1 * jn1);
    center_u = camera.cx + camera.ortho_scale * c.x();
    center_v = camera.cy + camera.ortho_scale * c.y();
    view_length2 = 1.0;
  }
  const double scale2 = f00 + f11, det2 = f00 * f11 - f01 * f01;
  if (n_dot_view * n_dot_view < kEdgeOnCosine * kEdgeOnCosine * view_length2 ||
      !(det2 > 1e-18 * scale2 * scale2))
    return false;  // edge-on

  // EWA: object-space Gaussian plus the screen-space low-pass filter; conic scaled to r2 = 1 at the cut-off.
  const double sigma2 = kKernelSigmaPerRadius * kKernelSigmaPerRadius;
  double c00 = sigma2 * f00, c01 = sigma2 * f01, c11 = sigma2 * f11;
  if (params.ewa_filter) {
    c00 += params.lowpass_variance;
    c11 += params.lowpass_variance;
  }
  c00 += 1e-6;
  c11 += 1e-6;
  const double cutoff_sigmas = params.cutoff_radius / kKernelSigmaPerRadius;
  const double det = c00 * c11 - c01 * c01;
  if (!(det > 0) || !std::isfinite(det)) {
    *result = SplatSetup::kInvalid;
    return true;
  }
  const double conic_scale = 1.0 / (det * cutoff_sigmas * cutoff_sigmas);
  if (!pixelBox(center_u, center_v, cutoff_sigmas * std::sqrt(c00), cutoff_sigmas * std::sqrt(c11), camera,
                raster)) {
    *result = SplatSetup::kCulled;
    return true;
  }
  // Depth: range of the cut-off disc, fuzzy tolerance (3.2.1) and the plane along the pixel rays.
  const double z_half_extent = params.cutoff_radius * radius * std::sqrt(std::max(0.0, 1.0 - n.z() * n.z()));
  double z_lo = c.z() - z_half_extent, z_hi = c.z() + z_half_extent;
  if (!planeDepth(c, n, center_u, center_v, camera, raster, &z_lo, &z_hi))
    return false;  // edge-on in the box
  raster->center_u = float(center_u);
  raster->center_v = float(center_v);
  raster->conic_a = float(c11 * conic_scale);
  raster->conic_b = float(-c01 * conic_scale);
  raster->conic_c = float(c00 * conic_scale);
  raster->z_lo = float(z_lo);
  raster->z_hi = float(z_hi);
  raster->depth_tolerance = depthTolerance(params, params.cutoff_radius * radius,
                                           std::abs(n_dot_view) / std::sqrt(view_length2), c.z());
  raster->flags = n_dot_view > 0 ? SplatRaster::kBackFacing : 0;
  *result = SplatSetup::kDrawn;
  return true;
}

}  // namespace

SplatSetup setupCircularEwaSplat(const Vec3& center, const Vec3& normal, double radius,
                                 const CameraFrame& camera, const EwaParams& params, SplatRaster* raster,
                                 float* unit_normal_out) {
  if (!center.allFinite() || !normal.allFinite() || !std::isfinite(radius)) return SplatSetup::kInvalid;
  const double normal_length = normal.norm();
  if (!(normal_length > 0) || !(std::abs(radius) > 0)) return SplatSetup::kInvalid;
  const Vec3 unit_normal = normal * (1.0 / normal_length);
  if (unit_normal_out)
    for (int k = 0; k < 3; ++k) unit_normal_out[k] = float(unit_normal[k]);
  CameraSurfel surfel;
  surfel.c = camera.camera_R_world * center + camera.camera_t_world;
  surfel.n = camera.camera_R_world * unit_normal;
  surfel.has_axes = false;
  surfel.radius = std::abs(radius);
  SplatSetup result;
  if (setupCircularCommonCase(surfel.c, surfel.n, surfel.radius, camera, params, raster, &result))
    return result;
  return setupCameraSurfel(surfel, camera, params, raster, nullptr, nullptr, nullptr, nullptr);
}

Vec3 fragmentWorldPoint(const SplatGeometry& geometry, const CameraFrame& camera, double u, double v) {
  {
    Vec3 origin, direction;
    if (camera.perspective) {
      origin = camera.eye;
      direction = camera.world_R_camera * Vec3((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
    } else {
      origin = camera.eye + camera.world_R_camera * Vec3((u - camera.cx) / camera.ortho_scale,
                                                         (v - camera.cy) / camera.ortho_scale, 0.0);
      direction = camera.world_R_camera.col(2);
    }
    const double denominator = geometry.normal_world.dot(direction);
    if (std::abs(denominator) > 1e-12 * direction.norm()) {
      const double t = geometry.normal_world.dot(geometry.center_world - origin) / denominator;
      if (std::isfinite(t)) {
        if (!geometry.edge_on) return origin + t * direction;
        // Edge-on: the ray/plane point too (the affine inverse is a point off the ray, which clipped a
        // 1 px band outside silhouettes), clamped radially to the cut-off ellipse of the disc.
        const Vec3 offset = origin + t * direction - geometry.center_world;
        Eigen::Vector2d local(offset.dot(geometry.axis1_world) / geometry.axis1_world.squaredNorm(),
                              offset.dot(geometry.axis2_world) / geometry.axis2_world.squaredNorm());
        const double length = local.norm();
        if (length > geometry.cutoff) local *= geometry.cutoff / length;
        return geometry.center_world + local.x() * geometry.axis1_world + local.y() * geometry.axis2_world;
      }
    }
  }
  Eigen::Vector2d local =
      geometry.screen_to_local * Eigen::Vector2d(u - geometry.center_u, v - geometry.center_v);
  const double length = local.norm();
  if (length > geometry.cutoff) local *= geometry.cutoff / length;
  return geometry.center_world + local.x() * geometry.axis1_world + local.y() * geometry.axis2_world;
}

}  // namespace rc
