// The object_mover node: the second 6-DOF input of a painting session (thesis Fig. 5.1: one hand holds the
// brush, the other turns the object). Poses on a topic (a second haptic device, a space mouse) or an rviz
// interactive marker move the painted object's frame; the paint model paints in that frame and the renderer
// draws in it, so moving the object is a tf change for both (the renderer then makes a full update). The
// session runs a second one for the renderer's camera (camera_mover: the user orbits the view with its
// marker).
//
// Subscribes  object_pose (geometry_msgs/PoseStamped in parent_frame; an empty frame_id means parent_frame)
// Publishes   tf parent_frame -> child_frame, at `rate` and on every accepted pose
//             ~marker/update, ~marker/update_full (with interactive_marker: a 6-DOF handle at the pose)
// Parameters  (private) parent_frame ("world"), child_frame ("painted_object"), initial_pose ([x, y, z, roll,
//             pitch, yaw] or [x, y, z, qx, qy, qz, qw] as static_transform_publisher takes them, zeros),
//             rate ([Hz] 30), interactive_marker (false), marker_scale ([m] 0.2)
// A pose (topic or marker) in another frame, non-finite or with a non-unit quaternion is logged and rejected;
// the frame stays. A pose from the topic also moves the marker.
#pragma once

#include <geometry_msgs/PoseStamped.h>
#include <interactive_markers/interactive_marker_server.h>
#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>

#include <memory>
#include <string>
#include <vector>

#include "relaxed_connectivity/ros/node_diagnostics.h"

namespace rc {

struct ObjectMoverParams {
  std::string parent_frame = "world", child_frame = "painted_object";
  std::vector<double> initial_pose = {0, 0, 0, 0, 0, 0};
  double rate = 30.0;
  bool interactive_marker = false;
  double marker_scale = 0.2;
  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

ObjectMoverParams readObjectMoverParams(const ros::NodeHandle& private_nh);

class ObjectMover {
 public:
  ObjectMover(ros::NodeHandle nh, ros::NodeHandle private_nh);
  void poseCallback(const geometry_msgs::PoseStampedConstPtr& msg);
  uint32_t rejected() const { return rejected_; }

 private:
  /// Takes a pose in parent_frame (an empty frame means parent_frame) from `source`, or logs why not.
  bool accept(const std::string& frame, const geometry_msgs::Pose& pose, const char* source,
              std::string* why = nullptr);
  void markerFeedback(const visualization_msgs::InteractiveMarkerFeedbackConstPtr& feedback);
  void broadcast();
  ros::NodeHandle nh_;
  ObjectMoverParams params_;
  tf2_ros::TransformBroadcaster broadcaster_;
  ros::Subscriber pose_sub_;
  ros::WallTimer timer_;
  geometry_msgs::Pose pose_;
  uint32_t rejected_ = 0;
  std::unique_ptr<interactive_markers::InteractiveMarkerServer> marker_server_;
  NodeDiagnostics diagnostics_;  // the pose topic's accepted / rejected counts on /diagnostics
};

}  // namespace rc
