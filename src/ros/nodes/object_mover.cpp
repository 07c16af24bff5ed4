// object_mover node: a pose topic in, the painted object's tf frame out (see src/ros/object_mover.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/object_mover.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "object_mover");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::ObjectMover mover(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("object_mover: " << e.what());
    return 1;
  }
  return 0;
}
