// paint_model under hostile input (issue 24): every malformed or hostile surfels cloud of
// hostile_input_support.h is refused (counted in /diagnostics and paint_stats, the reason named) or, for one
// infinite coordinate, taken without that surfel; the current object is kept through all of them, a bad
// device pose is refused, services called with bad arguments answer false with a message, and the next valid
// cloud becomes the object.
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/PaintCommand.h>
#include <relaxed_connectivity/PaintFile.h>
#include <relaxed_connectivity/PaintStats.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <cmath>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "hostile_input_support.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {
namespace {

/// A side x side grid of surfels with normals on the plane z = 0 in world, `spacing` apart.
sensor_msgs::PointCloud2 plane(int side, double spacing, const ros::Time& stamp) {
  SurfelCloud c;
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      c.positions.emplace_back(spacing * (i - side / 2), spacing * (j - side / 2), 0.0);
      c.normals.push_back(Vec3::UnitZ());
      c.radii.push_back(float(spacing));
    }
  c.frame_id = "world";
  c.stamp_ns = stamp.toNSec();
  sensor_msgs::PointCloud2 msg;
  PointCloud2Converter::toMessage(c, msg, PointCloud2Layout::kPointSurfel);
  return msg;
}

struct Session {
  std::mutex mutex;
  sensor_msgs::PointCloud2ConstPtr painted;  // the latest full cloud
  size_t full_clouds = 0;
  relaxed_connectivity::PaintStatsConstPtr stats;
  ros::Subscriber painted_sub, stats_sub;

  Session() {
    ros::NodeHandle nh;
    painted_sub = nh.subscribe<sensor_msgs::PointCloud2>("surfels/painted", 5, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(mutex);
      painted = m;
      ++full_clouds;
    });
    stats_sub = nh.subscribe<relaxed_connectivity::PaintStats>("paint_stats", 5, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(mutex);
      stats = m;
    });
  }
  size_t paintedPoints() {
    std::lock_guard<std::mutex> lock(mutex);
    return painted ? size_t(painted->width) * painted->height : 0;
  }
  unsigned rejected() {
    std::lock_guard<std::mutex> lock(mutex);
    return stats ? stats->rejected_messages : 0;
  }
};

template <class Service>
bool call(const std::string& name, Service& srv) {
  EXPECT_TRUE(ros::service::waitForService(name, ros::Duration(10.0))) << name;
  EXPECT_TRUE(ros::service::call(name, srv)) << name;
  return srv.response.success;
}

bool spinUntil(const std::function<bool()>& done, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::WallTime::now() < end && ros::ok()) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.02).sleep();
  }
  return false;
}

