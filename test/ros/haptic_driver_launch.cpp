// launch/haptic_driver.launch with the replay device playing config/paint/strokes/straight.csv (node or
// nodelet): the stroke's poses come out in haptic_base, its paint button goes down and up, the force loop
// publishes forces (the penalty K_p d N for a contact the test sends) and 1 Hz stats, and world ->
// haptic_base is on tf.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/BrushContact.h>
#include <relaxed_connectivity/HapticButtons.h>
#include <relaxed_connectivity/HapticLoopStats.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>

#include "launch_test_support.h"

namespace rc {
namespace {

TEST(HapticDriverLaunch, ReplayPublishesTheContract) {
  ros::NodeHandle nh;
  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener(tf_buffer);
  int poses = 0, forces = 0;
  geometry_msgs::PoseStamped last_pose;
  double last_fz = 0;
  bool pressed_seen = false, released_after_press = false;
  relaxed_connectivity::HapticLoopStats stats;
  int stats_count = 0;
  auto pose_sub = nh.subscribe<geometry_msgs::PoseStamped>("haptic/pose", 5000, [&](const auto& m) {
    ++poses;
    last_pose = *m;
  });
  auto force_sub =
      nh.subscribe<geometry_msgs::WrenchStamped>("haptic/force_feedback", 5000, [&](const auto& m) {
        ++forces;
        EXPECT_EQ(m->header.frame_id, "haptic_base");
        last_fz = m->wrench.force.z;
      });
  auto button_sub =
      nh.subscribe<relaxed_connectivity::HapticButtons>("haptic/button", 100, [&](const auto& m) {
        ASSERT_FALSE(m->pressed.empty());
        if (m->pressed[0]) pressed_seen = true;
        if (!m->pressed[0] && pressed_seen) released_after_press = true;
      });
  auto stats_sub =
      nh.subscribe<relaxed_connectivity::HapticLoopStats>("haptic/stats", 10, [&](const auto& m) {
        stats = *m;
        ++stats_count;
      });
  // straight.csv: paints from 0.5 s to 2.5 s; the replay then holds the last pose.
  // Wait until the replay holds the stroke's last sample (stylus lifted to z = 44 mm at x = 40 mm).
  ASSERT_TRUE(waitFor(
      [&] { return released_after_press && stats_count >= 2 && last_pose.pose.position.z == 0.044; }, 30.0))
      << "poses " << poses << ", pressed " << pressed_seen << ", stats " << stats_count;
  EXPECT_GT(poses, 1000);
  EXPECT_GT(forces, 1000);
  EXPECT_EQ(last_pose.header.frame_id, "haptic_base");
  EXPECT_NEAR(last_pose.pose.position.x, 0.04, 1e-12);  // the stroke's last sample
  EXPECT_NEAR(last_pose.pose.position.z, 0.044, 1e-12);
  EXPECT_EQ(stats.rate, 1000.0);
  EXPECT_GT(stats.ticks, 1000u);
  EXPECT_GT(stats.period_p50, 0.0);
  EXPECT_EQ(stats.dropped_poses, 0u);
  EXPECT_EQ(last_fz, 0.0);  // no contact yet

  // A contact at the (held) last pose: the force becomes K_p d N (the axis handle point, plane depth d).
  ros::Publisher contact_pub = nh.advertise<relaxed_connectivity::BrushContact>("brush_contact", 10);
  relaxed_connectivity::BrushContact c;
  c.header.frame_id = "haptic_base";
  c.penalty_stiffness = 400;
  relaxed_connectivity::HandleContact h;
  h.depth = 0.001;
  h.normal.z = 1;
  h.position.z = 0.044;  // the handle points lie in the ferrule plane, at the stylus' height
  c.handles.push_back(h);
  ASSERT_TRUE(waitFor(
      [&] {
        contact_pub.publish(c);
        return std::abs(last_fz - 0.4) < 1e-9;
      },
      10.0))
      << "force z " << last_fz;

  geometry_msgs::TransformStamped base;
  ASSERT_TRUE(waitFor([&] { return tf_buffer.canTransform("world", "haptic_base", ros::Time(0)); }, 5.0));
  base = tf_buffer.lookupTransform("world", "haptic_base", ros::Time(0));
  EXPECT_NEAR(base.transform.translation.x, 0.1, 1e-12);
  EXPECT_NEAR(base.transform.translation.z, 0.75, 1e-12);
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "haptic_driver_launch_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
