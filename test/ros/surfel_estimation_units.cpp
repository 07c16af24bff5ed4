// The ROS-free helpers behind surfel_estimator and scanner, and their parameter validation.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <cmath>
#include <limits>

#include "relaxed_connectivity/ros/scanner_node.h"
#include "relaxed_connectivity/ros/surfel_estimator.h"
#include "relaxed_connectivity/scan/surfel_accumulator.h"
#include "relaxed_connectivity/scan/surfel_estimation_pipeline.h"

namespace rc {
namespace {

/// n x n grid with `spacing` on the plane z = depth of the sensor frame.
SurfelCloud planeView(int n, double spacing, double depth) {
  SurfelCloud c;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) c.positions.emplace_back(spacing * (i - n / 2), spacing * (j - n / 2), depth);
  return c;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(SurfelEstimationPipeline, PlaneViewBecomesOrientedSurfelsInTheFixedFrame) {
  SurfelCloud view = planeView(20, 0.01, 1.5);
  view.positions[7] = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();  // sensor z -> world -y
  T.translation() = Vec3(0.5, 0.0, 1.0);
  SurfelEstimationStats stats;
  const SurfelCloud s = estimateSurfels(view, T, "world", SurfelEstimationConfig(), &stats);
  EXPECT_EQ(stats.input_points, 400u);
  EXPECT_EQ(stats.valid_points, 399u);
  EXPECT_EQ(stats.output_surfels, 399u);
  ASSERT_EQ(s.size(), 399u);
  EXPECT_EQ(s.frame_id, "world");
  for (size_t i = 0; i < s.size(); ++i) {
    EXPECT_NEAR(s.positions[i].y(), -1.5, 1e-12);   // the plane z = 1.5 m in front of the sensor
    EXPECT_NEAR(s.normals[i].y(), 1.0, 1e-9) << i;  // facing the sensor (sensor -z -> world +y)
    EXPECT_GT(s.radii[i], 0.0);
  }
}

TEST(SurfelEstimationPipeline, RejectsEmptyNonFiniteAndTooSmallViews) {
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  const SurfelEstimationConfig config;
  EXPECT_NE(errorOf([&] { estimateSurfels(SurfelCloud(), I, "world", config); }).find("empty cloud"),
            std::string::npos);
  SurfelCloud nan = planeView(5, 0.01, 1.0);
  for (auto& p : nan.positions) p.x() = std::numeric_limits<double>::infinity();
  EXPECT_NE(errorOf([&] { estimateSurfels(nan, I, "world", config); }).find("no finite points (all 25"),
            std::string::npos);
  EXPECT_NE(
      errorOf([&] { estimateSurfels(planeView(3, 0.01, 1.0), I, "world", config); }).find("only 9 finite"),
      std::string::npos);
  Eigen::Isometry3d bad = I;
  bad.translation().x() = std::nan("");
  EXPECT_NE(
      errorOf([&] { estimateSurfels(planeView(5, 0.01, 1.0), bad, "world", config); }).find("not finite"),
      std::string::npos);
}

TEST(SurfelAccumulator, KeepsOneSurfelPerVoxelUpToTheCap) {
  SurfelAccumulator acc(0.01, 1000);
  SurfelCloud view = planeView(10, 0.02, 0.005);  // 100 points, in every other 1 cm voxel, at voxel centres
  for (auto& p : view.positions) p += Vec3(0.005, 0.005, 0.0);
  EXPECT_EQ(acc.add(view), 100u);
  EXPECT_EQ(acc.add(view), 0u) << "the same surfaces must not be added twice";
  SurfelCloud shifted = view;
  for (auto& p : shifted.positions) p.x() += 0.002;  // same voxels
  EXPECT_EQ(acc.add(shifted), 0u);
  for (auto& p : shifted.positions) p.x() += 0.018;  // two voxels on: only the last column is new
  EXPECT_EQ(acc.add(shifted), 10u);
  EXPECT_EQ(acc.size(), 110u);

  SurfelAccumulator small(0.01, 30);
  EXPECT_EQ(small.add(view), 30u);
  EXPECT_TRUE(small.full());
  EXPECT_EQ(small.overflow(), 70u);
  EXPECT_EQ(small.reset(), 30u);
  EXPECT_EQ(small.size(), 0u);
  EXPECT_EQ(small.add(view), 30u);

  EXPECT_NE(errorOf([] { SurfelAccumulator(0.0, 10); }).find("accumulation_voxel"), std::string::npos);
  EXPECT_NE(errorOf([] { SurfelAccumulator(0.01, 0); }).find("max_accumulated_points"), std::string::npos);
}

TEST(Parameters, BadValuesAreRejectedNamingTheParameter) {
  ros::NodeHandle pnh("~");
  EXPECT_EQ(errorOf([&] { readSurfelEstimatorParams(pnh); }), "") << "defaults must be valid";
  pnh.setParam("accumulation_voxel", -0.1);
  EXPECT_NE(errorOf([&] { readSurfelEstimatorParams(pnh); }).find("accumulation_voxel"), std::string::npos);
  pnh.deleteParam("accumulation_voxel");
  pnh.setParam("normal_k", 2);
  EXPECT_NE(errorOf([&] { readSurfelEstimatorParams(pnh); }).find("normal_k"), std::string::npos);
  pnh.deleteParam("normal_k");
  pnh.setParam("mls_smoothing", true);
  pnh.setParam("mls_support_radius", 0.0);
  EXPECT_NE(errorOf([&] { readSurfelEstimatorParams(pnh); }).find("mls_support_radius"), std::string::npos);
  pnh.deleteParam("mls_smoothing");
  pnh.deleteParam("mls_support_radius");

  EXPECT_EQ(errorOf([&] { readScannerParams(pnh); }), "") << "defaults must be valid";
  pnh.setParam("rate", 0.0);
  EXPECT_NE(errorOf([&] { readScannerParams(pnh); }).find("rate"), std::string::npos);
  pnh.deleteParam("rate");
  pnh.setParam("horizontal_fov", 200.0);
  EXPECT_NE(errorOf([&] { readScannerParams(pnh); }).find("horizontal_fov"), std::string::npos);
  pnh.deleteParam("horizontal_fov");
  pnh.setParam("orbit_radius", -1.0);
  EXPECT_NE(errorOf([&] { readScannerParams(pnh); }).find("radius"), std::string::npos);
  pnh.deleteParam("orbit_radius");
  pnh.setParam("frame_id", "world");
  EXPECT_NE(errorOf([&] { readScannerParams(pnh); }).find("must differ"), std::string::npos);
  pnh.deleteParam("frame_id");
}

TEST(ScannerNode, SimulatedFramesAreOrganisedScansOfTheModel) {
  ros::NodeHandle nh("scanner_test"), pnh("~scanner");
  pnh.setParam("model", "icosphere");
  pnh.setParam("rate", 1.0);
  ScannerNode scanner(nh, pnh);
  EXPECT_EQ(scanner.publishFrame(ros::Time::now()), 160u * 120u);  // organised: one point per pixel
  pnh.setParam("model", "no_such_model");
  EXPECT_NE(errorOf([&] { ScannerNode bad(nh, pnh); }).find("no_such_model"), std::string::npos);
  pnh.setParam("model", "icosphere");
  pnh.setParam("files", std::vector<std::string>{"/nonexistent/cloud.ply"});
  EXPECT_NE(errorOf([&] { ScannerNode bad(nh, pnh); }).find("/nonexistent/cloud.ply"), std::string::npos);
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "surfel_estimation_units");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
