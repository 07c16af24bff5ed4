// launch/shell_demo.launch (gui:=false, the balloon of Fig. 7.10 with node_count:=300): shell_sim publishes
// the dense surfels with the scene's surfel count and the node / fiber markers with the simulation's counts,
// pauses, steps whole frames, resets to t = 0; a force on one node (or on the nodes near a point) pushes that
// node farther than any other along the force; unknown commands, non-finite or zero forces, node indices out
// of range, bad durations and radii are refused with a clear message, and the node keeps running; the rviz
// config shows topics the node publishes.
#include <gtest/gtest.h>
#include <relaxed_connectivity/ShellForce.h>
#include <relaxed_connectivity/ShellHold.h>
#include <relaxed_connectivity/ShellStats.h>
#include <relaxed_connectivity/SimulationCommand.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <unistd.h>
#include <visualization_msgs/Marker.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "launch_test_support.h"
#include "relaxed_connectivity/ros/shell_simulator.h"
#include "relaxed_connectivity/shell/shell_scene_reader.h"

namespace {

using rc::expectRvizTopicsPublished;
using rc::waitFor;

using relaxed_connectivity::ShellForce;
using relaxed_connectivity::ShellStats;
using relaxed_connectivity::SimulationCommand;

struct Inbox {
  std::mutex mutex;
  sensor_msgs::PointCloud2ConstPtr surfels;
  visualization_msgs::MarkerConstPtr nodes, fibers;
  ShellStats stats;
  int stats_count = 0;
};

/// Spins until `done` or the timeout.
/// Waits until the node is paused at `frame` and the surfels and markers of that publication have arrived.
bool waitForPausedFrame(Inbox& inbox, uint32_t frame) {
  return waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        return inbox.surfels && inbox.nodes && inbox.fibers && !inbox.stats.running &&
               inbox.stats.frame == frame && inbox.nodes->header.stamp == inbox.stats.header.stamp &&
               inbox.fibers->header.stamp == inbox.stats.header.stamp &&
               inbox.surfels->header.stamp == inbox.stats.header.stamp;
      },
      30.0);
}

std::vector<rc::Vec3> markerPoints(const visualization_msgs::Marker& marker) {
  std::vector<rc::Vec3> points;
  for (const auto& p : marker.points) points.emplace_back(p.x, p.y, p.z);
  return points;
}

