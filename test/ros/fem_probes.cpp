// fem_sim's ~probes (relaxed_connectivity/FemProbes) for config/fem/dropped_block_probes.yaml: the probe
// names and node counts of the scene, and before the block lands (t < 0.4 s) the exact implicit Euler free
// fall of its mass-weighted mean displacement and momentum; ~load and ~hold change the run as they say.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/FemHold.h>
#include <relaxed_connectivity/FemLoad.h>
#include <relaxed_connectivity/FemProbes.h>
#include <relaxed_connectivity/SimulationCommand.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <string>
#include <vector>

#include "launch_test_support.h"

namespace {

/// fem_sim's ~probes as they arrive.
struct ProbeInbox {
  std::mutex mutex;
  std::vector<relaxed_connectivity::FemProbesConstPtr> received;
  ros::Subscriber sub;
  explicit ProbeInbox(ros::NodeHandle& nh) {
    sub = nh.subscribe<relaxed_connectivity::FemProbes>("fem_sim/probes", 100, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(mutex);
      received.push_back(m);
    });
  }
  void waitForPublisher() {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(10.0);
    while (sub.getNumPublishers() == 0 && ros::WallTime::now() < end) ros::WallDuration(0.01).sleep();
  }
  /// Forgets what came, after the frames in flight.
  void clear() {
    ros::WallDuration(0.2).sleep();
    std::lock_guard<std::mutex> lock(mutex);
    received.clear();
  }
  /// Whether probes past simulated time `t` arrive within `seconds` of wall time.
  bool waitPast(double t, double seconds) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    for (;;) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (!received.empty() && received.back()->time > t) return true;
      }
      if (ros::WallTime::now() > end) return false;
      ros::WallDuration(0.05).sleep();
    }
  }
};

/// fem_sim's ~command, the simulation paused at t = 0 (reset).
ros::ServiceClient pausedAtStart(ros::NodeHandle& nh) {
  ros::ServiceClient command = nh.serviceClient<relaxed_connectivity::SimulationCommand>("fem_sim/command");
  EXPECT_TRUE(command.waitForExistence(ros::Duration(10)));
  rc::callCommand(command, "pause");
  rc::callCommand(command, "reset");
  return command;
}

TEST(FemProbes, TheNodePublishesTheScenesProbesWithEachFrame) {
  ros::NodeHandle nh;
  ProbeInbox inbox(nh);
  // From t = 0: reset (paused at the start), forget what came before, start.
  ros::ServiceClient command = nh.serviceClient<relaxed_connectivity::SimulationCommand>("fem_sim/command");
  ASSERT_TRUE(command.waitForExistence(ros::Duration(10)));
  inbox.waitForPublisher();
  rc::callCommand(command, "reset");
  inbox.clear();
  rc::callCommand(command, "start");
  ASSERT_TRUE(inbox.waitPast(0.6, 30.0)) << "no probes past t = 0.6 s within 30 s";
  std::lock_guard<std::mutex> lock(inbox.mutex);
  const auto& received = inbox.received;
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

TEST(FemProbes, ALoadByServiceHoldsTheBlockAgainstGravity) {
  // ~load with a force equal to the block's weight, upward, over all its nodes: its centre of mass stays (the
  // mass-weighted mean displacement and the momentum 0 to 1e-9); bad loads are refused and change nothing.
  ros::NodeHandle nh;
  ProbeInbox inbox(nh);
  ros::ServiceClient command = pausedAtStart(nh);
  ros::ServiceClient load = nh.serviceClient<relaxed_connectivity::FemLoad>("fem_sim/load");
  ASSERT_TRUE(load.waitForExistence(ros::Duration(10)));
  relaxed_connectivity::FemLoad bad;
  bad.request.lo.x = bad.request.lo.y = bad.request.lo.z = 50;
  bad.request.hi.x = bad.request.hi.y = bad.request.hi.z = 60;  // no node there
  bad.request.force.z = 1;
  ASSERT_TRUE(load.call(bad));
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find("holds no node"), std::string::npos) << bad.response.message;
  bad.request.hi.x = 40;  // hi below lo
  ASSERT_TRUE(load.call(bad));
  EXPECT_FALSE(bad.response.success);
  const double mass = 1.0 * 0.5 * 0.5, g = 9.81;
  relaxed_connectivity::FemLoad lift;
  lift.request.lo.x = lift.request.lo.y = lift.request.lo.z = -100;
  lift.request.hi.x = lift.request.hi.y = lift.request.hi.z = 100;
  lift.request.force.z = mass * g;
  lift.request.clear = true;
  ASSERT_TRUE(load.call(lift));
  EXPECT_TRUE(lift.response.success) << lift.response.message;
  EXPECT_EQ(lift.response.nodes, 45u);
  EXPECT_EQ(lift.response.loads, 1u);
  inbox.waitForPublisher();
  inbox.clear();
  rc::callCommand(command, "step", 20);
  ASSERT_TRUE(inbox.waitPast(0.19, 20.0)) << "no probes past t = 0.19 s within 20 s";
  std::lock_guard<std::mutex> lock(inbox.mutex);
  for (const auto& m : inbox.received) {
    EXPECT_NEAR(m->momentum.z, 0.0, 1e-9) << "t " << m->time;
    EXPECT_NEAR(m->mean_displacements[0].z, 0.0, 1e-9) << "t " << m->time;
  }
  rc::callCommand(command, "reset");  // the scene's own loads (none) again
}

