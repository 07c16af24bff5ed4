// launch/scan.launch bag:=... (scan_launch_bag.test): the recorded views play in simulated time
// (/use_sim_time, rosbag's /clock) through surfel_estimator: one surfel cloud per recorded view, each stamped
// with its recorded stamp, none rejected (the recorded tf resolves at the recorded times), the clock within
// the recording.
#include <gtest/gtest.h>
#include <relaxed_connectivity/SurfelStats.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <mutex>
#include <vector>

namespace {

TEST(ScanLaunchBag, RecordedViewsBecomeSurfelsInSimulatedTime) {
  ros::NodeHandle nh;
  bool use_sim_time = false;
  ASSERT_TRUE(nh.getParam("/use_sim_time", use_sim_time));
  EXPECT_TRUE(use_sim_time);
  std::mutex mutex;
  std::vector<double> surfel_stamps;
  std::vector<relaxed_connectivity::SurfelStats> stats;
  ros::Subscriber surfels =
      nh.subscribe<sensor_msgs::PointCloud2>("surfels", 20, [&](const sensor_msgs::PointCloud2ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        surfel_stamps.push_back(m->header.stamp.toSec());
      });
  ros::Subscriber stats_sub = nh.subscribe<relaxed_connectivity::SurfelStats>(
      "surfel_estimator/stats", 20, [&](const relaxed_connectivity::SurfelStatsConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        stats.push_back(*m);
      });
  // The recording: 8 views from 1795362128.86 s to 1795362130.60 s (rosbag info).
  const double first = 1795362128.8, last = 1795362130.7;
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(60.0);
  double clock_seen = 0.0;
  for (;;) {
    ros::spinOnce();
    const double now = ros::Time::now().toSec();
    if (now > 0) clock_seen = now;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (surfel_stamps.size() >= 8 && stats.size() >= 8) break;
    }
    ASSERT_LT(ros::WallTime::now(), end) << "8 views not processed within 60 s of wall time";
    ros::WallDuration(0.02).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(surfel_stamps.size(), 8u);
  for (double stamp : surfel_stamps) {
    EXPECT_GE(stamp, first);
    EXPECT_LE(stamp, last);
  }
  for (const auto& s : stats) {
    EXPECT_EQ(s.rejected_messages, 0u) << s.last_error;
    EXPECT_GT(s.output_surfels, 1000u);
  }
  // The node's clock is rosbag's: within the recording, not the wall time.
  EXPECT_GE(clock_seen, first);
  EXPECT_LE(clock_seen, last + 1.0);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "scan_launch_bag_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