TEST(ShellDemoLaunch, CloudMarkersCommandsAndForces) {
  const rc::ShellScene scene =
      rc::loadShellScene(std::string(RC_SOURCE_DIR) + "/config/shell/fig7_10_balloon.yaml");
  ASSERT_EQ(scene.surfels.size(), 24578u);  // Table 7.1
  ASSERT_GT(scene.frame_time, 0.0);

  ros::NodeHandle nh;
  int node_count = 0;
  ASSERT_TRUE(nh.getParam("shell_sim/node_count", node_count));
  ASSERT_EQ(node_count, 300);

  Inbox inbox;
  auto surfels_sub = nh.subscribe<sensor_msgs::PointCloud2>("shell_sim/surfels", 2,
                                                            [&](const sensor_msgs::PointCloud2ConstPtr& m) {
                                                              std::lock_guard<std::mutex> lock(inbox.mutex);
                                                              inbox.surfels = m;
                                                            });
  auto nodes_sub = nh.subscribe<visualization_msgs::Marker>("shell_sim/nodes", 2,
                                                            [&](const visualization_msgs::MarkerConstPtr& m) {
                                                              std::lock_guard<std::mutex> lock(inbox.mutex);
                                                              inbox.nodes = m;
                                                            });
  auto fibers_sub = nh.subscribe<visualization_msgs::Marker>(
      "shell_sim/fibers", 2, [&](const visualization_msgs::MarkerConstPtr& m) {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        inbox.fibers = m;
      });
  auto stats_sub = nh.subscribe<ShellStats>("shell_sim/stats", 100,
                                            [&](const relaxed_connectivity::ShellStatsConstPtr& m) {
                                              std::lock_guard<std::mutex> lock(inbox.mutex);
                                              inbox.stats = *m;
                                              ++inbox.stats_count;
                                            });

  // Running: the surfels (the scene's count) and the markers (the simulation's counts) arrive.
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        return inbox.surfels && inbox.nodes && inbox.fibers && inbox.stats.running && inbox.stats.frame >= 2;
      },
      90.0));
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_TRUE(inbox.stats.error.empty()) << inbox.stats.error;
    EXPECT_EQ(inbox.stats.scene, "fig7_10_balloon");
    EXPECT_EQ(inbox.surfels->width * inbox.surfels->height, scene.surfels.size());
    EXPECT_EQ(inbox.stats.surfels, scene.surfels.size());
    EXPECT_NEAR(double(inbox.stats.nodes), 300.0, 0.02 * 300.0);  // selectShellNodes: within 2 %
    EXPECT_GT(inbox.stats.fibers, inbox.stats.nodes);
    EXPECT_EQ(inbox.surfels->header.frame_id, "world");
    EXPECT_EQ(inbox.nodes->header.frame_id, "world");
    EXPECT_EQ(inbox.fibers->header.frame_id, "world");
    EXPECT_EQ(inbox.nodes->type, visualization_msgs::Marker::SPHERE_LIST);
    EXPECT_EQ(inbox.fibers->type, visualization_msgs::Marker::LINE_LIST);
    std::set<std::string> fields;
    for (const auto& field : inbox.surfels->fields) fields.insert(field.name);
    for (const char* name : {"x", "y", "z", "normal_x", "normal_y", "normal_z"})
      EXPECT_EQ(fields.count(name), 1u) << name;
  }

  ros::ServiceClient command = nh.serviceClient<SimulationCommand>("shell_sim/command");
  ros::ServiceClient force = nh.serviceClient<ShellForce>("shell_sim/apply_force");
  ASSERT_TRUE(command.waitForExistence(ros::Duration(10)));
  ASSERT_TRUE(force.waitForExistence(ros::Duration(10)));
  auto call = [&](const std::string& name, uint32_t steps = 0) {
    return rc::callCommand(command, name, steps);
  };

  // Pause and reset: t = 0, the markers show every node and fiber.
  call("pause");
  call("reset");
  ASSERT_TRUE(waitForPausedFrame(inbox, 0));
  uint32_t nodes = 0;
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_EQ(inbox.stats.step, 0u);
    EXPECT_EQ(inbox.stats.time, 0.0);
    EXPECT_EQ(inbox.stats.active_forces, 0u);
    nodes = inbox.stats.nodes;
    EXPECT_EQ(inbox.nodes->points.size(), inbox.stats.nodes);
    EXPECT_EQ(inbox.fibers->points.size(), 4u * inbox.stats.fibers);
    EXPECT_EQ(inbox.surfels->width * inbox.surfels->height, scene.surfels.size());
  }

  // Exactly 2 frames of frame_time each.
  call("frame", 2);
  ASSERT_TRUE(waitForPausedFrame(inbox, 2));
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_NEAR(inbox.stats.time, 2 * scene.frame_time, 1e-9 * scene.frame_time);
    EXPECT_GT(inbox.stats.step, 2u);
    EXPECT_GT(inbox.stats.pressure, 0.0);  // the balloon's ramp has started
  }
  // step N: N solver steps inside the frame (the frame count stays; the next frame still ends at its time).
  uint64_t steps_before = 0;
  double time_before = 0.0;
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    steps_before = inbox.stats.step;
    time_before = inbox.stats.time;
  }
  call("step", 3);
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        return inbox.stats.step == steps_before + 3;
      },
      30.0));
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_EQ(inbox.stats.frame, 2u);
    EXPECT_GT(inbox.stats.time, time_before);
    EXPECT_LT(inbox.stats.time, time_before + scene.frame_time);
  }
  // ~save: the deformed surfels as PLY (read back); another extension is refused.
  EXPECT_EQ(rc::savedPointCount(nh, "shell_sim/save", ".vtu", "supported: .ply .pcd .xyz"),
            scene.surfels.size());

  // ~hold: bad requests are refused and change nothing; holding every node keeps it where it is (the
  // balloon's pressure pushes, nothing moves); reset restores the scene's own (none).
  ros::ServiceClient hold = nh.serviceClient<relaxed_connectivity::ShellHold>("shell_sim/hold");
  ASSERT_TRUE(hold.waitForExistence(ros::Duration(10)));
  {
    relaxed_connectivity::ShellHold bad;
    bad.request.lo.x = bad.request.lo.y = bad.request.lo.z = -100;
    bad.request.hi.x = bad.request.hi.y = bad.request.hi.z = 100;
    bad.request.components = "xw";
    ASSERT_TRUE(hold.call(bad));
    EXPECT_FALSE(bad.response.success);
    EXPECT_NE(bad.response.message.find("components 'xw'"), std::string::npos) << bad.response.message;
    bad.request.components = "";
    bad.request.lo.x = bad.request.hi.x = 1000;  // no node
    ASSERT_TRUE(hold.call(bad));
    EXPECT_FALSE(bad.response.success);
    EXPECT_NE(bad.response.message.find("holds no node"), std::string::npos) << bad.response.message;
    bad.request.lo.x = 5, bad.request.hi.x = -5;  // hi below lo
    ASSERT_TRUE(hold.call(bad));
    EXPECT_FALSE(bad.response.success);
  }
  {
    relaxed_connectivity::ShellHold all;
    all.request.lo.x = all.request.lo.y = all.request.lo.z = -100;
    all.request.hi.x = all.request.hi.y = all.request.hi.z = 100;
    ASSERT_TRUE(hold.call(all));
    EXPECT_TRUE(all.response.success) << all.response.message;
    EXPECT_EQ(all.response.nodes, nodes);
    std::vector<rc::Vec3> before;
    {
      std::lock_guard<std::mutex> lock(inbox.mutex);
      before = markerPoints(*inbox.nodes);
    }
    call("frame", 1);
    ASSERT_TRUE(waitForPausedFrame(inbox, 3));
    std::lock_guard<std::mutex> lock(inbox.mutex);
    const std::vector<rc::Vec3> after = markerPoints(*inbox.nodes);
    ASSERT_EQ(after.size(), before.size());
    double moved = 0.0;
    for (size_t i = 0; i < after.size(); ++i) moved = std::max(moved, (after[i] - before[i]).norm());
    EXPECT_EQ(moved, 0.0);
  }

  // One frame without a force, then the same frame with an outward force on node `pushed`: the node moves
  // outward, farther than any other node.
  call("reset");
  ASSERT_TRUE(waitForPausedFrame(inbox, 0));
  const std::vector<rc::Vec3> rest = markerPoints(*inbox.nodes);
  ASSERT_EQ(rest.size(), nodes);
  call("frame", 1);
  ASSERT_TRUE(waitForPausedFrame(inbox, 1));
  const std::vector<rc::Vec3> free_frame = markerPoints(*inbox.nodes);
  call("reset");
  ASSERT_TRUE(waitForPausedFrame(inbox, 0));
  const size_t pushed = nodes / 3;
  const rc::Vec3 outward = rest[pushed].normalized();
  ShellForce push;
  push.request.node = int32_t(pushed);
  push.request.force.x = 2000.0 * outward.x();
  push.request.force.y = 2000.0 * outward.y();
  push.request.force.z = 2000.0 * outward.z();
  push.request.duration = scene.frame_time;
  ASSERT_TRUE(force.call(push));
  EXPECT_TRUE(push.response.success) << push.response.message;
  EXPECT_EQ(push.response.nodes, 1u);
  call("frame", 1);
  ASSERT_TRUE(waitForPausedFrame(inbox, 1));
  const std::vector<rc::Vec3> pushed_frame = markerPoints(*inbox.nodes);
  ASSERT_EQ(pushed_frame.size(), free_frame.size());
  size_t farthest = 0;
  double farthest_distance = 0.0;
  for (size_t i = 0; i < pushed_frame.size(); ++i) {
    const double d = (pushed_frame[i] - free_frame[i]).norm();
    if (d > farthest_distance) farthest = i, farthest_distance = d;
  }
  EXPECT_EQ(farthest, pushed);
  // Free flight: mass ~ density (1) * sphere area / nodes, displacement F T^2 / m; the fibers hold it back a
  // little, the pressure ramp is the same in both runs.
  const double mass = 4.0 * M_PI * 10.0 * 10.0 / double(nodes);
  const double free_flight = 2000.0 * scene.frame_time * scene.frame_time / mass;
  const double pushed_out = (pushed_frame[pushed] - free_frame[pushed]).dot(outward);
  EXPECT_GT(pushed_out, 0.5 * free_flight);
  EXPECT_LT(pushed_out, 1.5 * free_flight);
  EXPECT_EQ(inbox.stats.active_forces, 0u);  // lasted exactly one frame

  // The nodes near a point (given at the pushed node's position, 3 m radius) are selected.
  ShellForce area = push;
  area.request.node = -1;
  area.request.point.x = pushed_frame[pushed].x();
  area.request.point.y = pushed_frame[pushed].y();
  area.request.point.z = pushed_frame[pushed].z();
  area.request.radius = 3.0;
  ASSERT_TRUE(force.call(area));
  EXPECT_TRUE(area.response.success) << area.response.message;
  size_t near = 0;
  for (const rc::Vec3& p : pushed_frame) near += (p - pushed_frame[pushed]).norm() <= 3.0;
  EXPECT_EQ(area.response.nodes, near);
  EXPECT_GT(near, 1u);

  // Refused: the message says why, no force is added.
  SimulationCommand unknown;
  unknown.request.command = "fly";
  ASSERT_TRUE(command.call(unknown));
  EXPECT_FALSE(unknown.response.success);
  EXPECT_NE(unknown.response.message.find("unknown command 'fly'"), std::string::npos);
  auto refused = [&](ShellForce request, const std::string& expected_text) {
    ASSERT_TRUE(force.call(request));
    EXPECT_FALSE(request.response.success);
    EXPECT_EQ(request.response.nodes, 0u);
    EXPECT_NE(request.response.message.find(expected_text), std::string::npos) << request.response.message;
  };
  ShellForce nan_force = push;
  nan_force.request.force.y = std::numeric_limits<double>::quiet_NaN();
  refused(nan_force, "force is not finite");
  ShellForce zero_force = push;
  zero_force.request.force.x = zero_force.request.force.y = zero_force.request.force.z = 0.0;
  refused(zero_force, "force is zero");
  ShellForce out_of_range = push;
  out_of_range.request.node = int32_t(nodes);
  refused(out_of_range,
          "node " + std::to_string(nodes) + " is out of range (" + std::to_string(nodes) + " nodes)");
  ShellForce negative_node = push;
  negative_node.request.node = -2;
  refused(negative_node, "node must be");
  ShellForce no_duration = push;
  no_duration.request.duration = 0.0;
  refused(no_duration, "duration must be");
  ShellForce no_radius = area;
  no_radius.request.radius = 0.0;
  refused(no_radius, "radius must be");
  ShellForce far_away = area;
  far_away.request.point.x = 100.0;
  refused(far_away, "no node within");

  // Still running: only the area force is active; one more frame applies it, then start.
  call("frame", 1);
  ASSERT_TRUE(waitForPausedFrame(inbox, 2));
  EXPECT_EQ(inbox.stats.active_forces, 0u);
  EXPECT_TRUE(inbox.stats.error.empty()) << inbox.stats.error;
  call("start");
  const int seen = inbox.stats_count;
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        return inbox.stats.running && inbox.stats_count > seen + 3 && inbox.stats.frame > 3;
      },
      30.0));
}

// config/rviz/shell_demo.rviz shows topics that shell_sim publishes.
TEST(ShellDemoLaunch, RvizConfigShowsPublishedTopics) {
  expectRvizTopicsPublished(std::string(RC_SOURCE_DIR) + "/config/rviz/shell_demo.rviz", 4);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "shell_demo_launch_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
