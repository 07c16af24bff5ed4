#include "relaxed_connectivity/paint/device_state.h"

#include <algorithm>
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
  if (count_ > 0 && !(t > kept_[newest_].t)) count_ = 0;  // restarted stream
  newest_ = (newest_ + 1) % kKept;
  kept_[newest_] = {t, position, orientation};
  count_ = std::min(count_ + 1, kKept);
  DeviceState state;
  state.pose.linear() = orientation.toRotationMatrix();
  state.pose.translation() = position;
  if (count_ < 2) return state;
  // The newest pose at least `baseline_` older, else the oldest kept.
  int reference = (newest_ - count_ + 1 + kKept) % kKept;
  for (int back = 1; back < count_; ++back) {
    const int i = (newest_ - back + kKept) % kKept;
    if (t - kept_[i].t >= baseline_) {
      reference = i;
      break;
    }
  }
  const Stamped& r = kept_[reference];
  const double dt = t - r.t;
  state.linear_velocity = (position - r.position) / dt;
  // Rotation from the reference orientation to this one, in the base frame: q = dq * q_ref.
  const Eigen::AngleAxisd dq(orientation * r.orientation.conjugate());
  double angle = dq.angle();
  if (angle > M_PI) angle -= 2 * M_PI;  // the short way round
  state.angular_velocity = dq.axis() * (angle / dt);
  return state;
}

}  // namespace rc
