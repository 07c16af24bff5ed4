// The replay device as fast as possible (see haptic_driver_replay_fast.test): the loop runs on virtual time,
// so tick k publishes the stroke sampled at k / 1000 s with the stamp start + k ms, every tick and nothing
// else. Both are pure functions of k: two replays publish the same poses.
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/HapticButtons.h>
#include <ros/ros.h>

#include <vector>

#include "launch_test_support.h"
#include "relaxed_connectivity/paint/stroke_file.h"

namespace rc {
namespace {

TEST(HapticDriverReplayFast, EveryTickPublishesTheSampledStroke) {
  ros::NodeHandle nh, pnh("~");
  std::string stroke_path;
  ASSERT_TRUE(pnh.getParam("stroke", stroke_path));
  const StrokeSampler sampler(readStrokeFile(stroke_path));
  size_t expected = 0;  // ticks k = 0, 1, ... up to the first with k / 1000 > duration
  while (!(double(expected) / 1000.0 > sampler.duration())) ++expected;
  ++expected;

  std::vector<geometry_msgs::PoseStamped> poses;
  std::vector<bool> button_changes;
  auto pose_sub = nh.subscribe<geometry_msgs::PoseStamped>("haptic/pose", 20000,
                                                           [&](const auto& m) { poses.push_back(*m); });
  auto button_sub = nh.subscribe<relaxed_connectivity::HapticButtons>(
      "haptic/button", 100, [&](const auto& m) { button_changes.push_back(m->pressed.at(0)); });
  ASSERT_TRUE(waitFor([&] { return poses.size() >= expected; }, 30.0)) << poses.size() << " of " << expected;
  waitFor([] { return false; }, 1.0);  // nothing may follow
  ASSERT_EQ(poses.size(), expected);

  for (size_t k = 0; k < poses.size(); ++k) {
    const StrokeSample s = sampler.at(sampler.startTime() + double(k) / 1000.0);
    const Eigen::Quaterniond q(s.orientation.toRotationMatrix());  // as the driver publishes it
    const auto& p = poses[k].pose;
    EXPECT_EQ(p.position.x, s.position.x()) << k;
    EXPECT_EQ(p.position.y, s.position.y()) << k;
    EXPECT_EQ(p.position.z, s.position.z()) << k;
    EXPECT_NEAR(p.orientation.x, q.x(), 1e-15) << k;
    EXPECT_NEAR(p.orientation.y, q.y(), 1e-15) << k;
    EXPECT_NEAR(p.orientation.w, q.w(), 1e-15) << k;
    EXPECT_EQ((poses[k].header.stamp - poses[0].header.stamp).toNSec(), int64_t(k) * 1000000) << k;
  }
  // straight.csv: up, pressed from 0.5 s to 2.5 s, up.
  EXPECT_EQ(button_changes, (std::vector<bool>{false, true, false}));
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "haptic_driver_replay_fast_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
