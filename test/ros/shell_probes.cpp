// shell_sim's ~probes (relaxed_connectivity/ShellProbes) for config/shell/hanging_sheet_probes.yaml: the
// probe names of the scene; at t = 0 the pinned top edge carries only its own weight (its reaction is -m g of
// its nodes), and when the damped sheet has come to rest (6 s) its reaction is the whole sheet's weight
// within 1 %.
#include <gtest/gtest.h>
#include <relaxed_connectivity/ShellProbes.h>
#include <relaxed_connectivity/SimulationCommand.h>
#include <ros/ros.h>

#include <cmath>
#include <mutex>
#include <vector>

#include "launch_test_support.h"

namespace {

TEST(ShellProbes, TheNodePublishesTheScenesProbesWithEachFrame) {
  ros::NodeHandle nh;
  std::mutex mutex;
  std::vector<relaxed_connectivity::ShellProbesConstPtr> received;
  auto sub = nh.subscribe<relaxed_connectivity::ShellProbes>("shell_sim/probes", 100, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(mutex);
    received.push_back(m);
  });
  ros::ServiceClient command = nh.serviceClient<relaxed_connectivity::SimulationCommand>("shell_sim/command");
  ASSERT_TRUE(command.waitForExistence(ros::Duration(10)));
  const ros::WallTime connect = ros::WallTime::now() + ros::WallDuration(10.0);
  while (sub.getNumPublishers() == 0 && ros::WallTime::now() < connect) ros::WallDuration(0.01).sleep();
  rc::callCommand(command, "reset");
  ros::WallDuration(0.3).sleep();         // frames in flight, and the reset state published
  rc::callCommand(command, "frame", 30);  // 30 frames: 6 s of simulated time
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(60.0);
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (!received.empty() && received.back()->time > 5.9) break;
    }
    ASSERT_LT(ros::WallTime::now(), end) << "no probes past t = 5.9 s within 60 s";
    ros::WallDuration(0.05).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  const auto& last = received.back();
  ASSERT_EQ(last->names.size(), 2u);
  EXPECT_EQ(last->scene, "hanging_sheet_probes");
  EXPECT_EQ(last->names[0], "top");
  EXPECT_EQ(last->names[1], "bottom");
  ASSERT_EQ(last->reactions.size(), 2u);
  const double weight = last->mass * 1.0;  // g = 1
  EXPECT_NEAR(last->reactions[0].y, weight, 0.01 * weight);
  EXPECT_NEAR(last->reactions[0].x, 0.0, 1e-3 * weight);
  EXPECT_LT(last->mean_displacements[1].y, 0.0);  // the lower edge sagged
  EXPECT_LT(last->kinetic_energy, 1e-6 * last->membrane_energy);
  // At t = 0 (after the reset) the pins carry their own weight only.
  for (const auto& m : received) {
    if (m->time == 0.0) {
      EXPECT_NEAR(m->reactions[0].y, m->masses[0], 1e-12);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "shell_probes_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
