// surfel_estimator node: point clouds in, surfels out (see src/ros/surfel_estimator.h).
#include <ros/ros.h>

#include "relaxed_connectivity/core/heap_retention.h"
#include "relaxed_connectivity/ros/surfel_estimator.h"

int main(int argc, char** argv) {
  rc::fixMallocMmapThreshold();  // freed message buffers go back to the system
  ros::init(argc, argv, "surfel_estimator");
  ros::NodeHandle nh, private_nh("~");
  try {
    rc::SurfelEstimator estimator(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("surfel_estimator: " << e.what());
    return 1;
  }
  return 0;
}
