// paint_model node: the painted object and the brush in the main loop (see src/ros/paint_model.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/paint_model.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "paint_model");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::PaintModel model(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("paint_model: " << e.what());
    return 1;
  }
  return 0;
}
