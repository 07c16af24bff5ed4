// fem_sim node: an FEM scene in real time, surface as a Marker, nodes as PointCloud2, polygon cuts by service
// (see src/ros/fem_simulator.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/fem_simulator.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "fem_sim");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::FemSimulator simulator(nh, private_nh);
    ros::AsyncSpinner spinner(2);  // services stay responsive while a frame is simulated
    spinner.start();
    ros::waitForShutdown();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("fem_sim: " << e.what());
    return 1;
  }
  return 0;
}
