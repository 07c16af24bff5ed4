// The object_mover node: the second 6-DOF input of a painting session (thesis Fig. 5.1: one hand holds the
// brush, the other turns the object). Poses on a topic (a second haptic device, a space mouse, an rviz
// marker) move the painted object's frame; the paint model paints in that frame and the renderer draws in it,
// so moving the object is a tf change for both (the renderer then makes a full update).
//
// Subscribes  object_pose (geometry_msgs/PoseStamped in parent_frame; an empty frame_id means parent_frame)
// Publishes   tf parent_frame -> child_frame, at `rate` and on every accepted pose
// Parameters  (private) parent_frame ("world"), child_frame ("painted_object"), initial_pose ([x, y, z, roll,
//             pitch, yaw], zeros), rate ([Hz] 30)
// A pose in another frame, non-finite or with a non-unit quaternion is logged and rejected; the object stays.
#pragma once

#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>

#include <string>
#include <vector>

namespace rc {

struct ObjectMoverParams {
  std::string parent_frame = "world", child_frame = "painted_object";
  std::vector<double> initial_pose = {0, 0, 0, 0, 0, 0};
  double rate = 30.0;
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
  void broadcast();
  ros::NodeHandle nh_;
  ObjectMoverParams params_;
  tf2_ros::TransformBroadcaster broadcaster_;
  ros::Subscriber pose_sub_;
  ros::WallTimer timer_;
  geometry_msgs::Pose pose_;
  uint32_t rejected_ = 0;
};

}  // namespace rc
