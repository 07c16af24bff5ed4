// Cameras for splatting: perspective (pinhole, OpenCV/ROS optical convention: x right, y down, z forward) and
// orthographic. world_T_camera places the camera; pixels are (u, v) with (0, 0) the centre of the top-left
// pixel.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

struct Camera {
  enum class Projection { kPerspective, kOrthographic };
  Projection projection = Projection::kPerspective;
  uint32_t width = 640, height = 480;
  double fx = 500, fy = 500, cx = 319.5, cy = 239.5;  ///< perspective intrinsics [px]
  double ortho_scale = 100;  ///< orthographic: pixels per metre (u = cx + s x, v = cy + s y)
  double near_clip = 0.01, far_clip = 1000;
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();

  /// Perspective camera with the given horizontal field of view (radians), centred principal point.
  static Camera perspective(uint32_t width, uint32_t height, double horizontal_fov);
  /// Orthographic camera showing `view_width` metres across the image.
  static Camera orthographic(uint32_t width, uint32_t height, double view_width);
  /// Places the camera at `eye` looking at `target` (image up is as close to `up` as possible).
  void lookAt(const Vec3& eye, const Vec3& target, const Vec3& up = Vec3::UnitZ());

  /// Throws std::invalid_argument naming the bad field.
  void validate() const;
  /// World point -> camera frame.
  Vec3 toCamera(const Vec3& p_world) const { return world_T_camera.inverse() * p_world; }
  /// Camera-frame point -> pixel (u, v) and depth z (camera z). False if behind the near plane.
  bool project(const Vec3& p_camera, double* u, double* v) const;
  /// Ray (origin, unit direction) in the world frame through pixel (u, v).
  void pixelRay(double u, double v, Vec3* origin, Vec3* direction) const;
};

}  // namespace rc
