// surfel_estimator must reject bad clouds with a named reason, keep its accumulated surfels and keep running.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/ResetAccumulation.h>
#include <relaxed_connectivity/SurfelStats.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace {

using relaxed_connectivity::SurfelStats;

class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh;
    pub_ = nh.advertise<sensor_msgs::PointCloud2>("points", 10);
    stats_sub_ = nh.subscribe<SurfelStats>("surfel_estimator/stats", 50, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      stats_.push_back(*m);
    });
    surfels_sub_ = nh.subscribe<sensor_msgs::PointCloud2>("surfels", 10, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      surfels_.push_back(m);
    });
    diagnostics_sub_ =
        nh.subscribe<diagnostic_msgs::DiagnosticArray>("/diagnostics", 50, [this](const auto& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          for (const auto& status : m->status) {
            seen_names_.insert(status.name);
            if (status.name == "surfel_estimator: input /points") input_status_.push_back(status);
          }
        });
    // The sensor frame: 1 m, 2 m, 3 m from the world origin, not rotated.
    geometry_msgs::TransformStamped tf;
    tf.header.stamp = ros::Time::now();
    tf.header.frame_id = "world";
    tf.child_frame_id = "test_sensor";
    tf.transform.translation.x = 1.0;
    tf.transform.translation.y = 2.0;
    tf.transform.translation.z = 3.0;
    tf.transform.rotation.w = 1.0;
    tf_broadcaster_.sendTransform(tf);

    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(20.0);
    while ((pub_.getNumSubscribers() == 0 || stats_sub_.getNumPublishers() == 0) &&
           ros::WallTime::now() < end) {
      ros::spinOnce();
      ros::WallDuration(0.05).sleep();
    }
    ASSERT_GT(pub_.getNumSubscribers(), 0u) << "surfel_estimator is not running";
    ros::WallDuration(0.5).sleep();  // let the estimator's tf listener receive the static transform
  }

  /// Waits (spinning, up to 5 s) for a /diagnostics status of the estimator's input at `level` whose value
  /// `key` is `value`; returns it (an empty status with a failure after the wait).
  diagnostic_msgs::DiagnosticStatus waitForInputStatus(uint8_t level, const std::string& key,
                                                       const std::string& value) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(5.0);
    while (ros::WallTime::now() < end) {
      ros::spinOnce();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (auto it = input_status_.rbegin(); it != input_status_.rend(); ++it)
          if (it->level == level && BadInput::value(*it, key) == value) {
            const diagnostic_msgs::DiagnosticStatus found = *it;
            input_status_.clear();
            return found;
          }
      }
      ros::WallDuration(0.02).sleep();
    }
    std::string names = " (" + std::to_string(diagnostics_sub_.getNumPublishers()) + " publishers)";
    for (const std::string& name : seen_names_) names += " '" + name + "'";
    ADD_FAILURE() << "no input status at level " << int(level)
                  << " on /diagnostics within 5 s; seen:" << names;
    return {};
  }
  static std::string value(const diagnostic_msgs::DiagnosticStatus& status, const std::string& key) {
    for (const auto& kv : status.values)
      if (kv.key == key) return kv.value;
    return "(missing)";
  }

  /// Publishes `msg` and waits for the stats message it causes.
  SurfelStats send(const sensor_msgs::PointCloud2& msg) {
    size_t before;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      before = stats_.size();
    }
    pub_.publish(msg);
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(10.0);
    while (ros::WallTime::now() < end) {
      ros::spinOnce();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (stats_.size() > before) return stats_.back();
      }
      ros::WallDuration(0.01).sleep();
    }
    ADD_FAILURE() << "no stats message after publishing a cloud (node dead?)";
    return SurfelStats();
  }

  /// A 30 x 30 grid with 1 cm spacing on the plane z = 1 m in front of the sensor.
  static sensor_msgs::PointCloud2 planeCloud(const std::string& frame) {
    rc::SurfelCloud c;
    for (int i = 0; i < 30; ++i)
      for (int j = 0; j < 30; ++j) c.positions.emplace_back(0.01 * i - 0.15, 0.01 * j - 0.15, 1.0);
    c.frame_id = frame;
    c.stamp_ns = ros::Time::now().toNSec();
    sensor_msgs::PointCloud2 msg;
    rc::PointCloud2Converter::toMessage(c, msg, rc::PointCloud2Layout::kCompact);
    return msg;
  }

  std::mutex mutex_;
  std::vector<SurfelStats> stats_;
  std::vector<sensor_msgs::PointCloud2ConstPtr> surfels_;
  ros::Publisher pub_;
  ros::Subscriber stats_sub_, surfels_sub_, diagnostics_sub_;
  std::vector<diagnostic_msgs::DiagnosticStatus> input_status_;
  std::set<std::string> seen_names_;
  tf2_ros::StaticTransformBroadcaster tf_broadcaster_;
};

