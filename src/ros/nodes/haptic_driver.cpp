// haptic_driver node: the 1 kHz haptic force loop and a simulated or topic device (see
// src/ros/haptic_driver.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/haptic_driver.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "haptic_driver");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::HapticDriver driver(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("haptic_driver: " << e.what());
    return 1;
  }
  return 0;
}
