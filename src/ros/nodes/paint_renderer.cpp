// paint_renderer node: the painted cloud and its deltas in, differentially rendered images out (see
// src/ros/paint_renderer.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/paint_renderer.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "paint_renderer");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::PaintRenderer renderer(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("paint_renderer: " << e.what());
    return 1;
  }
  return 0;
}
