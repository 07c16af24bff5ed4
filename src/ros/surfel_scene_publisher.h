// The surfel_scene_publisher node: loads a CSG scene file (render/scene.h, config/scenes/*.yaml) and
// publishes its patches as one PointCloud2 with int32 `patch_id` and `surfel_role` fields (latched), moving
// every frame for dynamic scenes; hands the scene's CSG expression to csg_renderer; places the camera by tf.
//
// Publishes   surfels (sensor_msgs/PointCloud2, pcl::PointSurfel layout + patch_id + surfel_role, frame_id)
//             tf frame_id -> camera_frame (optical convention) from one of the scene's cameras, static or
//             orbiting the z axis of frame_id
// Calls       csg_service (relaxed_connectivity/SetCsgTree) with the scene's expression over patch ids, once
//             the service exists
// Parameters  (private) scene (file, required), frame_id, rate, time_scale, csg_service, camera_frame,
//             camera (name; "" the first), camera_orbit_speed (degrees per second); see config/csg_demo.yaml.
#pragma once

#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <string>

#include "relaxed_connectivity/render/scene/csg_scene.h"

namespace rc {

struct SurfelScenePublisherParams {
  std::string scene;
  std::string frame_id = "world";
  double rate = 10.0;       ///< frames per second (dynamic scenes and an orbiting camera)
  double time_scale = 1.0;  ///< scene time per wall-clock second
  std::string csg_service = "csg_renderer/set_csg_tree";  ///< empty: do not send the expression
  std::string camera_frame = "csg_camera";                ///< empty: publish no camera transform
  std::string camera;                                     ///< scene camera name; empty: the first
  double camera_orbit_speed = 0.0;                        ///< degrees per second; 0: static camera

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

SurfelScenePublisherParams readSurfelScenePublisherParams(const ros::NodeHandle& private_nh);

/// The expression of `tree` over patch ids ("(0 & 1) - 2"), every binary node parenthesised.
std::string patchIdExpression(const CsgTree& tree);

class SurfelScenePublisher {
 public:
  /// Reads the parameters and loads the scene (throws std::invalid_argument / std::runtime_error).
  SurfelScenePublisher(ros::NodeHandle nh, ros::NodeHandle private_nh);

  const CsgScene& scene() const { return scene_; }

 private:
  void publishFrame(double t);
  void timerCallback(const ros::WallTimerEvent&);
  void sendExpression();

  ros::NodeHandle nh_, private_nh_;
  SurfelScenePublisherParams params_;
  CsgScene scene_;
  std::string expression_;  // over patch ids
  bool expression_sent_ = false;
  SurfelCloud moving_;  // the surfels at the current time (dynamic scenes)
  Camera camera_;       // the scene camera at t = 0
  ros::Publisher surfels_pub_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  tf2_ros::TransformBroadcaster tf_;
  ros::WallTimer timer_;
  ros::WallTime start_;
};

}  // namespace rc
