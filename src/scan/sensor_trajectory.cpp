#include "relaxed_connectivity/scan/sensor_trajectory.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

namespace {
constexpr double kPi = 3.14159265358979323846;

void requireFinite(const char* name, double value) {
  if (!std::isfinite(value))
    throw std::invalid_argument(std::string("OrbitParameters: ") + name + " must be finite, got " +
                                std::to_string(value));
}
}  // namespace

Eigen::Isometry3d lookAt(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 forward_raw = target - eye;
  if (!(forward_raw.norm() > 0.0) || !forward_raw.allFinite())
    throw std::invalid_argument("lookAt: eye and target must be distinct finite points");
  const Vec3 forward = forward_raw.normalized();
  Vec3 right = forward.cross(up);
  if (right.norm() < 1e-9 * std::max(1.0, up.norm())) {
    // Looking along `up`: pick the world axis least aligned with the view direction.
    Vec3 other = Vec3::UnitX();
    if (std::abs(forward.x()) > std::abs(forward.y())) other = Vec3::UnitY();
    right = forward.cross(other);
  }
  right.normalize();
  const Vec3 down = forward.cross(right);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear().col(0) = right;
  pose.linear().col(1) = down;
  pose.linear().col(2) = forward;
  pose.translation() = eye;
  return pose;
}

void validateOrbit(const OrbitParameters& orbit) {
  if (!orbit.target.allFinite()) throw std::invalid_argument("OrbitParameters: target must be finite");
  requireFinite("radius", orbit.radius);
  requireFinite("height", orbit.height);
  requireFinite("angular_speed", orbit.angular_speed);
  requireFinite("start_angle", orbit.start_angle);
  requireFinite("height_amplitude", orbit.height_amplitude);
  requireFinite("height_period", orbit.height_period);
  requireFinite("climb_rate", orbit.climb_rate);
  if (!(orbit.radius > 0.0))
    throw std::invalid_argument("OrbitParameters: radius must be > 0, got " + std::to_string(orbit.radius));
  if (!(orbit.height_period > 0.0))
    throw std::invalid_argument("OrbitParameters: height_period must be > 0, got " +
                                std::to_string(orbit.height_period));
}

Vec3 orbitEye(const OrbitParameters& orbit, double time) {
  validateOrbit(orbit);
  const double angle = orbit.start_angle + orbit.angular_speed * time;
  const double z = orbit.height + orbit.height_amplitude * std::sin(2.0 * kPi * time / orbit.height_period) +
                   orbit.climb_rate * time;
  return orbit.target + Vec3(orbit.radius * std::cos(angle), orbit.radius * std::sin(angle), z);
}

Eigen::Isometry3d orbitTrajectory(const OrbitParameters& orbit, double time) {
  return lookAt(orbitEye(orbit, time), orbit.target);
}

}  // namespace rc