TEST(PaintModelBadInput, HostileCloudsPosesAndServiceArgumentsAreRefusedAndTheObjectKept) {
  ros::NodeHandle nh;
  ros::Publisher surfels = nh.advertise<sensor_msgs::PointCloud2>("surfels", 20);
  ros::Publisher pose = nh.advertise<geometry_msgs::PoseStamped>("haptic/pose", 20);
  Session session;
  test::InputDiagnostics diagnostics;
  ASSERT_TRUE(
      spinUntil([&] { return surfels.getNumSubscribers() > 0 && pose.getNumSubscribers() > 0; }, 20.0))
      << "paint_model is not running";
  const std::string input = "paint_model: input surfels";

  // 1. A valid object: 20 x 20 surfels.
  const ros::Time first_stamp = ros::Time::now();
  surfels.publish(plane(20, 0.01, first_stamp));
  ASSERT_TRUE(spinUntil([&] { return session.paintedPoints() >= 400; }, 10.0)) << "the object was not taken";
  const size_t object_points = session.paintedPoints();
  const test::InputDiagnostics::Counts start =
      diagnostics.waitFor(input, [](const auto& c) { return c.accepted >= 1; });

  // 2. Hostile variants: each refused, the object kept.
  const std::vector<test::HostileCloud> hostile =
      test::hostileClouds(plane(20, 0.01, first_stamp), ros::Time::now(), first_stamp);
  long rejected = start.rejected;
  long accepted = start.accepted;
  for (const test::HostileCloud& h : hostile) {
    if (h.what == "one infinite coordinate") continue;  // taken without that surfel: below
    surfels.publish(h.msg);
    // An unknown frame waits in the tf message filter for ~tf_wait (2 s here).
    const double wait = h.what == "unknown frame" ? 12.0 : 8.0;
    const auto counts = diagnostics.waitFor(
        input, [&](const auto& c) { return c.rejected > rejected; }, wait);
    EXPECT_EQ(counts.rejected, rejected + 1) << h.what;
    EXPECT_EQ(counts.accepted, accepted) << h.what;
    EXPECT_FALSE(counts.last_rejection.empty()) << h.what;
    std::printf("  %-40s refused: %s\n", h.what.c_str(), counts.last_rejection.c_str());
    rejected = counts.rejected;
  }
  spinUntil([] { return false; }, 0.5);
  EXPECT_EQ(session.paintedPoints(), object_points) << "a refused cloud replaced the object";
  EXPECT_TRUE(spinUntil([&] { return session.rejected() >= unsigned(rejected); }, 5.0))
      << "paint_stats.rejected_messages " << session.rejected() << ", diagnostics " << rejected;

  // 3. Bad device poses: NaN position, a zero quaternion; refused and counted.
  const std::string pose_input = "paint_model: input /haptic/pose";
  const auto pose_start = diagnostics.waitFor(pose_input, [](const auto& c) { return c.rejected >= 0; });
  geometry_msgs::PoseStamped p;
  p.header.frame_id = "world";
  p.header.stamp = ros::Time::now();
  p.pose.position.x = std::numeric_limits<double>::quiet_NaN();
  p.pose.orientation.w = 1.0;
  pose.publish(p);
  p.pose.position.x = 0.0;
  p.pose.orientation.w = 0.0;
  pose.publish(p);
  const auto pose_counts =
      diagnostics.waitFor(pose_input, [&](const auto& c) { return c.rejected >= pose_start.rejected + 2; });
  EXPECT_EQ(pose_counts.rejected, pose_start.rejected + 2);

  // 4. Services with bad arguments: false and a reason; nothing changes.
  relaxed_connectivity::PaintCommand command;
  EXPECT_FALSE(call("paint_model/undo", command));  // nothing painted
  EXPECT_FALSE(command.response.message.empty());
  EXPECT_FALSE(call("paint_model/redo", command));
  relaxed_connectivity::PaintFile file;
  file.request.path = "/nonexistent/folder/state.ply";
  EXPECT_FALSE(call("paint_model/save", file));
  EXPECT_NE(file.response.message.find("/nonexistent/folder"), std::string::npos) << file.response.message;
  file.request.path = "";
  EXPECT_FALSE(call("paint_model/load", file));
  EXPECT_FALSE(call("paint_model/set_paint", file));
  file.request.path = "/nonexistent/brush.yaml";
  EXPECT_FALSE(call("paint_model/set_brush", file));
  EXPECT_NE(file.response.message.find("/nonexistent/brush.yaml"), std::string::npos)
      << file.response.message;
  EXPECT_EQ(session.paintedPoints(), object_points);

  // 5. One infinite coordinate: that surfel is dropped, the rest becomes the object; then a valid, larger
  // object replaces it.
  for (const test::HostileCloud& h : hostile) {
    if (h.what != "one infinite coordinate") continue;
    sensor_msgs::PointCloud2 msg = h.msg;
    msg.header.stamp = ros::Time::now();
    surfels.publish(msg);
    EXPECT_TRUE(spinUntil([&] { return session.paintedPoints() == object_points - 1; }, 10.0))
        << "painted points " << session.paintedPoints();
  }
  surfels.publish(plane(30, 0.01, ros::Time::now()));
  EXPECT_TRUE(spinUntil([&] { return session.paintedPoints() == 900; }, 10.0))
      << "painted points " << session.paintedPoints();
  const auto end = diagnostics.waitFor(input, [&](const auto& c) { return c.accepted >= accepted + 2; });
  EXPECT_EQ(end.accepted, accepted + 2);
  EXPECT_EQ(end.rejected, rejected);
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "paint_model_bad_input");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
