// Plays test/ros/data/scan_small.bag through surfel_estimator (see surfel_estimator_bag.test) and checks
// every output: pcl::PointSurfel layout, frame, counts, unit normals facing outwards on the star-shaped blob,
// positive radii, one output per input (so the output rate equals the bag rate), and the stats messages.
#include <gtest/gtest.h>
#include <relaxed_connectivity/SurfelStats.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <set>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace {

struct Received {
  std::mutex mutex;
  std::vector<sensor_msgs::PointCloud2ConstPtr> inputs, surfels, accumulated;
  std::vector<double> input_arrivals, surfel_arrivals;
  std::vector<relaxed_connectivity::SurfelStats> stats;
};

class SurfelEstimatorBag : public ::testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh, pnh("~");
    pnh.param("expected_frames", expected_frames_, expected_frames_);
    input_sub_ = nh.subscribe<sensor_msgs::PointCloud2>("points", 20, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(r_.mutex);
      r_.inputs.push_back(m);
      r_.input_arrivals.push_back(ros::WallTime::now().toSec());
    });
    surfel_sub_ = nh.subscribe<sensor_msgs::PointCloud2>("surfels", 20, [this](const auto& m) {
      std::lock_guard<std::mutex> lock(r_.mutex);
      r_.surfels.push_back(m);
      r_.surfel_arrivals.push_back(ros::WallTime::now().toSec());
    });
    accumulated_sub_ =
        nh.subscribe<sensor_msgs::PointCloud2>("surfels_accumulated", 20, [this](const auto& m) {
          std::lock_guard<std::mutex> lock(r_.mutex);
          r_.accumulated.push_back(m);
        });
    stats_sub_ =
        nh.subscribe<relaxed_connectivity::SurfelStats>("surfel_estimator/stats", 20, [this](const auto& m) {
          std::lock_guard<std::mutex> lock(r_.mutex);
          r_.stats.push_back(*m);
        });
  }

  /// Spins until the bag has been played and every input has its stats (or the time runs out).
  void waitForBag(double timeout) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::ok() && ros::WallTime::now() < end) {
      ros::spinOnce();
      {
        std::lock_guard<std::mutex> lock(r_.mutex);
        const bool quiet =
            !r_.input_arrivals.empty() && ros::WallTime::now().toSec() - r_.input_arrivals.back() > 2.0;
        if (quiet && r_.stats.size() >= r_.inputs.size() && int(r_.inputs.size()) >= expected_frames_) break;
      }
      ros::WallDuration(0.02).sleep();
    }
  }

  int expected_frames_ = 8;
  Received r_;
  ros::Subscriber input_sub_, surfel_sub_, accumulated_sub_, stats_sub_;
};

