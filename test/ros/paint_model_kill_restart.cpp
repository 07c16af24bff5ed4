// paint_model killed mid-session and restarted (issue 24): a stroke is painted on a plane, the node
// autosaves, then it is killed with SIGKILL (no chance to save) and roslaunch respawns it; with ~resume it
// loads its autosave: the painted object comes back surfel for surfel (positions, colours, the children paint
// made), the latched plane on `surfels` is refused (the object holds paint), and painting goes on.
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/PaintStats.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {
namespace {

/// The plane z = 0 of `world`, 6 cm square, 0.5 mm grid (radius 0.5 mm), normals +z, grey.
sensor_msgs::PointCloud2Ptr planeMessage() {
  SurfelCloud c;
  for (int i = -60; i <= 60; ++i)
    for (int j = -60; j <= 60; ++j) {
      c.positions.push_back(Vec3(0.1 + 0.0005 * i, 0.0005 * j, 0));
      c.normals.push_back(Vec3::UnitZ());
      c.radii.push_back(0.0005f);
      c.colors.push_back({128, 128, 128, 255});
    }
  c.frame_id = "world";
  return PointCloud2Converter::toMessage(c);
}

/// The surfels of a full cloud as sorted (position, colour) rows: equal for equal states, whatever the order.
using State = std::vector<std::array<float, 6>>;
State stateOf(const sensor_msgs::PointCloud2& msg) {
  const SurfelCloud c = PointCloud2Converter::fromMessage(msg);
  State s;
  for (size_t i = 0; i < c.size(); ++i)
    s.push_back({float(c.positions[i].x()), float(c.positions[i].y()), float(c.positions[i].z()),
                 float(c.colors[i][0]), float(c.colors[i][1]), float(c.colors[i][2])});
  std::sort(s.begin(), s.end());
  return s;
}

size_t grey(const State& s) {
  return size_t(std::count_if(s.begin(), s.end(), [](const auto& r) { return r[3] == 128 && r[4] == 128; }));
}

class PaintModelKillRestart : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh;
    surfels_pub_ = nh.advertise<sensor_msgs::PointCloud2>("surfels", 1, /*latch=*/true);
    pose_pub_ = nh.advertise<geometry_msgs::PoseStamped>("haptic/pose", 10);
    painted_sub_ = nh.subscribe<sensor_msgs::PointCloud2>("surfels/painted", 5, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      full_.push_back(m);
    });
    stats_sub_ = nh.subscribe<relaxed_connectivity::PaintStats>("paint_stats", 5, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      stats_ = m;
    });
    ASSERT_TRUE(waitFor([&] { return pose_pub_.getNumSubscribers() > 0; }, 20.0))
        << "paint_model is not running";
    ASSERT_TRUE(ros::param::get("/paint_model/autosave", autosave_));
  }

  bool waitFor(const std::function<bool()>& done, double seconds) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::WallTime::now() < end && ros::ok()) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (done()) return true;
      }
      ros::WallDuration(0.02).sleep();
    }
    return false;
  }

  /// The ferrule at height z over the plane at x (haptic_base sits at (0.1, 0, 0.2) of world), for `seconds`,
  /// moving along x by `dx` meanwhile.
  void hold(double x, double z, double dx, double seconds) {
    geometry_msgs::PoseStamped p;
    p.header.frame_id = "haptic_base";
    p.pose.orientation.w = 1.0;
    const ros::WallTime start = ros::WallTime::now();
    for (double t = 0; t < seconds; t = (ros::WallTime::now() - start).toSec()) {
      p.header.stamp = ros::Time::now();
      p.pose.position.x = x + dx * t / seconds;
      p.pose.position.z = z - 0.2;
      pose_pub_.publish(p);
      ros::WallDuration(0.005).sleep();
    }
  }

  ros::Publisher surfels_pub_, pose_pub_;
  ros::Subscriber painted_sub_, stats_sub_;
  std::mutex mutex_;
  std::vector<sensor_msgs::PointCloud2ConstPtr> full_;
  relaxed_connectivity::PaintStatsConstPtr stats_;
  std::string autosave_;
};

TEST_F(PaintModelKillRestart, ResumesFromItsAutosaveWithNothingPaintedLost) {
  surfels_pub_.publish(planeMessage());
  ASSERT_TRUE(waitFor([&] { return !full_.empty(); }, 10.0)) << "no painted cloud";
  // A stroke across the plane, then the brush lifted (the stroke ends after stroke_gap).
  hold(-0.015, 0.03, 0.0, 0.3);
  hold(-0.015, 0.004, 0.03, 1.5);
  hold(0.015, 0.03, 0.0, 0.5);
  const bool stroke = waitFor([&] { return stats_ && stats_->undo_strokes >= 1; }, 5.0);
  ASSERT_TRUE(stroke) << "no stroke was recorded";
  // The state after the stroke: the last full cloud (painted_rate 10 Hz: one follows the last change within
  // 0.1 s; nothing changes after the stroke, drying and downsampling are off).
  ros::WallDuration(1.0).sleep();
  State before;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    before = stateOf(*full_.back());
  }
  const size_t painted = before.size() - grey(before);
  std::printf("before the kill: %zu surfels, %zu painted\n", before.size(), painted);
  ASSERT_GT(painted, 50u) << "the stroke left no paint";
  // An autosave after that state (autosave_period 1 s; written to a temporary file, then renamed).
  const auto saved_after = std::filesystem::file_time_type::clock::now();
  ASSERT_TRUE(waitFor(
      [&] {
        std::error_code error;
        return std::filesystem::last_write_time(autosave_, error) >
               saved_after + std::chrono::milliseconds(200);
      },
      10.0))
      << "no autosave to " << autosave_;

  // SIGKILL: the node cannot save anything on its way out. roslaunch respawns it.
  size_t clouds_before_kill;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    clouds_before_kill = full_.size();
  }
  const ros::Time killed = ros::Time::now();
  ASSERT_EQ(std::system("pkill -KILL -f '__name:=paint_model( |$)'"), 0);
  ASSERT_TRUE(
      waitFor([&] { return full_.size() > clouds_before_kill && full_.back()->header.stamp > killed; }, 30.0))
      << "the respawned paint_model published no object";
  State after;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    after = stateOf(*full_.back());
  }
  std::printf("after the restart: %zu surfels, %zu painted\n", after.size(), after.size() - grey(after));
  EXPECT_EQ(after.size(), before.size());
  EXPECT_TRUE(after == before) << "the resumed object differs from the state before the kill";
  // The latched plane came again to the new node and was refused (the object holds paint).
  EXPECT_TRUE(waitFor(
      [&] { return stats_ && stats_->header.stamp > killed && stats_->rejected_messages >= 1; }, 10.0));
  // Painting goes on.
  hold(-0.015, 0.03, 0.0, 0.3);
  hold(-0.015, 0.004, 0.0, 1.0);
  hold(-0.015, 0.03, 0.0, 0.5);
  EXPECT_TRUE(waitFor([&] { return stats_ && stats_->undo_strokes >= 1; }, 5.0));
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "paint_model_kill_restart_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
