// csg_renderer, paint_renderer, mesh_converter and object_mover under hostile input (issue 24): the malformed
// and hostile clouds of hostile_input_support.h are refused with a reason and counted (/diagnostics), the
// node's state is kept, and the next valid message is taken; mesh_converter aborts such goals with the reason
// and converts the next; object_mover refuses non-finite, unnormalised and foreign-frame poses and moves on
// the next. Out-of-order stamps: csg_renderer refuses a cloud older than the one it shows; paint_renderer
// ignores a full cloud older than its copy by design (its deltas are newer), which the test checks too.
// (boost::function inside actionlib's client warns of a maybe-uninitialized copy with GCC 12)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <actionlib/client/simple_action_client.h>
#pragma GCC diagnostic pop
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/ConvertSurfelsAction.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "hostile_input_support.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {
namespace {

enum class Ids { kNone, kPatch, kFather };

/// A sphere of `count` surfels (radius 0.2) at z = 1 in front of the camera, in `frame`; with an int32
/// patch_id column (0) for csg_renderer's surfels topic or a uint32 father column (the surfel's index) as the
/// paint model's full clouds carry.
sensor_msgs::PointCloud2 sphere(size_t count, const ros::Time& stamp, Ids ids, const std::string& frame) {
  SurfelCloud c;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < count; ++i) {
    const double z = 1.0 - 2.0 * (double(i) + 0.5) / double(count), r = std::sqrt(1.0 - z * z);
    const Vec3 n(r * std::cos(golden * double(i)), r * std::sin(golden * double(i)), z);
    c.positions.push_back(0.2 * n + Vec3(0, 0, 1));
    c.normals.push_back(n);
    c.radii.push_back(float(0.2 * std::sqrt(4.0 / double(count)) * 1.5));
    c.colors.push_back({200, 120, 60, 255});
  }
  if (ids == Ids::kPatch) c.attributes.add("patch_id", ScalarType::kInt32, 1, count);
  if (ids == Ids::kFather) {
    Attribute& father = c.attributes.add("father", ScalarType::kUInt32, 1, count);
    for (size_t i = 0; i < count; ++i) father.set(i, double(i));
  }
  c.frame_id = frame;
  c.stamp_ns = stamp.toNSec();
  sensor_msgs::PointCloud2 msg;
  PointCloud2Converter::toMessage(c, msg, PointCloud2Layout::kPointSurfel);
  return msg;
}

bool spinFor(double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::WallTime::now() < end && ros::ok()) {
    ros::spinOnce();
    ros::WallDuration(0.02).sleep();
  }
  return true;
}

bool waitForSubscriber(const ros::Publisher& pub) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(20.0);
  while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < end && ros::ok()) {
    ros::spinOnce();
    ros::WallDuration(0.05).sleep();
  }
  return pub.getNumSubscribers() > 0;
}

/// Publishes each hostile cloud but those in `skip` on `pub` and expects the input status `status` to count
/// one more rejection each (unknown frames wait for the node's tf_wait, 2 s in the launch file); returns the
/// last counts. `accepted` must not change.
test::InputDiagnostics::Counts refuseAll(ros::Publisher& pub, test::InputDiagnostics& diagnostics,
                                         const std::string& status,
                                         const std::vector<test::HostileCloud>& hostile,
                                         const std::vector<std::string>& skip,
                                         const test::InputDiagnostics::Counts& start) {
  long rejected = start.rejected;
  test::InputDiagnostics::Counts counts = start;
  for (const test::HostileCloud& h : hostile) {
    if (std::find(skip.begin(), skip.end(), h.what) != skip.end()) continue;
    pub.publish(h.msg);
    const double wait = h.what == "unknown frame" ? 12.0 : 8.0;
    counts = diagnostics.waitFor(
        status, [&](const auto& c) { return c.rejected > rejected; }, wait);
    EXPECT_EQ(counts.rejected, rejected + 1) << status << ": " << h.what;
    EXPECT_EQ(counts.accepted, start.accepted) << status << ": " << h.what;
    std::printf("  %s, %-40s refused: %s\n", status.c_str(), h.what.c_str(), counts.last_rejection.c_str());
    rejected = counts.rejected;
  }
  return counts;
}

class RenderNodesBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    geometry_msgs::TransformStamped tf;  // the camera at the origin looking along +z (REP 103 optical)
    tf.header.stamp = ros::Time::now();
    tf.header.frame_id = "world";
    tf.child_frame_id = "test_camera";
    tf.transform.rotation.w = 1.0;
    broadcaster_.sendTransform(tf);
  }
  tf2_ros::StaticTransformBroadcaster broadcaster_;
  test::InputDiagnostics diagnostics_;
};

TEST_F(RenderNodesBadInput, CsgRenderer) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("surfels", 20);
  ASSERT_TRUE(waitForSubscriber(pub)) << "csg_renderer is not running";
  const std::string status = "csg_renderer: input surfels";
  const ros::Time first = ros::Time::now();
  pub.publish(sphere(400, first, Ids::kPatch, "world"));
  const auto start = diagnostics_.waitFor(status, [](const auto& c) { return c.accepted >= 1; });
  const auto hostile = test::hostileClouds(sphere(400, first, Ids::kPatch, "world"), ros::Time::now(), first);
  // One infinite coordinate: the renderer draws the finite surfels (checkRenderableCloud takes such clouds).
  const auto counts = refuseAll(pub, diagnostics_, status, hostile, {"one infinite coordinate"}, start);
  pub.publish(sphere(500, ros::Time::now(), Ids::kPatch, "world"));
  const auto end = diagnostics_.waitFor(status, [&](const auto& c) { return c.accepted > start.accepted; });
  EXPECT_EQ(end.accepted, start.accepted + 1);
  EXPECT_EQ(end.rejected, counts.rejected);
}

TEST_F(RenderNodesBadInput, PaintRenderer) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("surfels/painted", 20);
  ASSERT_TRUE(waitForSubscriber(pub)) << "paint_renderer is not running";
  const std::string status = "paint_renderer: input /surfels/painted";
  const ros::Time first = ros::Time::now();
  pub.publish(sphere(400, first, Ids::kFather, "world"));
  const auto start = diagnostics_.waitFor(status, [](const auto& c) { return c.accepted >= 1; });
  // An older full cloud than the copy is ignored by design (the copy follows newer deltas): not counted.
  const auto hostile =
      test::hostileClouds(sphere(400, first, Ids::kFather, "world"), ros::Time::now(), first);
  const auto counts = refuseAll(pub, diagnostics_, status, hostile,
                                {"one infinite coordinate", "stamp older than the current input"}, start);
  pub.publish(sphere(500, ros::Time::now(), Ids::kFather, "world"));
  const auto end = diagnostics_.waitFor(status, [&](const auto& c) { return c.accepted > start.accepted; });
  EXPECT_EQ(end.accepted, start.accepted + 1);
  EXPECT_EQ(end.rejected, counts.rejected) << end.last_rejection;
}

