// haptic_driver under bad input (see haptic_driver_bad_input.test): bad poses and contacts are dropped and
// counted, the force stays what the good input gives, a stale contact fades the force to zero without a jump
// (no step between two force messages larger than F0 * (stamp difference) / fade_time * (1 + g / T): the fade
// is linear, and the 1/60 s box filter over held ticks steepens it by at most the longest tick gap g over T),
// and the loop keeps publishing.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/BrushContact.h>
#include <relaxed_connectivity/HapticLoopStats.h>
#include <ros/ros.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "launch_test_support.h"

namespace rc {
namespace {

constexpr double kDepth = 0.002, kStiffness = 400, kFadeTime = 0.05, kWindow = 1.0 / 60.0;

relaxed_connectivity::BrushContact axisContact(uint32_t index, double depth) {
  relaxed_connectivity::BrushContact c;
  c.header.frame_id = "haptic_base";
  c.penalty_stiffness = kStiffness;
  c.friction = 2;
  relaxed_connectivity::HandleContact h;
  h.index = index;
  h.depth = depth;
  h.normal.z = 1;
  c.handles.push_back(h);
  return c;
}

geometry_msgs::PoseStamped pose(double x, double qw) {
  geometry_msgs::PoseStamped p;
  p.header.frame_id = "haptic_base";
  p.header.stamp = ros::Time::now();
  p.pose.position.x = x;
  p.pose.orientation.w = qw;
  return p;
}

TEST(HapticDriverBadInput, DropsCountsFadesAndKeepsPublishing) {
  ros::NodeHandle nh;
  ros::Publisher pose_pub = nh.advertise<geometry_msgs::PoseStamped>("haptic/pose", 100);
  ros::Publisher contact_pub = nh.advertise<relaxed_connectivity::BrushContact>("brush_contact", 10);
  struct Force {
    double t, fz;
  };
  std::vector<Force> forces;
  ros::Subscriber force_sub = nh.subscribe<geometry_msgs::WrenchStamped>(
      "haptic/force_feedback", 10000, [&](const geometry_msgs::WrenchStampedConstPtr& m) {
        forces.push_back({m->header.stamp.toSec(), m->wrench.force.z});
      });
  std::map<std::string, diagnostic_msgs::DiagnosticStatus> diagnostics;  // latest per status name
  ros::Subscriber diagnostics_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
        for (const auto& status : m->status) diagnostics[status.name] = status;
      });
  std::vector<relaxed_connectivity::HapticLoopStats> stats;
  ros::Subscriber stats_sub = nh.subscribe<relaxed_connectivity::HapticLoopStats>(
      "haptic/stats", 100,
      [&](const relaxed_connectivity::HapticLoopStatsConstPtr& m) { stats.push_back(*m); });
  ASSERT_TRUE(waitFor(
      [&] {
        return force_sub.getNumPublishers() > 0 && pose_pub.getNumSubscribers() > 0 &&
               contact_pub.getNumSubscribers() > 0;
      },
      20.0));

  // Good input: the stylus at rest, the axis handle point 2 mm deep.
  bool send_contact = true;
  ros::WallTimer input = nh.createWallTimer(ros::WallDuration(0.01), [&](const ros::WallTimerEvent&) {
    pose_pub.publish(pose(0, 1));
    if (send_contact) contact_pub.publish(axisContact(0, kDepth));
  });
  const double full = kStiffness * kDepth;
  ASSERT_TRUE(waitFor([&] { return !forces.empty() && std::abs(forces.back().fz - full) < 1e-9; }, 10.0));