TEST_F(SurfelEstimatorBag, EveryViewBecomesValidSurfelsInWorld) {
  waitForBag(60.0);
  std::lock_guard<std::mutex> lock(r_.mutex);
  ASSERT_EQ(int(r_.inputs.size()), expected_frames_) << "the bag was not played completely";
  ASSERT_EQ(r_.surfels.size(), r_.inputs.size()) << "surfel_estimator dropped or rejected views";
  ASSERT_EQ(r_.stats.size(), r_.inputs.size());

  std::set<uint64_t> input_stamps;
  for (const auto& m : r_.inputs) input_stamps.insert(m->header.stamp.toNSec());
  const std::vector<std::string> names = {"x",        "y",    "z",      "normal_x",   "normal_y",
                                          "normal_z", "rgba", "radius", "confidence", "curvature"};
  const std::vector<uint32_t> offsets = {0, 4, 8, 16, 20, 24, 32, 36, 40, 44};

  for (const auto& msg : r_.surfels) {
    EXPECT_EQ(msg->header.frame_id, "world");
    EXPECT_TRUE(input_stamps.count(msg->header.stamp.toNSec())) << "output stamp is not an input stamp";
    ASSERT_GE(msg->fields.size(), names.size());
    for (size_t i = 0; i < names.size(); ++i) {
      EXPECT_EQ(msg->fields[i].name, names[i]);
      EXPECT_EQ(msg->fields[i].offset, offsets[i]) << names[i];
      EXPECT_EQ(msg->fields[i].count, 1u) << names[i];
    }
    EXPECT_EQ(msg->point_step, 48u);
    EXPECT_EQ(msg->height, 1u);
    EXPECT_GT(msg->width, 500u);
    EXPECT_TRUE(msg->is_dense);

    const rc::SurfelCloud c = rc::PointCloud2Converter::fromMessage(*msg);
    ASSERT_TRUE(c.hasNormals() && c.hasRadii());
    size_t outward = 0;
    for (size_t i = 0; i < c.size(); ++i) {
      ASSERT_TRUE(c.positions[i].allFinite());
      ASSERT_TRUE(c.normals[i].allFinite());
      EXPECT_NEAR(c.normals[i].norm(), 1.0, 1e-5);
      ASSERT_TRUE(std::isfinite(c.radii[i]));
      EXPECT_GT(c.radii[i], 0.0);
      // The blob is star-shaped around the world origin: outward normals have n . p > 0. Normals were
      // oriented towards the sensor, which sees the outside.
      outward += c.normals[i].dot(c.positions[i]) > 0;
    }
    EXPECT_GT(double(outward) / c.size(), 0.97) << "normals not oriented towards the sensor";
    // Pixel spacing on the blob: 2 * 2.15 m * tan(30 deg) / 160 = 15.5 mm; covering radii are of that order
    // (isolated silhouette points may need larger discs).
    std::vector<double> radii = c.radii;
    std::sort(radii.begin(), radii.end());
    const double median = radii[radii.size() / 2], p95 = radii[radii.size() * 95 / 100];
    EXPECT_GT(median, 0.005);
    EXPECT_LT(median, 0.05);
    EXPECT_LT(p95, 0.1);
    std::printf("view: %zu surfels, radius median %.4f p95 %.4f max %.4f, outward %.4f\n", c.size(), median,
                p95, radii.back(), double(outward) / c.size());
    // The blob has radius about 0.5 m around the origin.
    for (const auto& p : c.positions) ASSERT_LT(p.norm(), 1.0);
  }

  // Output rate: one output per input, same stamps, so the stamp rate equals the bag's; arrivals keep pace
  // too.
  ASSERT_GE(r_.inputs.size(), 3u);
  const double input_span = r_.input_arrivals.back() - r_.input_arrivals.front();
  const double output_span = r_.surfel_arrivals.back() - r_.surfel_arrivals.front();
  const double input_rate = (r_.inputs.size() - 1) / input_span;
  const double output_rate = (r_.surfels.size() - 1) / output_span;
  EXPECT_NEAR(output_rate, input_rate, 0.3 * input_rate);
  const double bag_rate =
      (r_.inputs.size() - 1) / (r_.inputs.back()->header.stamp - r_.inputs.front()->header.stamp).toSec();
  EXPECT_NEAR(bag_rate, 4.0, 0.4);  // recorded at 4 Hz

  // Stats: one per input, consistent counts, nothing rejected, accumulation grows and stays deduplicated.
  uint32_t previous_accumulated = 0;
  size_t total_output = 0;
  for (const auto& s : r_.stats) {
    EXPECT_EQ(s.input_points, 160u * 120u);
    EXPECT_GT(s.valid_points, 500u);
    EXPECT_LT(s.valid_points, s.input_points);  // the organised scan has background pixels
    EXPECT_EQ(s.output_surfels, s.valid_points);
    EXPECT_GE(s.accumulated_surfels, previous_accumulated);
    EXPECT_EQ(s.rejected_messages, 0u);
    EXPECT_EQ(s.last_error, "");
    EXPECT_GT(s.processing_time, 0.0);
    previous_accumulated = s.accumulated_surfels;
    total_output += s.output_surfels;
  }
  EXPECT_GT(previous_accumulated, r_.stats.front().output_surfels);
  EXPECT_LE(previous_accumulated, total_output);  // overlapping views share voxels

  ASSERT_FALSE(r_.accumulated.empty());
  const auto& acc = r_.accumulated.back();
  EXPECT_EQ(acc->header.frame_id, "world");
  EXPECT_EQ(acc->point_step, 48u);
  EXPECT_GT(acc->width, 0u);
  EXPECT_LE(acc->width, previous_accumulated);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "surfel_estimator_bag_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
