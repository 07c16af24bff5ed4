// launch/paint_session.launch end to end (paint_session_launch.test): scan -> paint model -> replayed stroke
// -> paint_renderer images; the second 6-DOF input (object_pose) moves the object and the renderer follows
// with a full update.
#include <geometry_msgs/PoseStamped.h>

#include "launch_test_support.h"
#include "paint_session_support.h"

namespace rc {
namespace {

TEST(PaintSessionLaunch, ScansPaintsRendersAndFollowsTheObject) {
  ros::NodeHandle nh;
  SessionObserver session(nh);
  expectRvizTopicsPublished(std::string(RC_SOURCE_DIR) + "/config/rviz/paint_session.rviz", 3);
  ASSERT_TRUE(
      waitFor([&] { return session.paint_stats.children > 200 && session.differential_updates > 10; }, 90))
      << session.paint_stats.children << " children, " << session.differential_updates
      << " differential updates";
  EXPECT_GT(session.paint_stats.originals, 50000u);  // the scanned box and the palette
  ASSERT_TRUE(session.image);
  EXPECT_EQ(session.image->width, 1280u);
  EXPECT_EQ(session.image->height, 720u);
  EXPECT_EQ(session.render_stats.rejected_messages, 0u) << session.render_stats.last_error;

  // Turn the object a little: what the camera sees changed, so the next frame is a full update.
  ros::Publisher object_pub = nh.advertise<geometry_msgs::PoseStamped>("object_pose", 1, true);
  geometry_msgs::PoseStamped pose;
  pose.header.frame_id = "world";
  pose.pose.position.x = 0.02;
  pose.pose.orientation.z = std::sin(0.05);
  pose.pose.orientation.w = std::cos(0.05);
  object_pub.publish(pose);
  const uint32_t full_before = session.full_updates;
  EXPECT_TRUE(waitFor(
      [&] {
        return session.full_updates > full_before &&
               session.render_stats.last_full_update_reason == "camera_moved";
      },
      10))
      << session.render_stats.last_full_update_reason;
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "paint_session_launch");
  return RUN_ALL_TESTS();
}
