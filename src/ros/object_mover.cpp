#include "relaxed_connectivity/ros/object_mover.h"

#include <geometry_msgs/TransformStamped.h>

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

namespace rc {

void ObjectMoverParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("object_mover: " + what); };
  if (parent_frame.empty() || child_frame.empty() || parent_frame == child_frame)
    fail("parent_frame and child_frame must be two different, non-empty frames");
  if (initial_pose.size() != 6) fail("initial_pose must be [x, y, z, roll, pitch, yaw]");
  for (double v : initial_pose)
    if (!std::isfinite(v)) fail("initial_pose must be finite");
  if (!(rate > 0) || !std::isfinite(rate)) fail("rate must be > 0 Hz");
}

ObjectMoverParams readObjectMoverParams(const ros::NodeHandle& pnh) {
  ObjectMoverParams p;
  pnh.param("parent_frame", p.parent_frame, p.parent_frame);
  pnh.param("child_frame", p.child_frame, p.child_frame);
  pnh.param("initial_pose", p.initial_pose, p.initial_pose);
  pnh.param("rate", p.rate, p.rate);
  p.validate();
  return p;
}

ObjectMover::ObjectMover(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), params_(readObjectMoverParams(private_nh)) {
  const std::vector<double>& b = params_.initial_pose;
  const Eigen::Quaterniond q = Eigen::AngleAxisd(b[5], Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(b[4], Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(b[3], Eigen::Vector3d::UnitX());
  pose_.position.x = b[0];
  pose_.position.y = b[1];
  pose_.position.z = b[2];
  pose_.orientation.x = q.x();
  pose_.orientation.y = q.y();
  pose_.orientation.z = q.z();
  pose_.orientation.w = q.w();
  pose_sub_ = nh_.subscribe("object_pose", 10, &ObjectMover::poseCallback, this);
  timer_ = nh_.createWallTimer(ros::WallDuration(1.0 / params_.rate),
                               [this](const ros::WallTimerEvent&) { broadcast(); });
  broadcast();
  ROS_INFO_STREAM("object_mover: " << params_.parent_frame << " -> " << params_.child_frame
                                   << " from object_pose");
}

void ObjectMover::poseCallback(const geometry_msgs::PoseStampedConstPtr& msg) {
  const geometry_msgs::Pose& p = msg->pose;
  const double values[] = {p.position.x,    p.position.y,    p.position.z,   p.orientation.x,
                           p.orientation.y, p.orientation.z, p.orientation.w};
  std::string problem;
  if (!msg->header.frame_id.empty() && msg->header.frame_id != params_.parent_frame)
    problem = "frame '" + msg->header.frame_id + "', expected '" + params_.parent_frame + "'";
  for (double v : values)
    if (!std::isfinite(v)) problem = "not finite";
  const double norm = std::sqrt(values[3] * values[3] + values[4] * values[4] + values[5] * values[5] +
                                values[6] * values[6]);
  if (problem.empty() && std::abs(norm - 1) > 1e-3) problem = "quaternion of norm " + std::to_string(norm);
  if (!problem.empty()) {
    ++rejected_;
    ROS_ERROR_STREAM_THROTTLE(
        1.0, "object_mover: rejected object pose: " << problem << " (" << rejected_ << " rejected so far)");
    return;
  }
  pose_ = p;
  broadcast();
}

void ObjectMover::broadcast() {
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = params_.parent_frame;
  t.child_frame_id = params_.child_frame;
  t.transform.translation.x = pose_.position.x;
  t.transform.translation.y = pose_.position.y;
  t.transform.translation.z = pose_.position.z;
  t.transform.rotation = pose_.orientation;
  broadcaster_.sendTransform(t);
}

}  // namespace rc
