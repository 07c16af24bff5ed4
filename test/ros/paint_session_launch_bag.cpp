// launch/paint_session.launch playing a recorded session (bag:=, device:=topic;
// paint_session_launch_bag.test): the session runs in the bag's simulated time, scans and paints the recorded
// object, and keeps running after the bag ends.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include "launch_test_support.h"
#include "paint_session_support.h"

namespace rc {
namespace {

constexpr double kBagStart = 1795915095.4, kBagEnd = 1795915106.9;  // rosbag info paint_session_small.bag

TEST(PaintSessionLaunchBag, ARecordedSessionIsScannedAndPaintedInSimulatedTime) {
  ros::NodeHandle nh;
  SessionObserver session(nh);
  bool sim_time = false;
  EXPECT_TRUE(ros::param::get("/use_sim_time", sim_time));
  EXPECT_TRUE(sim_time);
  ASSERT_TRUE(waitFor([&] { return session.paint_stats.originals > 10000; }, 60))
      << session.paint_stats.originals << " originals";
  EXPECT_GT(session.paint_stats.header.stamp.toSec(), kBagStart);  // stamped in the recording's time
  ASSERT_TRUE(waitFor([&] { return session.paint_stats.children > 500; }, 60))
      << session.paint_stats.children << " children, " << session.pose_count << " device poses";
  // The recorded stroke, from the bag (6,809 poses; the test's own subscription may lag under load).
  EXPECT_TRUE(waitFor([&] { return session.pose_count > 1000; }, 30)) << session.pose_count << " poses";
  // rosbag play --keep-alive: the clock runs on past the bag's end and the session with it.
  EXPECT_TRUE(waitFor([&] { return session.paint_stats.header.stamp.toSec() > kBagEnd + 3; }, 30))
      << session.paint_stats.header.stamp.toSec() - kBagEnd << " s after the bag's end";
  EXPECT_EQ(session.paint_stats.rejected_messages, 0u);
  EXPECT_EQ(session.paint_stats.instabilities, 0u);
  EXPECT_GT(session.frames, 0u);  // paint_renderer drew it
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "paint_session_launch_bag_test");
  return RUN_ALL_TESTS();
}
