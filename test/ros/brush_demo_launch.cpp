// launch/brush_demo.launch end to end: stroke replay -> paint_model brush on the board -> haptic_driver
// force, and the board painted.
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/BrushContact.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <mutex>

TEST(BrushDemoLaunch, TheStrokeBendsTheBristlesAndTheDeviceFeelsIt) {
  ros::NodeHandle nh;
  std::mutex mutex;
  double largest_bristle_force = 0, largest_device_force = 0;
  size_t contacts = 0, forces = 0, skins = 0, skeletons = 0, object_points = 0, painted_points = 0;
  bool painted_has_paint = false;
  auto contact_sub =
      nh.subscribe<relaxed_connectivity::BrushContact>("brush_contact", 100, [&](const auto& m) {
        std::lock_guard<std::mutex> lock(mutex);
        ++contacts;
        largest_bristle_force = std::max(largest_bristle_force, m->bristle_force.z);
      });
  auto force_sub =
      nh.subscribe<geometry_msgs::WrenchStamped>("haptic/force_feedback", 2000, [&](const auto& m) {
        std::lock_guard<std::mutex> lock(mutex);
        ++forces;
        largest_device_force = std::max(largest_device_force, m->wrench.force.z);
      });
  auto skin_sub = nh.subscribe<sensor_msgs::PointCloud2>("brush/skin", 5, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(mutex);
    skins += m->width * m->height > 1000;
  });
  auto skeleton_sub = nh.subscribe<visualization_msgs::MarkerArray>("brush/skeleton", 5, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(mutex);
    skeletons += m->markers.size() == 3;
  });
  auto object_sub = nh.subscribe<sensor_msgs::PointCloud2>("surfels", 1, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(mutex);
    object_points = m->width * m->height;
  });
  auto painted_sub = nh.subscribe<sensor_msgs::PointCloud2>("surfels/painted", 1, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(mutex);
    painted_points = m->width * m->height;
    painted_has_paint = false;
    for (const auto& f : m->fields) painted_has_paint = painted_has_paint || f.name == "paint_wet_volume";
  });
  // The straight stroke takes 4 s after the driver's start delay; wait until the bristles have pressed.
  // Rates are counted over at least one second of listening.
  const ros::WallTime start = ros::WallTime::now(), end = start + ros::WallDuration(45.0);
  while (ros::WallTime::now() < end) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (largest_bristle_force > 0.05 && largest_device_force > 0.05 && skins > 0 && skeletons > 0 &&
          painted_points > object_points && object_points > 0 &&
          ros::WallTime::now() - start > ros::WallDuration(1.0))
        break;
    }
    ros::WallDuration(0.1).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_GT(contacts, 30u);  // 60 Hz
  EXPECT_GT(forces, 500u);   // 1 kHz
  // The bent bristles push the stylus up (newtons), and the force loop passes that on to the device.
  EXPECT_GT(largest_bristle_force, 0.05);
  EXPECT_GT(largest_device_force, 0.05);
  EXPECT_GT(skins, 0u);
  EXPECT_GT(skeletons, 0u);
  // The brush painted: the object was resampled where it pressed (children added: more surfels than the
  // object had), and the painted cloud carries the paint columns.
  EXPECT_GT(object_points, 0u);
  EXPECT_GT(painted_points, object_points);
  EXPECT_TRUE(painted_has_paint);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "brush_demo_launch_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
