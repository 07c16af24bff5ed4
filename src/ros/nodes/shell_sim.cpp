// shell_sim node: a thin-shell scene in real time, dense surfels as PointCloud2, nodes and fibers as Markers,
// forces on nodes by service (see src/ros/shell_simulator.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/shell_simulator.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "shell_sim");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::ShellSimulator simulator(nh, private_nh);
    ros::AsyncSpinner spinner(2);  // services stay responsive while a frame is simulated
    spinner.start();
    ros::waitForShutdown();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("shell_sim: " << e.what());
    return 1;
  }
  return 0;
}
