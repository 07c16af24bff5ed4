// The marker device of haptic_driver (see haptic_driver_marker.test): the interactive marker "stylus" is
// served, a dragged pose (POSE_UPDATE feedback, as rviz sends it) becomes the stylus pose published at the
// loop rate, the "Paint (button 0)" menu entry toggles button 0, and a non-finite dragged pose is ignored.
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/HapticButtons.h>
#include <ros/ros.h>
#include <visualization_msgs/InteractiveMarkerFeedback.h>
#include <visualization_msgs/InteractiveMarkerInit.h>

#include <cmath>

#include "launch_test_support.h"

namespace rc {
namespace {

visualization_msgs::InteractiveMarkerFeedback feedback(uint8_t event, double x, double y, double z) {
  visualization_msgs::InteractiveMarkerFeedback f;
  f.header.frame_id = "haptic_base";
  f.header.stamp = ros::Time::now();
  f.client_id = "/rviz/InteractiveMarkers";
  f.marker_name = "stylus";
  f.event_type = event;
  f.pose.position.x = x;
  f.pose.position.y = y;
  f.pose.position.z = z;
  f.pose.orientation.w = 1;
  return f;
}

TEST(HapticDriverMarker, DraggedPoseAndMenuDriveTheStylus) {
  ros::NodeHandle nh;
  visualization_msgs::InteractiveMarkerInit init;
  bool has_init = false;
  auto init_sub = nh.subscribe<visualization_msgs::InteractiveMarkerInit>("haptic_driver/marker/update_full",
                                                                          1, [&](const auto& m) {
                                                                            init = *m;
                                                                            has_init = true;
                                                                          });
  geometry_msgs::PoseStamped last_pose;
  int poses = 0;
  auto pose_sub = nh.subscribe<geometry_msgs::PoseStamped>("haptic/pose", 5000, [&](const auto& m) {
    last_pose = *m;
    ++poses;
  });
  bool painting = false;
  auto button_sub = nh.subscribe<relaxed_connectivity::HapticButtons>(
      "haptic/button", 10, [&](const auto& m) { painting = !m->pressed.empty() && m->pressed[0]; });
  ros::Publisher feedback_pub =
      nh.advertise<visualization_msgs::InteractiveMarkerFeedback>("haptic_driver/marker/feedback", 10);

  ASSERT_TRUE(waitFor([&] { return has_init && poses > 100 && feedback_pub.getNumSubscribers() > 0; }, 20.0));
  ASSERT_EQ(init.markers.size(), 1u);
  EXPECT_EQ(init.markers[0].name, "stylus");
  EXPECT_EQ(init.markers[0].header.frame_id, "haptic_base");
  EXPECT_EQ(last_pose.header.frame_id, "haptic_base");
  EXPECT_NEAR(last_pose.pose.position.z, 0.04, 1e-12);  // the start: two bristle lengths above the origin
  EXPECT_FALSE(painting);

  using Feedback = visualization_msgs::InteractiveMarkerFeedback;
  ASSERT_TRUE(waitFor(
      [&] {
        feedback_pub.publish(feedback(Feedback::POSE_UPDATE, 0.01, -0.02, 0.015));
        return std::abs(last_pose.pose.position.x - 0.01) < 1e-12 &&
               std::abs(last_pose.pose.position.z - 0.015) < 1e-12;
      },
      10.0))
      << "stylus at " << last_pose.pose.position.x << " " << last_pose.pose.position.z;
  EXPECT_NEAR(last_pose.pose.position.y, -0.02, 1e-12);

  Feedback nan_pose = feedback(Feedback::POSE_UPDATE, NAN, 0, 0);
  feedback_pub.publish(nan_pose);
  const int poses_before = poses;
  ASSERT_TRUE(waitFor([&] { return poses > poses_before + 200; }, 10.0));
  EXPECT_NEAR(last_pose.pose.position.x, 0.01, 1e-12);  // the non-finite pose was ignored

  Feedback menu = feedback(Feedback::MENU_SELECT, 0.01, -0.02, 0.015);
  menu.menu_entry_id = 1;  // "Paint (button 0)"
  feedback_pub.publish(menu);
  EXPECT_TRUE(waitFor([&] { return painting; }, 5.0));
  feedback_pub.publish(menu);
  EXPECT_TRUE(waitFor([&] { return !painting; }, 5.0));
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "haptic_driver_marker_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
