// fem_sim's ~probes (relaxed_connectivity/FemProbes) for config/fem/dropped_block_probes.yaml: the probe
// names and node counts of the scene, and before the block lands (t < 0.4 s) the exact implicit Euler free
// fall of its mass-weighted mean displacement and momentum.
#include <gtest/gtest.h>
#include <relaxed_connectivity/FemProbes.h>
#include <relaxed_connectivity/SimulationCommand.h>
#include <ros/ros.h>

#include <cmath>
#include <mutex>
#include <vector>

#include "launch_test_support.h"

namespace {

TEST(FemProbes, TheNodePublishesTheScenesProbesWithEachFrame) {
  ros::NodeHandle nh;
  std::mutex mutex;
  std::vector<relaxed_connectivity::FemProbesConstPtr> received;
  auto sub = nh.subscribe<relaxed_connectivity::FemProbes>("fem_sim/probes", 100, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(mutex);
    received.push_back(m);
  });
  // From t = 0: reset (paused at the start), forget what came before, start.
  ros::ServiceClient command = nh.serviceClient<relaxed_connectivity::SimulationCommand>("fem_sim/command");
  ASSERT_TRUE(command.waitForExistence(ros::Duration(10)));
  const ros::WallTime connect = ros::WallTime::now() + ros::WallDuration(10.0);
  while (sub.getNumPublishers() == 0 && ros::WallTime::now() < connect) ros::WallDuration(0.01).sleep();
  rc::callCommand(command, "reset");
  ros::WallDuration(0.2).sleep();  // frames in flight
  {
    std::lock_guard<std::mutex> lock(mutex);
    received.clear();
  }
  rc::callCommand(command, "start");
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(30.0);
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (!received.empty() && received.back()->time > 0.6) break;
    }
    ASSERT_LT(ros::WallTime::now(), end) << "no probes past t = 0.6 s within 30 s";
    ros::WallDuration(0.05).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  const double h = 0.01, g = 9.81, mass = 1.0 * 0.5 * 0.5;
  size_t falling = 0;
  for (const auto& m : received) {
    EXPECT_EQ(m->scene, "dropped_block_probes");
    ASSERT_EQ(m->names.size(), 2u);
    EXPECT_EQ(m->names[0], "block");
    EXPECT_EQ(m->names[1], "bottom");
    ASSERT_EQ(m->nodes.size(), 2u);
    EXPECT_EQ(m->nodes[0], 45u);  // 5 x 3 x 3
    EXPECT_EQ(m->nodes[1], 15u);  // the bottom face, 5 x 3
    ASSERT_EQ(m->mean_displacements.size(), 2u);
    EXPECT_NEAR(m->masses[0], mass, 1e-12);
    if (m->time < 0.4) {
      ++falling;
      const double n = std::round(m->time / h);
      EXPECT_NEAR(m->mean_displacements[0].z, -g * h * h * n * (n + 1) / 2, 1e-9) << "t " << m->time;
      EXPECT_NEAR(m->momentum.z, -mass * g * m->time, 1e-9);
    }
  }
  EXPECT_GE(falling, 5u);
  // Landed: the bottom face rests on the ground (its mean displacement about -1 m, within the bounce).
  EXPECT_LT(received.back()->mean_displacements[1].z, -0.9);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "fem_probes_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
