#include "relaxed_connectivity/ros/object_mover.h"

#include <geometry_msgs/TransformStamped.h>
#include <tf2_eigen/tf2_eigen.h>
#include <visualization_msgs/InteractiveMarker.h>

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

#include "relaxed_connectivity/ros/six_dof_marker.h"

namespace rc {

void ObjectMoverParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("object_mover: " + what); };
  if (parent_frame.empty() || child_frame.empty() || parent_frame == child_frame)
    fail("parent_frame and child_frame must be two different, non-empty frames");
  if (initial_pose.size() != 6 && initial_pose.size() != 7)
    fail("initial_pose must be [x, y, z, roll, pitch, yaw] or [x, y, z, qx, qy, qz, qw]");
  for (double v : initial_pose)
    if (!std::isfinite(v)) fail("initial_pose must be finite");
  if (initial_pose.size() == 7) {
    const double norm =
        Eigen::Vector4d(initial_pose[3], initial_pose[4], initial_pose[5], initial_pose[6]).norm();
    if (std::abs(norm - 1) > 1e-3) fail("initial_pose's quaternion has norm " + std::to_string(norm));
  }
  if (!(rate > 0) || !std::isfinite(rate)) fail("rate must be > 0 Hz");
  if (!(marker_scale > 0) || !std::isfinite(marker_scale)) fail("marker_scale must be > 0 m");
}

ObjectMoverParams readObjectMoverParams(const ros::NodeHandle& pnh) {
  ObjectMoverParams p;
  pnh.param("parent_frame", p.parent_frame, p.parent_frame);
  pnh.param("child_frame", p.child_frame, p.child_frame);
  pnh.param("initial_pose", p.initial_pose, p.initial_pose);
  pnh.param("rate", p.rate, p.rate);
  pnh.param("interactive_marker", p.interactive_marker, p.interactive_marker);
  pnh.param("marker_scale", p.marker_scale, p.marker_scale);
  p.validate();
  return p;
}

ObjectMover::ObjectMover(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh), params_(readObjectMoverParams(private_nh)), diagnostics_(nh, private_nh, "object_mover") {
  const std::vector<double>& b = params_.initial_pose;
  const Eigen::Quaterniond q = b.size() == 7
                                   ? Eigen::Quaterniond(b[6], b[3], b[4], b[5]).normalized()
                                   : Eigen::Quaterniond(Eigen::AngleAxisd(b[5], Eigen::Vector3d::UnitZ()) *
                                                        Eigen::AngleAxisd(b[4], Eigen::Vector3d::UnitY()) *
                                                        Eigen::AngleAxisd(b[3], Eigen::Vector3d::UnitX()));
  pose_.position.x = b[0];
  pose_.position.y = b[1];
  pose_.position.z = b[2];
  pose_.orientation.x = q.x();
  pose_.orientation.y = q.y();
  pose_.orientation.z = q.z();
  pose_.orientation.w = q.w();
  pose_sub_ = nh_.subscribe("object_pose", 10, &ObjectMover::poseCallback, this);
  diagnostics_.addInput(pose_sub_.getTopic(), 0.0);  // poses come when someone moves the object
  if (params_.interactive_marker) {
    marker_server_ = std::make_unique<interactive_markers::InteractiveMarkerServer>(
        private_nh.getNamespace() + "/marker", "", /*spin_thread=*/false);
    visualization_msgs::InteractiveMarker marker;
    marker.header.frame_id = params_.parent_frame;
    marker.name = params_.child_frame;
    marker.description = params_.child_frame + " (drag to move)";
    marker.scale = float(params_.marker_scale);
    marker.pose = pose_;
    // The frame's +z (a camera's viewing direction in REP 103 optical frames) as an arrow.
    visualization_msgs::Marker arrow;
    arrow.type = visualization_msgs::Marker::ARROW;
    arrow.scale.x = 0.5 * params_.marker_scale;
    arrow.scale.y = arrow.scale.z = 0.08 * params_.marker_scale;
    arrow.pose.orientation =
        tf2::toMsg(Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ()));
    arrow.color = markerColor(0.3f, 0.7f, 1.0f);
    addSixDofControls(arrow, &marker);
    marker_server_->insert(marker, [this](const auto& f) { markerFeedback(f); });
    marker_server_->applyChanges();
  }
  timer_ = nh_.createWallTimer(ros::WallDuration(1.0 / params_.rate),
                               [this](const ros::WallTimerEvent&) { broadcast(); });
  broadcast();
  ROS_INFO_STREAM("object_mover: " << params_.parent_frame << " -> " << params_.child_frame << " from "
                                   << pose_sub_.getTopic()
                                   << (marker_server_ ? " and the interactive marker " +
                                                            private_nh.getNamespace() + "/marker"
                                                      : std::string()));
}

void ObjectMover::poseCallback(const geometry_msgs::PoseStampedConstPtr& msg) {
  std::string problem;
  if (!accept(msg->header.frame_id, msg->pose, "object pose", &problem)) {
    diagnostics_.rejected(pose_sub_.getTopic(), problem);
    return;
  }
  diagnostics_.accepted(pose_sub_.getTopic());
  if (marker_server_) {  // the handle follows the topic
    marker_server_->setPose(params_.child_frame, pose_);
    marker_server_->applyChanges();
  }
}

void ObjectMover::markerFeedback(const visualization_msgs::InteractiveMarkerFeedbackConstPtr& feedback) {
  if (feedback->event_type != visualization_msgs::InteractiveMarkerFeedback::POSE_UPDATE) return;
  accept(feedback->header.frame_id, feedback->pose, "marker pose");
}

bool ObjectMover::accept(const std::string& frame, const geometry_msgs::Pose& p, const char* source,
                         std::string* why) {
  const double values[] = {p.position.x,    p.position.y,    p.position.z,   p.orientation.x,
                           p.orientation.y, p.orientation.z, p.orientation.w};
  std::string problem;
  if (!frame.empty() && frame != params_.parent_frame)
    problem = "frame '" + frame + "', expected '" + params_.parent_frame + "'";
  for (double v : values)
    if (!std::isfinite(v)) problem = "not finite";
  const double norm = std::sqrt(values[3] * values[3] + values[4] * values[4] + values[5] * values[5] +
                                values[6] * values[6]);
  if (problem.empty() && std::abs(norm - 1) > 1e-3) problem = "quaternion of norm " + std::to_string(norm);
  if (!problem.empty()) {
    if (why) *why = problem;
    ++rejected_;
    ROS_ERROR_STREAM_THROTTLE(1.0, "object_mover: rejected " << source << ": " << problem << " (" << rejected_
                                                             << " rejected so far)");
    return false;
  }
  pose_ = p;
  broadcast();
  return true;
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
