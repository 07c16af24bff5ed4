// haptic_driver with device:=topic against a recorded bag of device poses (see haptic_driver_bag.test): in
// the bag's steady segments (constant linear or angular velocity for at least 0.2 s, longer than the 1/60 s
// filter window plus the transport delay) the published force must equal the force law written out here:
// every handle point d0 deep below the plane z = 0 (plane depth stays d0 under tangential motion), so
//   F = sum_i K_p d0 N - eta d0 v_t,i,   tau = sum_i r_i x F_i,   v_i = v + w x r_i,  r_i = R * offset_i.
// Tolerance: the driver's velocity is a backward difference of pose stamps (taken relative to the first pose:
// as epoch seconds a double resolves only ~240 ns) over a baseline of >= 2 ms, stamps that ROS rounds to 1
// ns: relative error <= 1e-6 of the 0.56 N friction; the test's own velocity is taken over its 0.2 s window
// (5e-9); in a steady segment the box filter averages equal values (rounding only). Hence 1e-5 N and 1e-7 N m
// against forces of ~6 N and torques of ~6e-4 N m.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/BrushContact.h>
#include <relaxed_connectivity/HapticLoopStats.h>
#include <ros/ros.h>

#include <deque>

#include "launch_test_support.h"
#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/brush_skeleton.h"

namespace rc {
namespace {

constexpr double kDepth = 0.002, kStiffness = 400, kFriction = 1000;

struct StampedPose {
  double t;
  Vec3 position;
  Eigen::Quaterniond orientation;
};

TEST(HapticDriverBag, ForceFollowsTheForceLaw) {
  ros::NodeHandle nh, pnh("~");
  std::string brush_path;
  ASSERT_TRUE(pnh.getParam("brush", brush_path));
  const std::vector<Vec3> offsets = BrushSkeleton(readBrushPreset(brush_path)).handleOffsets();

  relaxed_connectivity::BrushContact contact;
  contact.header.frame_id = "haptic_base";
  contact.penalty_stiffness = kStiffness;
  contact.friction = kFriction;
  for (size_t i = 0; i < offsets.size(); ++i) {
    relaxed_connectivity::HandleContact h;
    h.index = uint32_t(i);
    h.depth = kDepth;
    h.normal.z = 1;
    h.position.x =
        offsets[i].x();  // where the handle point was when d was evaluated (the stylus at the origin,
    h.position.y = offsets[i].y();  // not rotated); the stroke moves and turns it in its plane, so d stays d0
    h.position.z = offsets[i].z();
    contact.handles.push_back(h);
  }
  ros::Publisher contact_pub = nh.advertise<relaxed_connectivity::BrushContact>("brush_contact", 10);
  ros::WallTimer contact_timer = nh.createWallTimer(ros::WallDuration(0.02), [&](const ros::WallTimerEvent&) {
    contact.header.stamp = ros::Time::now();
    contact_pub.publish(contact);
  });

  // Steady state: over the last 200 poses (0.2 s) every pose-to-pose velocity equals the window's mean one
  // (within the stamp rounding); v and w are then the window's (end minus start over 0.2 s).
  std::deque<StampedPose> window;
  ros::Time stamp_origin;
  Vec3 v = Vec3::Zero(), w = Vec3::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  int poses = 0;
  ros::Subscriber pose_sub = nh.subscribe<
      geometry_msgs::PoseStamped>("haptic/pose", 10000, [&](const geometry_msgs::PoseStampedConstPtr& m) {
    ++poses;
    const auto& o = m->pose.orientation;
    const auto& p = m->pose.position;
    window.push_back({m->header.stamp.toSec(), Vec3(p.x, p.y, p.z), Eigen::Quaterniond(o.w, o.x, o.y, o.z)});
    if (window.size() > 200) window.pop_front();
    rotation = window.back().orientation.toRotationMatrix();
  });
  auto velocityBetween = [](const StampedPose& a, const StampedPose& b) {
    const Eigen::AngleAxisd dq(b.orientation * a.orientation.conjugate());
    return std::make_pair(Vec3((b.position - a.position) / (b.t - a.t)),
                          Vec3(dq.axis() * dq.angle() / (b.t - a.t)));
  };
  auto isSteady = [&] {
    if (window.size() < 200) return false;
    const auto [v_mean, w_mean] = velocityBetween(window.front(), window.back());
    for (size_t i = 1; i < window.size(); ++i) {
      if (window[i].t - window[i - 1].t < 2e-4) continue;  // too close for the rounded stamps
      const auto [vi, wi] = velocityBetween(window[i - 1], window[i]);
      if ((vi - v_mean).norm() > 1e-4 || (wi - w_mean).norm() > 1e-3) return false;
    }
    v = v_mean;
    w = w_mean;
    return true;
  };

  int checked = 0, checked_moving = 0, checked_rotating = 0, forces = 0;
  double worst_force = 0, worst_torque = 0;
  ros::Subscriber force_sub = nh.subscribe<geometry_msgs::WrenchStamped>(
      "haptic/force_feedback", 10000, [&](const geometry_msgs::WrenchStampedConstPtr& m) {
        ++forces;
        EXPECT_EQ(m->header.frame_id, "haptic_base");
        if (!isSteady()) return;
        Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
        for (const Vec3& offset : offsets) {
          const Vec3 r = rotation * offset;
          const Vec3 vi = v + w.cross(r);
          const Vec3 v_t(vi.x(), vi.y(), 0);
          const Vec3 fi = kStiffness * kDepth * Vec3::UnitZ() - kFriction * kDepth * v_t;
          force += fi;
          torque += r.cross(fi);
        }
        const Vec3 got_force(m->wrench.force.x, m->wrench.force.y, m->wrench.force.z);
        const Vec3 got_torque(m->wrench.torque.x, m->wrench.torque.y, m->wrench.torque.z);
        worst_force = std::max(worst_force, (got_force - force).norm());
        worst_torque = std::max(worst_torque, (got_torque - torque).norm());
        ++checked;
        if (v.norm() > 0.01) ++checked_moving;
        if (w.norm() > 1) ++checked_rotating;
      });
  ros::Subscriber stats_sub;
  relaxed_connectivity::HapticLoopStats last_stats;
  stats_sub = nh.subscribe<relaxed_connectivity::HapticLoopStats>(
      "haptic/stats", 10, [&](const relaxed_connectivity::HapticLoopStatsConstPtr& m) { last_stats = *m; });

  // The bag: 4 s of stroke plus the held last pose; wait until its poses stop.
  ASSERT_TRUE(waitFor([&] { return poses > 4000; }, 40.0)) << "poses received: " << poses;
  waitFor([] { return false; }, 1.0);
  RecordProperty("checked_forces", checked);
  std::printf(
      "haptic_driver_bag: %d poses, %d forces, %d checked (%d moving, %d rotating); worst |dF| %.3g N, "
      "|dtau| %.3g N m\n",
      poses, forces, checked, checked_moving, checked_rotating, worst_force, worst_torque);
  EXPECT_GT(checked_moving, 100);
  EXPECT_GT(checked_rotating, 100);
  EXPECT_GT(checked, 1000);
  EXPECT_LT(worst_force, 1e-5);
  EXPECT_LT(worst_torque, 1e-7);
  EXPECT_EQ(last_stats.rate, 1000.0);
  EXPECT_EQ(last_stats.dropped_poses, 0u);
  EXPECT_EQ(last_stats.dropped_contacts, 0u);
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "haptic_driver_bag");
  return RUN_ALL_TESTS();
}