  // Bad input, each kind once: dropped, counted; the force does not change.
  pose_pub.publish(pose(NAN, 1));
  pose_pub.publish(pose(0.01, 1.2));
  contact_pub.publish(axisContact(8, kDepth));  // the round brush has handle points 0..7
  contact_pub.publish(axisContact(0, NAN));
  const size_t stats_before = stats.size();
  ASSERT_TRUE(waitFor([&] { return stats.size() > stats_before + 1; }, 5.0));
  EXPECT_EQ(stats.back().dropped_poses, 2u);
  EXPECT_EQ(stats.back().dropped_contacts, 2u);
  EXPECT_FALSE(stats.back().contact_stale);
  // /diagnostics: the loop's timing with its counts, and each input with its rejections.
  ASSERT_TRUE(waitFor(
      [&] {
        // a report after the bad input reached the stats window (the first reports have no window yet)
        if (diagnostics.count("haptic_driver: force loop") == 0) return false;
        for (const auto& kv : diagnostics["haptic_driver: force loop"].values)
          if (kv.key == "dropped contacts" && kv.value == "2") return true;
        return false;
      },
      5.0));
  const diagnostic_msgs::DiagnosticStatus& loop = diagnostics["haptic_driver: force loop"];
  std::map<std::string, std::string> values;
  for (const auto& kv : loop.values) values[kv.key] = kv.value;
  EXPECT_EQ(values["rate [Hz]"], "1000");
  EXPECT_EQ(values["dropped poses"], "2");
  EXPECT_EQ(values["dropped contacts"], "2");
  EXPECT_TRUE(values.count("jitter p99 [ms]"));
  EXPECT_LE(loop.level, diagnostic_msgs::DiagnosticStatus::WARN);  // timing warnings depend on the machine
  ASSERT_TRUE(diagnostics.count("haptic_driver: input /brush_contact"));
  std::string contact_rejected;
  for (const auto& kv : diagnostics["haptic_driver: input /brush_contact"].values)
    if (kv.key == "rejected") contact_rejected = kv.value;
  EXPECT_EQ(contact_rejected, "2");
  EXPECT_NEAR(forces.back().fz, full, 1e-9);

  // Stale: no more contacts. The force fades to exactly zero, never jumping.
  send_contact = false;
  const size_t fade_from = forces.size();
  ASSERT_TRUE(waitFor([&] { return forces.size() > fade_from && forces.back().fz == 0.0; }, 10.0));
  // The filter averages zero-order-held ticks: its output changes by at most the fade's slope times
  // (1 + g / T) per unit time, g the longest gap between ticks (one period when on time).
  double gap = 0;
  for (size_t i = std::max<size_t>(fade_from, 31) - 30; i < forces.size(); ++i)
    gap = std::max(gap, forces[i].t - forces[i - 1].t);
  double largest_step = 0, bound_at_largest = 0;
  int steps_checked = 0;
  for (size_t i = fade_from; i < forces.size(); ++i) {
    const double step = std::abs(forces[i].fz - forces[i - 1].fz);
    const double bound =
        full * (forces[i].t - forces[i - 1].t) / kFadeTime * (1 + gap / kWindow) * (1 + 1e-6) + 1e-9;
    EXPECT_LE(step, bound) << "force message " << i;
    if (step > largest_step) {
      largest_step = step;
      bound_at_largest = bound;
    }
    ++steps_checked;
  }
  std::printf(
      "haptic_driver_bad_input: fade over %d force messages, largest step %.4g N (bound %.4g N), "
      "longest tick gap %.3g ms\n",
      steps_checked, largest_step, bound_at_largest, 1e3 * gap);
  EXPECT_GT(steps_checked, 10);

  // The loop keeps publishing, the stats say stale.
  const size_t forces_after = forces.size(), stats_after = stats.size();
  ASSERT_TRUE(waitFor([&] { return stats.size() > stats_after + 1; }, 5.0));
  EXPECT_GT(forces.size(), forces_after + 100);
  EXPECT_TRUE(stats.back().contact_stale);
  EXPECT_EQ(stats.back().force_norm, 0.0);
  EXPECT_EQ(stats.back().rate, 1000.0);
  EXPECT_GT(stats.back().ticks, stats[stats.size() - 2].ticks);
  EXPECT_EQ(stats.back().dropped_poses, 2u);
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "haptic_driver_bad_input_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