TEST(FemProbes, FrameAdvancesStepsPerFrameAndStepOneSolverStep) {
  // dropped_block_probes: dt 0.01, 3 steps per frame: "frame 2" ends at t = 0.06, then "step 1" at 0.07.
  ros::NodeHandle nh;
  std::atomic<double> clock{-1.0};
  ros::Subscriber clock_sub = nh.subscribe<rosgraph_msgs::Clock>(
      "/clock", 10, [&](const rosgraph_msgs::ClockConstPtr& m) { clock = m->clock.toSec(); });
  ProbeInbox inbox(nh);
  ros::ServiceClient command = pausedAtStart(nh);
  inbox.waitForPublisher();
  inbox.clear();
  EXPECT_TRUE(rc::callCommand(command, "frame", 2).success);
  ASSERT_TRUE(inbox.waitPast(0.05, 20.0)) << "no probes past t = 0.05 s within 20 s";
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_NEAR(inbox.received.back()->time, 0.06, 1e-12);
  }
  EXPECT_TRUE(rc::callCommand(command, "step", 1).success);
  ASSERT_TRUE(inbox.waitPast(0.065, 20.0)) << "no probes past t = 0.065 s within 20 s";
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_NEAR(inbox.received.back()->time, 0.07, 1e-12);
    // publish_clock (fem_probes.test): the messages carry the simulated time as their stamp ...
    EXPECT_NEAR(inbox.received.back()->header.stamp.toSec(), 0.07, 1e-9);
  }
  // ... and /clock follows it.
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(10.0);
  while (!(clock.load() > 0.065) && ros::WallTime::now() < end) ros::WallDuration(0.01).sleep();
  EXPECT_NEAR(clock.load(), 0.07, 1e-9);
  // /diagnostics: the simulation paused where the step left it.
  std::mutex diagnostics_mutex;
  std::string simulation_status;
  ros::Subscriber diagnostics_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
        for (const auto& status : m->status)
          if (status.name == "fem_sim: simulation") {
            std::lock_guard<std::mutex> lock(diagnostics_mutex);
            simulation_status = status.message;
          }
      });
  const ros::WallTime diagnostics_end = ros::WallTime::now() + ros::WallDuration(5.0);
  auto statusSoFar = [&] {
    std::lock_guard<std::mutex> lock(diagnostics_mutex);
    return simulation_status;
  };
  while (statusSoFar().rfind("paused, step 7,", 0) != 0 && ros::WallTime::now() < diagnostics_end)
    ros::WallDuration(0.02).sleep();
  EXPECT_EQ(statusSoFar().rfind("paused, step 7,", 0), 0u) << statusSoFar();
  // ~save writes the current state (the nodes as PLY: 45 of them); another extension is refused.
  EXPECT_EQ(rc::savedPointCount(nh, "fem_sim/save", ".stl", "supported: .vtu .obj"), 45u);
  relaxed_connectivity::SimulationCommand unknown;
  unknown.request.command = "leap";
  ASSERT_TRUE(command.call(unknown));
  EXPECT_FALSE(unknown.response.success);
  EXPECT_NE(unknown.response.message.find("(start, pause, step, frame, reset)"), std::string::npos)
      << unknown.response.message;
  rc::callCommand(command, "reset");
}

