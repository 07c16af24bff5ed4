#include "relaxed_connectivity/paint/device_state.h"

#include <cmath>

namespace rc {

const char* poseProblemName(PoseProblem problem) {
  switch (problem) {
    case PoseProblem::kNone:
      return "none";
    case PoseProblem::kNonFinite:
      return "non-finite pose";
    case PoseProblem::kNonUnitQuaternion:
      return "non-unit quaternion";
  }
  return "unknown";
}

PoseProblem checkDevicePose(const Vec3& position, const Eigen::Quaterniond& orientation,
                            double unit_tolerance) {
  if (!position.allFinite() || !orientation.coeffs().allFinite()) return PoseProblem::kNonFinite;
  if (!(std::abs(orientation.norm() - 1.0) <= unit_tolerance)) return PoseProblem::kNonUnitQuaternion;
  return PoseProblem::kNone;
}

DeviceState DeviceVelocityEstimator::update(double t, const Vec3& position,
                                            const Eigen::Quaterniond& orientation) {
  if (has_previous_ && !(t > t_prev_)) has_previous_ = false;  // restarted stream
  if (!has_previous_) {
    v_.setZero();
    w_.setZero();
  } else if (t - t_prev_ >= min_interval_) {
    const double dt = t - t_prev_;
    v_ = (position - p_prev_) / dt;
    // Rotation from the previous orientation to this one, in the base frame: q = dq * q_prev.
    Eigen::AngleAxisd dq(orientation * q_prev_.conjugate());
    double angle = dq.angle();
    if (angle > M_PI) angle -= 2 * M_PI;  // the short way round
    w_ = dq.axis() * (angle / dt);
  }
  if (!has_previous_ || t - t_prev_ >= min_interval_) {
    t_prev_ = t;
    p_prev_ = position;
    q_prev_ = orientation;
    has_previous_ = true;
  }
  DeviceState state;
  state.pose = Eigen::Isometry3d::Identity();
  state.pose.linear() = orientation.toRotationMatrix();
  state.pose.translation() = position;
  state.linear_velocity = v_;
  state.angular_velocity = w_;
  return state;
}

}  // namespace rc
