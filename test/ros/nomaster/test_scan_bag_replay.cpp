// The recorded scan (test/ros/data/scan_small.bag) read through the rosbag C++ API, with no ROS master: every
// view's PointCloud2 converted (PointCloud2Converter), its sensor pose from the recorded /tf at its stamp
// (tf2::BufferCore), and the surfel pipeline the surfel_estimator node runs (estimateSurfels, then the voxel
// accumulation). Deterministic: a second pass gives bitwise the same accumulated surfels.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2/buffer_core.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"
#include "relaxed_connectivity/scan/surfel_accumulator.h"
#include "relaxed_connectivity/scan/surfel_estimation_pipeline.h"

namespace rc {
namespace {

struct Replay {
  size_t views = 0;
  std::vector<size_t> view_surfels;
  double worst_normal_facing = 1.0;  // min over surfels of n . (sensor - p) / |sensor - p|
  SurfelCloud accumulated;
};

Replay replay(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  tf2::BufferCore buffer(ros::Duration(60.0));
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(std::string("/tf"))))
    if (const auto tf = m.instantiate<tf2_msgs::TFMessage>())
      for (const geometry_msgs::TransformStamped& t : tf->transforms) buffer.setTransform(t, "bag");
  Replay out;
  SurfelAccumulator accumulator(0.005, 1000000);
  const SurfelEstimationConfig config;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(std::string("/points")))) {
    const auto msg = m.instantiate<sensor_msgs::PointCloud2>();
    if (!msg) continue;
    ++out.views;
    SurfelCloud view;
    PointCloud2Converter::fromMessage(*msg, view);
    const Eigen::Isometry3d sensor_to_world =
        tf2::transformToEigen(buffer.lookupTransform("world", msg->header.frame_id, msg->header.stamp));
    const SurfelCloud surfels = estimateSurfels(std::move(view), sensor_to_world, "world", config);
    out.view_surfels.push_back(surfels.size());
    const Vec3 sensor = sensor_to_world.translation();
    for (size_t i = 0; i < surfels.size(); ++i) {
      const Vec3 to_sensor = (sensor - surfels.positions[i]).normalized();
      out.worst_normal_facing = std::min(out.worst_normal_facing, surfels.normals[i].dot(to_sensor));
    }
    accumulator.add(surfels);
  }
  out.accumulated = accumulator.cloud();
  return out;
}

TEST(ScanBagReplay, RecordedViewsBecomeSurfelsWithoutAMaster) {
  const std::string path = std::string(RC_SOURCE_DIR) + "/test/ros/data/scan_small.bag";
  const Replay first = replay(path);
  EXPECT_EQ(first.views, 8u);
  ASSERT_EQ(first.view_surfels.size(), 8u);
  for (size_t n : first.view_surfels) EXPECT_GT(n, 1000u);
  EXPECT_GT(first.worst_normal_facing, 0.0);  // every normal faces its sensor
  EXPECT_GT(first.accumulated.size(), first.view_surfels[0]);
  // Deterministic: the same surfels, bit for bit.
  const Replay second = replay(path);
  ASSERT_EQ(second.accumulated.size(), first.accumulated.size());
  EXPECT_EQ(std::memcmp(second.accumulated.positions.data(), first.accumulated.positions.data(),
                        first.accumulated.size() * sizeof(Vec3)),
            0);
  EXPECT_EQ(std::memcmp(second.accumulated.normals.data(), first.accumulated.normals.data(),
                        first.accumulated.size() * sizeof(Vec3)),
            0);
  std::printf("scan_small.bag: 8 views, %zu to %zu surfels each, %zu accumulated\n",
              *std::min_element(first.view_surfels.begin(), first.view_surfels.end()),
              *std::max_element(first.view_surfels.begin(), first.view_surfels.end()),
              first.accumulated.size());
}

}  // namespace
}  // namespace rc
