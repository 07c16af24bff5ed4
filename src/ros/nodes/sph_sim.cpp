// sph_sim node: an SPH scene in real time, particles as PointCloud2 (see src/ros/sph_simulator.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/sph_simulator.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "sph_sim");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::SphSimulator simulator(nh, private_nh);
    ros::AsyncSpinner spinner(2);  // services stay responsive while a frame is simulated
    spinner.start();
    ros::waitForShutdown();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("sph_sim: " << e.what());
    return 1;
  }
  return 0;
}