TEST_F(RenderNodesBadInput, MeshConverterAbortsBadGoalsAndConvertsTheNext) {
  actionlib::SimpleActionClient<relaxed_connectivity::ConvertSurfelsAction> client("mesh_converter/convert",
                                                                                   true);
  ASSERT_TRUE(client.waitForServer(ros::Duration(20.0))) << "mesh_converter is not running";
  const std::string status = "mesh_converter: conversion";
  const auto start =
      diagnostics_.waitFor(status, [](const auto& c) { return c.number("goals aborted") >= 0; });
  const auto hostile = test::hostileClouds(sphere(400, ros::Time::now(), Ids::kNone, "world"),
                                           ros::Time::now(), ros::Time::now());
  long aborted = start.number("goals aborted");
  for (const test::HostileCloud& h : hostile) {
    // (frames and stamps mean nothing to a conversion; an infinite coordinate is dropped)
    if (h.what == "unknown frame" || h.what == "stamp older than the current input" ||
        h.what == "one infinite coordinate")
      continue;
    relaxed_connectivity::ConvertSurfelsGoal goal;
    goal.cloud = h.msg;
    goal.output_prefix = "/tmp/rc_render_nodes_bad_input";
    goal.write_obj = true;
    client.sendGoal(goal);
    ASSERT_TRUE(client.waitForResult(ros::Duration(30.0))) << h.what;
    EXPECT_EQ(client.getState(), actionlib::SimpleClientGoalState::ABORTED) << h.what;
    const auto result = client.getResult();
    EXPECT_FALSE(result->success) << h.what;
    EXPECT_FALSE(result->message.empty()) << h.what;
    std::printf("  mesh_converter, %-40s aborted: %s\n", h.what.c_str(), result->message.c_str());
    const auto counts =
        diagnostics_.waitFor(status, [&](const auto& c) { return c.number("goals aborted") > aborted; });
    EXPECT_EQ(counts.number("goals aborted"), aborted + 1) << h.what;
    aborted = counts.number("goals aborted");
  }
  relaxed_connectivity::ConvertSurfelsGoal goal;
  goal.cloud = sphere(600, ros::Time::now(), Ids::kNone, "world");
  goal.output_prefix = "/tmp/rc_render_nodes_bad_input";
  goal.write_obj = true;
  client.sendGoal(goal);
  ASSERT_TRUE(client.waitForResult(ros::Duration(60.0)));
  EXPECT_EQ(client.getState(), actionlib::SimpleClientGoalState::SUCCEEDED) << client.getResult()->message;
  EXPECT_GT(client.getResult()->triangles, 100u);
}

TEST_F(RenderNodesBadInput, ObjectMoverRefusesBadPosesAndTakesTheNext) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<geometry_msgs::PoseStamped>("object_pose", 20);
  ASSERT_TRUE(waitForSubscriber(pub)) << "object_mover is not running";
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  const std::string status = "object_mover: input /object_pose";
  const auto start = diagnostics_.waitFor(status, [](const auto& c) { return c.rejected >= 0; });
  geometry_msgs::PoseStamped good;
  good.header.frame_id = "world";
  good.pose.orientation.w = 1.0;
  std::vector<std::pair<std::string, geometry_msgs::PoseStamped>> bad;
  for (int k = 0; k < 4; ++k) bad.emplace_back("", good);
  bad[0].first = "NaN position", bad[0].second.pose.position.y = std::numeric_limits<double>::quiet_NaN();
  bad[1].first = "infinite quaternion", bad[1].second.pose.orientation.x = INFINITY;
  bad[2].first = "zero quaternion", bad[2].second.pose.orientation.w = 0.0;
  bad[3].first = "foreign frame", bad[3].second.header.frame_id = "no_such_frame";
  long rejected = start.rejected;
  for (auto& [what, pose] : bad) {
    pose.header.stamp = ros::Time::now();
    pub.publish(pose);
    const auto counts = diagnostics_.waitFor(status, [&](const auto& c) { return c.rejected > rejected; });
    EXPECT_EQ(counts.rejected, rejected + 1) << what;
    std::printf("  object_mover, %-20s refused: %s\n", what.c_str(), counts.last_rejection.c_str());
    rejected = counts.rejected;
  }
  good.pose.position.x = 0.25;
  good.header.stamp = ros::Time::now();
  pub.publish(good);
  const auto end = diagnostics_.waitFor(status, [&](const auto& c) { return c.accepted > start.accepted; });
  EXPECT_EQ(end.accepted, start.accepted + 1);
  // The transform follows the good pose.
  double x = 0.0;
  const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(5.0);
  while (ros::WallTime::now() < until && std::abs(x - 0.25) > 1e-9) {
    try {
      x = buffer.lookupTransform("world", "painted_object", ros::Time(0)).transform.translation.x;
    } catch (const tf2::TransformException&) {
    }
    spinFor(0.05);
  }
  EXPECT_NEAR(x, 0.25, 1e-9);
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "render_nodes_bad_input");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
