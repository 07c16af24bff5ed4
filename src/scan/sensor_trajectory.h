// Sensor poses for simulated scanning: a look-at camera pose in the REP 103 optical convention and an orbit
// (circle or helix) around a target as a function of time.
#pragma once

#include <Eigen/Geometry>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// world_T_sensor of an optical frame (z forward, x right, y down) at `eye` looking at `target`, with image
/// "up" (-y) as close to `up` as possible. Throws std::invalid_argument if eye == target; if the view
/// direction is parallel to `up`, another up vector is chosen.
Eigen::Isometry3d lookAt(const Vec3& eye, const Vec3& target, const Vec3& up = Vec3::UnitZ());

/// Viewpoint moving counter-clockwise (seen from +z) on a circle of `radius` around the vertical axis through
/// `target`, at `height` above it; with height_amplitude > 0 the height oscillates sinusoidally (a closed
/// helix sweep between height -/+ amplitude), with climb_rate != 0 it rises linearly (an open helix).
struct OrbitParameters {
  Vec3 target = Vec3::Zero();
  double radius = 1.5;            ///< horizontal distance to the target axis [m]
  double height = 0.6;            ///< eye z - target z at time 0 [m]
  double angular_speed = 0.5;     ///< [rad/s]
  double start_angle = 0.0;       ///< azimuth at time 0, from +x [rad]
  double height_amplitude = 0.0;  ///< [m]
  double height_period = 20.0;    ///< period of the height oscillation [s]
  double climb_rate = 0.0;        ///< [m/s]
};

/// Throws std::invalid_argument naming the bad parameter (radius <= 0, non-finite values, period <= 0).
void validateOrbit(const OrbitParameters& orbit);
/// Eye position at time t [s].
Vec3 orbitEye(const OrbitParameters& orbit, double time);
/// world_T_sensor at time t [s]: at orbitEye(orbit, t), looking at the target.
Eigen::Isometry3d orbitTrajectory(const OrbitParameters& orbit, double time);

}  // namespace rc
