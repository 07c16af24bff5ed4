// csg_renderer node: surfel patches + CSG tree + camera tf in, rendered colour/depth images out (see
// src/ros/csg_renderer.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/csg_renderer.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "csg_renderer");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::CsgRenderer renderer(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("csg_renderer: " << e.what());
    return 1;
  }
  return 0;
}
