// Simulated depth camera: pinhole projection, closest-hit visibility from the mesh ray caster, range limits,
// depth-dependent Gaussian noise (structured-light style) and random dropout. Output is a surfel cloud in the
// sensor optical frame (REP 103: z forward, x right, y down).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/mesh/mesh_ray_caster.h"

namespace rc {

/// Pinhole intrinsics in pixels; pixel (u, v) (column, row; integers at pixel centres) sees the optical-frame
/// direction ((u - cx) / fx, (v - cy) / fy, 1).
struct PinholeIntrinsics {
  uint32_t width = 640, height = 480;
  double fx = 525.0, fy = 525.0;
  double cx = 319.5, cy = 239.5;

  /// Square pixels, principal point at the image centre ((width - 1) / 2, (height - 1) / 2), fx from the
  /// horizontal field of view (radians, in (0, pi)). Throws std::invalid_argument for a bad size or angle.
  static PinholeIntrinsics fromHorizontalFov(uint32_t width, uint32_t height, double horizontal_fov);
  /// Throws std::invalid_argument naming the bad field (zero size, fx or fy <= 0, non-finite values).
  void validate() const;
};

/// Range noise sigma(z) = sigma_constant + sigma_quadratic * z^2 on the depth z (e.g. Kinect-like structured
/// light: a ~ 0.001 m, b ~ 0.0019 / m), and the probability that a valid return is dropped.
struct DepthNoise {
  double sigma_constant = 0.0;       ///< a [m]
  double sigma_quadratic = 0.0;      ///< b [1/m]
  double dropout_probability = 0.0;  ///< in [0, 1]
  double sigma(double depth) const { return sigma_constant + sigma_quadratic * depth * depth; }
};

struct DepthSensorConfig {
  PinholeIntrinsics intrinsics;
  /// Valid depths (z along the optical axis, before noise): min_range <= z <= max_range, 0 <= min < max.
  double min_range = 0.1;
  double max_range = 10.0;
  DepthNoise noise;
  uint64_t seed = 0;
  /// Organised width x height cloud with NaN positions for pixels without a return; otherwise only the
  /// returns (row-major pixel order), width = height = 0.
  bool organized = true;
  /// Per-point unit normals (sensor frame, flipped to face the sensor): interpolated vertex normals when the
  /// mesh has them and `smooth_normals`, else the triangle's geometric normal.
  bool output_normals = true;
  bool smooth_normals = true;
  std::string frame_id = "sensor_optical_frame";

  /// Throws std::invalid_argument naming the bad field.
  void validate() const;
};

class DepthSensor {
 public:
  /// Validates the configuration (throws std::invalid_argument).
  explicit DepthSensor(const DepthSensorConfig& config);
  const DepthSensorConfig& config() const { return config_; }

  /// Renders the scene of `caster` seen from `world_T_sensor` (the optical frame's pose in the world/mesh
  /// frame). Noise and dropout depend only on (seed, frame_index, pixel): the result is deterministic and
  /// independent of the thread count; pass increasing frame indices for independent noise per frame. Colours
  /// are interpolated vertex colours when the mesh has them. Multi-threaded (OpenMP).
  SurfelCloud capture(const MeshRayCaster& caster, const Eigen::Isometry3d& world_T_sensor,
                      uint64_t frame_index = 0) const;

  /// World-frame ray of pixel (u, v); the direction is unnormalised with unit optical-axis component, so the
  /// ray parameter t equals the depth z.
  Ray pixelRay(double u, double v, const Eigen::Isometry3d& world_T_sensor) const;
  /// Projects a sensor-frame point to pixel coordinates; false if it is behind the camera (z <= 0).
  bool project(const Vec3& point_in_sensor, double* u, double* v) const;

 private:
  DepthSensorConfig config_;
};

}  // namespace rc
