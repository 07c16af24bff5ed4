// surfel_scene_publisher node: a CSG scene file's patches as PointCloud2 (see
// src/ros/surfel_scene_publisher.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/surfel_scene_publisher.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "surfel_scene_publisher");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::SurfelScenePublisher publisher(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("surfel_scene_publisher: " << e.what());
    return 1;
  }
  return 0;
}
