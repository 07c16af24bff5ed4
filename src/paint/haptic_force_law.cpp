#include "relaxed_connectivity/paint/haptic_force_law.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rc {

const char* contactProblemName(ContactProblem problem) {
  switch (problem) {
    case ContactProblem::kNone:
      return "none";
    case ContactProblem::kNonFinite:
      return "non-finite value";
    case ContactProblem::kNegativeConstant:
      return "negative penalty stiffness or friction";
    case ContactProblem::kNegativeDepth:
      return "negative depth";
    case ContactProblem::kNonUnitNormal:
      return "normal not of unit length";
    case ContactProblem::kUnknownHandle:
      return "unknown handle point";
    case ContactProblem::kDuplicateHandle:
      return "handle point listed twice";
  }
  return "unknown";
}

DepthMode parseDepthMode(const std::string& name) {
  if (name == "constant") return DepthMode::kConstant;
  if (name == "plane") return DepthMode::kPlane;
  throw std::invalid_argument("depth mode '" + name + "' is neither 'constant' nor 'plane'");
}

void HapticForceLawOptions::validate() const {
  if (!(stale_timeout >= 0) || !std::isfinite(stale_timeout))
    throw std::invalid_argument("stale_timeout must be >= 0 s (got " + std::to_string(stale_timeout) + ")");
  if (!(fade_time > 0) || !std::isfinite(fade_time))
    throw std::invalid_argument("fade_time must be > 0 s (got " + std::to_string(fade_time) + ")");
  if (!(normal_tolerance >= 0)) throw std::invalid_argument("normal_tolerance must be >= 0");
}

HapticForceLaw::HapticForceLaw(std::vector<Vec3> handle_offsets, HapticForceLawOptions options)
    : offsets_(std::move(handle_offsets)), options_(options) {
  options_.validate();
  if (offsets_.empty()) throw std::invalid_argument("the brush has no handle points");
  contact_.handles.reserve(offsets_.size());
}

ContactProblem HapticForceLaw::check(const ContactParameters& c) const {
  if (!std::isfinite(c.penalty_stiffness) || !std::isfinite(c.friction) || !c.bristle_force.allFinite())
    return ContactProblem::kNonFinite;
  if (c.penalty_stiffness < 0 || c.friction < 0) return ContactProblem::kNegativeConstant;
  uint64_t seen = 0;  // handle counts are small; above 64 the duplicate check is skipped
  for (const HandleContactState& h : c.handles) {
    if (!std::isfinite(h.depth) || !h.normal.allFinite() || !h.position.allFinite())
      return ContactProblem::kNonFinite;
    if (h.index < 0 || h.index >= handleCount()) return ContactProblem::kUnknownHandle;
    if (h.depth < 0) return ContactProblem::kNegativeDepth;
    if (!(std::abs(h.normal.norm() - 1.0) <= options_.normal_tolerance))
      return ContactProblem::kNonUnitNormal;
    if (h.index < 64) {
      if (seen & (uint64_t(1) << h.index)) return ContactProblem::kDuplicateHandle;
      seen |= uint64_t(1) << h.index;
    }
  }
  return ContactProblem::kNone;
}

void HapticForceLaw::setContact(const ContactParameters& contact, double t) {
  contact_.penalty_stiffness = contact.penalty_stiffness;
  contact_.friction = contact.friction;
  contact_.bristle_force = contact.bristle_force;
  contact_.handles.clear();
  for (const HandleContactState& h : contact.handles)
    if (int(contact_.handles.size()) < handleCount()) contact_.handles.push_back(h);  // within the reserve
  contact_time_ = t;
  has_contact_ = true;
}

double HapticForceLaw::contactAge(double now) const {
  return has_contact_ ? now - contact_time_ : std::numeric_limits<double>::infinity();
}

double HapticForceLaw::fade(double now) const {
  if (!has_contact_) return 0;
  const double late = contactAge(now) - options_.stale_timeout;
  return std::clamp(1.0 - late / options_.fade_time, 0.0, 1.0);
}

HapticForce HapticForceLaw::evaluate(const DeviceState& device, double now) const {
  HapticForce out;
  out.fade = fade(now);
  if (out.fade == 0) return out;
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  const Eigen::Matrix3d rotation = device.pose.linear();
  for (const HandleContactState& h : contact_.handles) {
    const Vec3 lever = rotation * offsets_[size_t(h.index)];  // stylus origin -> handle point
    const Vec3 x = device.pose.translation() + lever;
    double d = h.depth;
    if (options_.depth_mode == DepthMode::kPlane) d = std::max(0.0, h.depth - (x - h.position).dot(h.normal));
    if (d <= 0) continue;
    const Vec3 v = device.linear_velocity + device.angular_velocity.cross(lever);
    const Vec3 v_t = v - v.dot(h.normal) * h.normal;
    const Vec3 f = contact_.penalty_stiffness * d * h.normal  // (5.6)
                   - contact_.friction * d * v_t;             // (5.7)
    force += f;
    torque += lever.cross(f);
    ++out.handles_in_contact;
  }
  if (options_.add_bristle_force) force += contact_.bristle_force;
  out.wrench.head<3>() = out.fade * force;
  out.wrench.tail<3>() = out.fade * torque;
  return out;
}

}  // namespace rc