TEST_F(BadInput, RejectsWithReasonKeepsStateAndRecovers) {
  // 1. A good cloud: 900 surfels, normals towards the sensor (-z), positions shifted by the sensor pose.
  SurfelStats s = send(planeCloud("test_sensor"));
  EXPECT_EQ(s.input_points, 900u);
  EXPECT_EQ(s.output_surfels, 900u);
  EXPECT_EQ(s.accumulated_surfels, 900u);
  EXPECT_EQ(s.rejected_messages, 0u);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ASSERT_EQ(surfels_.size(), 1u);
    const rc::SurfelCloud out = rc::PointCloud2Converter::fromMessage(*surfels_[0]);
    EXPECT_EQ(out.frame_id, "world");
    ASSERT_EQ(out.size(), 900u);
    for (size_t i = 0; i < out.size(); ++i) {
      EXPECT_NEAR(out.positions[i].z(), 4.0, 1e-6);
      EXPECT_NEAR(out.normals[i].z(), -1.0, 1e-5);  // exact plane: normal exactly towards the sensor
      EXPECT_GT(out.radii[i], 0.005);               // covering 1 cm spacing needs at least half the spacing
      EXPECT_LE(out.radii[i], 0.05);                // (the grid's corners get the largest discs)
    }
    std::vector<double> radii = out.radii;
    std::nth_element(radii.begin(), radii.begin() + radii.size() / 2, radii.end());
    EXPECT_GE(radii[radii.size() / 2], 0.00707 - 1e-6);  // a square grid is covered from spacing / sqrt(2)
    EXPECT_LT(radii[radii.size() / 2], 0.02);
    EXPECT_NEAR(out.positions[0].x(), 1.0 - 0.15, 1e-6);
    EXPECT_NEAR(out.positions[0].y(), 2.0 - 0.15, 1e-6);
  }

  // 2. NaN-only cloud.
  sensor_msgs::PointCloud2 nan_cloud = planeCloud("test_sensor");
  for (size_t i = 0; i + 4 <= nan_cloud.data.size(); i += 4) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(&nan_cloud.data[i], &nan, 4);
  }
  s = send(nan_cloud);
  EXPECT_EQ(s.rejected_messages, 1u);
  EXPECT_NE(s.last_error.find("no finite points"), std::string::npos) << s.last_error;
  EXPECT_EQ(s.valid_points, 0u);
  EXPECT_EQ(s.output_surfels, 0u);
  EXPECT_EQ(s.accumulated_surfels, 900u) << "accumulated state lost";

  // 3. Empty cloud (valid layout, no points).
  sensor_msgs::PointCloud2 empty = planeCloud("test_sensor");
  empty.width = 0;
  empty.row_step = 0;
  empty.data.clear();
  s = send(empty);
  EXPECT_EQ(s.rejected_messages, 2u);
  EXPECT_NE(s.last_error.find("empty cloud"), std::string::npos) << s.last_error;
  EXPECT_EQ(s.accumulated_surfels, 900u);

  // 4. No z field.
  sensor_msgs::PointCloud2 no_z = planeCloud("test_sensor");
  no_z.fields.erase(no_z.fields.begin() + 2);
  s = send(no_z);
  EXPECT_EQ(s.rejected_messages, 3u);
  EXPECT_NE(s.last_error.find("missing field 'z'"), std::string::npos) << s.last_error;
  EXPECT_EQ(s.accumulated_surfels, 900u);

  // 5. Unknown frame: the cloud waits in the tf message filter (tf_queue_size 2, the .test) for a transform
  // that never comes; two more such clouds push it out, and it is rejected naming its frame (the other two
  // still wait).
  pub_.publish(planeCloud("no_such_frame"));
  pub_.publish(planeCloud("no_such_frame"));
  s = send(planeCloud("no_such_frame"));
  EXPECT_EQ(s.rejected_messages, 4u);
  EXPECT_NE(s.last_error.find("no transform from 'no_such_frame' to 'world'"), std::string::npos)
      << s.last_error;
  EXPECT_EQ(s.accumulated_surfels, 900u);
  // /diagnostics reports the input with a warning naming the last rejection and the counts.
  const diagnostic_msgs::DiagnosticStatus warned =
      waitForInputStatus(diagnostic_msgs::DiagnosticStatus::WARN, "rejected", "4");
  EXPECT_NE(warned.message.find("rejected"), std::string::npos) << warned.message;
  EXPECT_NE(warned.message.find("no transform"), std::string::npos) << warned.message;
  EXPECT_EQ(value(warned, "rejected"), "4");

  // 6. Still alive: a good cloud is processed; the same surfaces fall into the same voxels.
  s = send(planeCloud("test_sensor"));
  EXPECT_EQ(s.output_surfels, 900u);
  EXPECT_EQ(s.rejected_messages, 4u);
  EXPECT_EQ(s.accumulated_surfels, 900u);
  EXPECT_NE(s.last_error.find("no transform"), std::string::npos) << "last_error keeps the last rejection";
  {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_EQ(surfels_.size(), 2u);
  }
  // Without new rejections the input's status is OK again.
  const diagnostic_msgs::DiagnosticStatus ok =
      waitForInputStatus(diagnostic_msgs::DiagnosticStatus::OK, "accepted", "2");
  EXPECT_EQ(value(ok, "accepted"), "2");

  // 7. Reset returns how many were dropped.
  ros::NodeHandle nh;
  ros::ServiceClient reset =
      nh.serviceClient<relaxed_connectivity::ResetAccumulation>("surfel_estimator/reset_accumulation");
  ASSERT_TRUE(reset.waitForExistence(ros::Duration(5.0)));
  relaxed_connectivity::ResetAccumulation srv;
  ASSERT_TRUE(reset.call(srv));
  EXPECT_TRUE(srv.response.success);
  EXPECT_EQ(srv.response.dropped_surfels, 900u);
  ASSERT_TRUE(reset.call(srv));
  EXPECT_EQ(srv.response.dropped_surfels, 0u);
  s = send(planeCloud("test_sensor"));
  EXPECT_EQ(s.accumulated_surfels, 900u);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "surfel_estimator_bad_input_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
