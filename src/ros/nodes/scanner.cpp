// scanner node: simulated or file-based point cloud source (see src/ros/scanner_node.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/scanner_node.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "scanner");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::ScannerNode scanner(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("scanner: " << e.what());
    return 1;
  }
  return 0;
}
