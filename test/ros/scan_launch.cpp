// launch/scan.launch (gui:=false): the scanner -> surfel_estimator pipeline delivers surfels in `world`.
#include <gtest/gtest.h>
#include <relaxed_connectivity/ResetAccumulation.h>
#include <relaxed_connectivity/SurfelStats.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <relaxed_connectivity/SaveSurfels.h>
#include <ros/master.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <mutex>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace {

TEST(ScanLaunch, SurfelsArriveAndAccumulate) {
  ros::NodeHandle nh;
  std::mutex mutex;
  std::vector<sensor_msgs::PointCloud2ConstPtr> surfels, accumulated;
  std::vector<relaxed_connectivity::SurfelStats> stats;
  auto surfel_sub = nh.subscribe<sensor_msgs::PointCloud2>("surfels", 10, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(mutex);
    surfels.push_back(m);
  });
  auto accumulated_sub =
      nh.subscribe<sensor_msgs::PointCloud2>("surfels_accumulated", 10, [&](const auto& m) {
        std::lock_guard<std::mutex> lock(mutex);
        accumulated.push_back(m);
      });
  auto stats_sub =
      nh.subscribe<relaxed_connectivity::SurfelStats>("surfel_estimator/stats", 50, [&](const auto& m) {
        std::lock_guard<std::mutex> lock(mutex);
        stats.push_back(*m);
      });

  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(60.0);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (surfels.size() >= 5 && accumulated.size() >= 2) break;
    }
    ros::WallDuration(0.02).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_GE(surfels.size(), 5u) << "no surfels from the scan pipeline";
  for (const auto& m : surfels) {
    EXPECT_EQ(m->header.frame_id, "world");
    EXPECT_TRUE(rc::PointCloud2Converter::hasPointSurfelLayout(*m));
    EXPECT_GT(m->width * m->height, 100u);
    const rc::SurfelCloud c = rc::PointCloud2Converter::fromMessage(*m);
    // The blob stands at the scan stage, 0.75 m above the world origin (static transform in scan.launch).
    rc::Vec3 lo, hi;
    ASSERT_TRUE(c.bounds(&lo, &hi));
    EXPECT_GT(lo.z(), 0.75 - 1.0);
    EXPECT_LT(hi.z(), 0.75 + 1.0);
    EXPECT_LT((0.5 * (lo + hi) - rc::Vec3(0, 0, 0.75)).norm(), 0.6);
  }
  ASSERT_FALSE(stats.empty());
  EXPECT_EQ(stats.back().rejected_messages, 0u) << stats.back().last_error;
  EXPECT_EQ(stats.back().input_points, 160u * 120u);
  EXPECT_GT(stats.back().accumulated_surfels, stats.front().output_surfels / 2);
  EXPECT_EQ(accumulated.back()->header.frame_id, "world");
  EXPECT_GT(accumulated.back()->width, 100u);

  ros::ServiceClient reset =
      nh.serviceClient<relaxed_connectivity::ResetAccumulation>("surfel_estimator/reset_accumulation");
  ASSERT_TRUE(reset.waitForExistence(ros::Duration(5.0)));
  relaxed_connectivity::ResetAccumulation srv;
  ASSERT_TRUE(reset.call(srv));
  EXPECT_GT(srv.response.dropped_surfels, 100u);
}

TEST(ScanLaunch, SaveServiceWritesTheAccumulatedSurfels) {
  ros::NodeHandle nh;
  ros::ServiceClient save = nh.serviceClient<relaxed_connectivity::SaveSurfels>("surfel_estimator/save");
  ASSERT_TRUE(save.waitForExistence(ros::Duration(5.0)));
  ros::WallDuration(1.0).sleep();  // a few views after the reset of the previous test
  const std::string path = "/tmp/rc_scan_launch_" + std::to_string(getpid()) + ".ply";
  relaxed_connectivity::SaveSurfels srv;
  srv.request.path = path;
  ASSERT_TRUE(save.call(srv));
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_GT(srv.response.saved_surfels, 100u);
  const rc::SurfelCloud saved = rc::readCloud(path);
  EXPECT_EQ(saved.size(), srv.response.saved_surfels);
  EXPECT_TRUE(saved.hasNormals());
  EXPECT_TRUE(saved.hasRadii());
  std::remove(path.c_str());

  srv.request.path = "/nonexistent_dir/x.ply";  // a bad path is reported, the node keeps running
  ASSERT_TRUE(save.call(srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("/nonexistent_dir/x.ply"), std::string::npos) << srv.response.message;
}

// config/rviz/scan.rviz is loaded and shows topics that the launched nodes publish, in the estimator's frame.
TEST(ScanLaunch, RvizConfigShowsPublishedTopics) {
  const YAML::Node rviz = YAML::LoadFile(std::string(RC_SOURCE_DIR) + "/config/rviz/scan.rviz");
  const YAML::Node manager = rviz["Visualization Manager"];
  ASSERT_TRUE(manager.IsMap());
  EXPECT_EQ(manager["Global Options"]["Fixed Frame"].as<std::string>(), "world");
  ros::master::V_TopicInfo topics;
  ASSERT_TRUE(ros::master::getTopics(topics));
  int clouds = 0;
  for (const auto& display : manager["Displays"]) {
    const std::string type = display["Class"].as<std::string>();
    if (type != "rviz/PointCloud2" && type != "relaxed_connectivity/SurfelCloud") continue;
    ++clouds;
    const std::string topic = display["Topic"].as<std::string>();
    const bool published = std::any_of(topics.begin(), topics.end(), [&](const ros::master::TopicInfo& t) {
      return t.name == topic && t.datatype == "sensor_msgs/PointCloud2";
    });
    EXPECT_TRUE(published) << "rviz shows " << topic << ", which nobody publishes";
  }
  EXPECT_EQ(clouds, 3);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "scan_launch_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
