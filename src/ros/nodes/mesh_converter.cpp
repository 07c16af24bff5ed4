// mesh_converter node: surfels -> textured meshes, as an action (see src/ros/mesh_converter.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/mesh_converter.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "mesh_converter");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::MeshConverter converter(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("mesh_converter: " << e.what());
    return 1;
  }
  return 0;
}