TEST(FemProbes, HoldByServiceKeepsRegionsWhereTheyAreAndReportsTheirReactions) {
  // ~hold in place over the whole block: it stays exactly, and the holders carry its weight (the probe's
  // reaction m g); then only the bottom face: it stays, the rest sags; a clear releases (free fall again).
  ros::NodeHandle nh;
  ProbeInbox inbox(nh);
  ros::ServiceClient command = pausedAtStart(nh);
  ros::ServiceClient hold = nh.serviceClient<relaxed_connectivity::FemHold>("fem_sim/hold");
  ASSERT_TRUE(hold.waitForExistence(ros::Duration(10)));
  relaxed_connectivity::FemHold request;
  request.request.lo.x = request.request.lo.y = request.request.lo.z = -100;
  request.request.hi.x = request.request.hi.y = request.request.hi.z = 100;
  request.request.components = "xw";
  ASSERT_TRUE(hold.call(request));
  EXPECT_FALSE(request.response.success);
  EXPECT_NE(request.response.message.find("letters of xyz"), std::string::npos) << request.response.message;
  request.request.components = "";
  request.request.path_times = {0.0};  // without its displacement
  ASSERT_TRUE(hold.call(request));
  EXPECT_FALSE(request.response.success);
  request.request.path_times.clear();
  request.request.in_place = true;
  ASSERT_TRUE(hold.call(request));
  ASSERT_TRUE(request.response.success) << request.response.message;
  EXPECT_EQ(request.response.nodes, 45u);
  EXPECT_EQ(request.response.regions, 1u);
  const double mass = 1.0 * 0.5 * 0.5, g = 9.81;
  inbox.waitForPublisher();
  inbox.clear();
  rc::callCommand(command, "step", 10);
  ASSERT_TRUE(inbox.waitPast(0.09, 20.0)) << "no probes past t = 0.09 s within 20 s";
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    for (const auto& m : inbox.received) {
      EXPECT_EQ(m->momentum.z, 0.0) << "t " << m->time;
      EXPECT_EQ(m->mean_displacements[0].z, 0.0) << "t " << m->time;
      ASSERT_EQ(m->reactions.size(), 2u);
      if (m->time > 0) EXPECT_NEAR(m->reactions[0].z, mass * g, 1e-9) << "t " << m->time;
    }
  }
  // Only the bottom face, replacing the region.
  request.request.clear = true;
  request.request.lo.x = 0, request.request.lo.y = 0, request.request.lo.z = 1;
  request.request.hi.x = 1, request.request.hi.y = 0.5, request.request.hi.z = 1;
  ASSERT_TRUE(hold.call(request));
  ASSERT_TRUE(request.response.success) << request.response.message;
  EXPECT_EQ(request.response.nodes, 15u);
  EXPECT_EQ(request.response.regions, 1u);
  inbox.clear();
  rc::callCommand(command, "step", 10);
  ASSERT_TRUE(inbox.waitPast(0.19, 20.0)) << "no probes past t = 0.19 s within 20 s";
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    const auto& last = inbox.received.back();
    EXPECT_EQ(last->mean_displacements[1].z, 0.0);
    EXPECT_LT(last->mean_displacements[0].z, -1e-4);  // the block sags onto its held face
    EXPECT_GT(last->mean_displacements[0].z, -0.1);
    EXPECT_GT(last->reactions[1].z, 0.0);
  }
  // Release everything: the block falls (its momentum grows downward).
  relaxed_connectivity::FemHold release;
  release.request.clear = true;
  ASSERT_TRUE(hold.call(release));
  ASSERT_TRUE(release.response.success) << release.response.message;
  EXPECT_EQ(release.response.regions, 0u);
  inbox.clear();
  rc::callCommand(command, "step", 5);
  ASSERT_TRUE(inbox.waitPast(0.24, 20.0)) << "no probes past t = 0.24 s within 20 s";
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_LT(inbox.received.back()->momentum.z, -0.5 * mass * g * 0.05);
  }
  rc::callCommand(command, "reset");  // the scene's own held regions (none) again
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "fem_probes_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
