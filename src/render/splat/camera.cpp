#include "relaxed_connectivity/render/splat/camera.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

void require(bool ok, const std::string& field, const std::string& problem) {
  if (!ok) throw std::invalid_argument("Camera: " + field + " " + problem);
}

}  // namespace

Camera Camera::perspective(uint32_t width, uint32_t height, double horizontal_fov) {
  if (!(horizontal_fov > 0 && horizontal_fov < M_PI))
    throw std::invalid_argument("Camera::perspective: horizontal_fov must lie in (0, pi), got " +
                                std::to_string(horizontal_fov));
  Camera camera;
  camera.projection = Projection::kPerspective;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = 0.5 * width / std::tan(0.5 * horizontal_fov);
  camera.cx = 0.5 * (double(width) - 1.0);
  camera.cy = 0.5 * (double(height) - 1.0);
  camera.validate();
  return camera;
}

Camera Camera::orthographic(uint32_t width, uint32_t height, double view_width) {
  if (!(view_width > 0 && std::isfinite(view_width)))
    throw std::invalid_argument("Camera::orthographic: view_width must be positive, got " +
                                std::to_string(view_width));
  Camera camera;
  camera.projection = Projection::kOrthographic;
  camera.width = width;
  camera.height = height;
  camera.ortho_scale = width / view_width;
  camera.cx = 0.5 * (double(width) - 1.0);
  camera.cy = 0.5 * (double(height) - 1.0);
  camera.validate();
  return camera;
}

void Camera::lookAt(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 forward = target - eye;
  if (!(forward.norm() > 0) || !eye.allFinite() || !target.allFinite())
    throw std::invalid_argument("Camera::lookAt: eye and target must be finite and distinct");
  const Vec3 z = forward.normalized();
  // Image up (-y) as close to `up` as possible; fall back to another axis when `up` is parallel to z.
  Vec3 up_perpendicular = up - up.dot(z) * z;
  if (up_perpendicular.norm() < 1e-9 * std::max(1.0, up.norm())) {
    const Vec3 fallback = std::abs(z.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    up_perpendicular = fallback - fallback.dot(z) * z;
  }
  const Vec3 y = -up_perpendicular.normalized();
  const Vec3 x = y.cross(z);
  Eigen::Matrix3d rotation;
  rotation.col(0) = x;
  rotation.col(1) = y;
  rotation.col(2) = z;
  world_T_camera = Eigen::Isometry3d::Identity();
  world_T_camera.linear() = rotation;
  world_T_camera.translation() = eye;
}

void Camera::validate() const {
  require(width > 0, "width", "must be positive");
  require(height > 0, "height", "must be positive");
  if (projection == Projection::kPerspective) {
    require(std::isfinite(fx) && fx > 0, "fx", "must be positive and finite");
    require(std::isfinite(fy) && fy > 0, "fy", "must be positive and finite");
    require(std::isfinite(near_clip) && near_clip > 0, "near_clip",
            "must be positive for a perspective camera");
  } else {
    require(std::isfinite(ortho_scale) && ortho_scale > 0, "ortho_scale", "must be positive and finite");
    require(std::isfinite(near_clip), "near_clip", "must be finite");
  }
  require(std::isfinite(cx), "cx", "must be finite");
  require(std::isfinite(cy), "cy", "must be finite");
  require(far_clip > near_clip, "far_clip", "must exceed near_clip");
  const Eigen::Matrix3d rotation = world_T_camera.linear();
  require(rotation.allFinite() && world_T_camera.translation().allFinite(), "world_T_camera",
          "must be finite");
  require((rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() < 1e-6 &&
              rotation.determinant() > 0,
          "world_T_camera", "must be a rigid transform (orthonormal rotation)");
}

bool Camera::project(const Vec3& p_camera, double* u, double* v) const {
  if (!(p_camera.z() >= near_clip)) return false;
  if (projection == Projection::kPerspective) {
    *u = cx + fx * p_camera.x() / p_camera.z();
    *v = cy + fy * p_camera.y() / p_camera.z();
  } else {
    *u = cx + ortho_scale * p_camera.x();
    *v = cy + ortho_scale * p_camera.y();
  }
  return true;
}

void Camera::pixelRay(double u, double v, Vec3* origin, Vec3* direction) const {
  const Eigen::Matrix3d rotation = world_T_camera.linear();
  if (projection == Projection::kPerspective) {
    *origin = world_T_camera.translation();
    *direction = (rotation * Vec3((u - cx) / fx, (v - cy) / fy, 1.0)).normalized();
  } else {
    *origin = world_T_camera * Vec3((u - cx) / ortho_scale, (v - cy) / ortho_scale, 0.0);
    *direction = rotation.col(2);
  }
}

}  // namespace rc
