// mesh_converter's ~convert action (see mesh_converter_action.test): conversions from a goal's cloud, a file
// and the latest cloud on `surfels`, with stage feedback, files, errors and the latched marker; cancellation
// in each stage; bad goals aborted with a clear message while the node keeps serving.
#include <actionlib/client/simple_action_client.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <relaxed_connectivity/ConvertSurfelsAction.h>
#include <ros/ros.h>
#include <visualization_msgs/Marker.h>

#include <cmath>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "../convert/sphere_surfels.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {
namespace {

using Client = actionlib::SimpleActionClient<relaxed_connectivity::ConvertSurfelsAction>;
using Goal = relaxed_connectivity::ConvertSurfelsGoal;
using State = actionlib::SimpleClientGoalState;

/// A unit sphere of n surfels (Fibonacci spiral) painted red on |z| < 0.15, blue elsewhere.
SurfelCloud paintedSphere(size_t n) {
  SurfelCloud c = fibonacciSphereSurfels(n, 2.5 / std::sqrt(double(n)));
  for (const Vec3& p : c.positions)
    c.colors.push_back(std::abs(p.z()) < 0.15 ? Rgba{230, 30, 30, 255} : Rgba{30, 60, 200, 255});
  return c;
}

sensor_msgs::PointCloud2 toCloud(const SurfelCloud& surfels, const std::string& frame = "world") {
  sensor_msgs::PointCloud2 msg;
  PointCloud2Converter::toMessage(surfels, msg);
  msg.header.frame_id = frame;
  msg.header.stamp = ros::Time::now();
  return msg;
}

class MeshConverterAction : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(client_.waitForServer(ros::Duration(20.0))) << "no mesh_converter/convert action server";
    ASSERT_TRUE(ros::param::get("/mesh_converter/output_dir", output_dir_));
  }
  /// Sends the goal and waits; records the stages seen in feedback, in order.
  State run(const Goal& goal, double seconds = 60) {
    stages_.clear();
    last_progress_ = 0;
    client_.sendGoal(goal, {}, {}, [&](const relaxed_connectivity::ConvertSurfelsFeedbackConstPtr& f) {
      if (stages_.empty() || stages_.back() != f->stage) stages_.push_back(f->stage);
      EXPECT_GE(f->progress, last_progress_ - 1e-6f) << "overall progress went back in " << f->stage;
      last_progress_ = f->progress;
    });
    EXPECT_TRUE(client_.waitForResult(ros::Duration(seconds)));
    return client_.getState();
  }
  Client client_{"mesh_converter/convert", true};
  std::string output_dir_;
  std::vector<std::string> stages_;
  float last_progress_ = 0;
};

TEST_F(MeshConverterAction, AGoalsCloudBecomesFilesWithItsErrorsAndAMarker) {
  visualization_msgs::MarkerConstPtr marker;
  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe<visualization_msgs::Marker>(
      "mesh_converter/converted", 1, [&](const visualization_msgs::MarkerConstPtr& m) { marker = m; });
  Goal goal;
  goal.cloud = toCloud(paintedSphere(8000));
  goal.target_triangles = 1000;
  goal.write_obj = goal.write_glb = true;
  goal.output_prefix = output_dir_ + "/sphere";
  ASSERT_EQ(run(goal), State::SUCCEEDED) << client_.getResult()->message;
  const auto result = client_.getResult();
  EXPECT_TRUE(result->success);
  EXPECT_EQ(result->surfels, 8000u);
  EXPECT_NEAR(double(result->triangles), 1000, 2);
  EXPECT_LT(result->hausdorff, 0.03);
  EXPECT_GT(result->texture_usage_with_borders, 0.3);
  EXPECT_LE(result->color_error_max, 0.03 + 1e-9);  // config/convert.yaml's threshold
  EXPECT_EQ(result->patches_at_resolution_limit, 0u);
  const std::vector<std::string> expected_stages = {
      "reading", "reconstruction", "simplification", "geometric error", "textures", "packing", "writing"};
  EXPECT_EQ(stages_, expected_stages);
  // The final feedback (progress 1) travels on another topic than the result and may come after it, when
  // the client no longer reports feedback: the last one seen is at least the start of "writing".
  EXPECT_GE(last_progress_, 0.9f);
  EXPECT_LE(last_progress_, 1.0f + 1e-6f);
  // OBJ, MTL, colour and normal pages, glb
  EXPECT_EQ(result->files.size(), 2 + 2 * result->texture_pages + 1);
  for (const std::string& f : result->files) EXPECT_TRUE(std::filesystem::exists(f)) << f;
  EXPECT_EQ(result->files.front(), output_dir_ + "/sphere.obj");
  const TriangleMesh mesh = readMesh(output_dir_ + "/sphere.obj");
  EXPECT_EQ(mesh.triangles.size(), size_t(result->triangles));
  // The latched marker: three coloured corners per triangle, red on the stripe, blue away from it.
  for (int i = 0; i < 500 && !marker; ++i) ros::WallDuration(0.01).sleep();  // (the AsyncSpinner delivers it)
  ASSERT_TRUE(marker != nullptr);
  EXPECT_EQ(marker->type, visualization_msgs::Marker::TRIANGLE_LIST);
  EXPECT_EQ(marker->header.frame_id, "world");
  ASSERT_EQ(marker->points.size(), 3 * size_t(result->triangles));
  ASSERT_EQ(marker->colors.size(), marker->points.size());
  size_t red = 0, blue = 0;
  for (size_t i = 0; i < marker->points.size(); ++i) {
    const double z = std::abs(marker->points[i].z);
    if (z < 0.1) red += marker->colors[i].r > 0.7 && marker->colors[i].b < 0.3;
    if (z > 0.2) blue += marker->colors[i].b > 0.6 && marker->colors[i].r < 0.3;
  }
  EXPECT_GT(red, 100u);
  EXPECT_GT(blue, 1000u);
}

TEST_F(MeshConverterAction, FilesAndTheLatestCloudConvertToo) {
  // A file (normals present), only glb asked for.
  const std::string ply = output_dir_ + "/input_sphere.ply";
  std::filesystem::create_directories(output_dir_);
  writeCloud(ply, paintedSphere(4000));
  Goal goal;
  goal.input_file = ply;
  goal.target_triangles = 400;
  goal.write_glb = true;
  goal.output_prefix = output_dir_ + "/from_file";
  ASSERT_EQ(run(goal), State::SUCCEEDED) << client_.getResult()->message;
  ASSERT_EQ(client_.getResult()->files.size(), 1u);
  EXPECT_EQ(client_.getResult()->files[0], output_dir_ + "/from_file.glb");
  EXPECT_GT(std::filesystem::file_size(output_dir_ + "/from_file.glb"), 1000u);
  // The latest cloud on `surfels` (as the painting session hands over its painted object), default files.
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("surfels", 1, true);
  pub.publish(toCloud(paintedSphere(4000), "painted_object"));
  ros::WallDuration(1.0).sleep();
  Goal latest;
  latest.use_latest = true;
  latest.target_triangles = 400;
  ASSERT_EQ(run(latest), State::SUCCEEDED) << client_.getResult()->message;
  const auto result = client_.getResult();
  EXPECT_EQ(result->surfels, 4000u);
  ASSERT_FALSE(result->files.empty());
  EXPECT_EQ(result->files.front().rfind(output_dir_ + "/painted_object_", 0), 0u) << result->files.front();
}

TEST_F(MeshConverterAction, CancellingPreemptsEveryStage) {
  const sensor_msgs::PointCloud2 cloud = toCloud(paintedSphere(30000));
  for (const std::string stage : {"reconstruction", "simplification", "textures"}) {
    Goal goal;
    goal.cloud = cloud;
    goal.target_triangles = 3000;
    goal.color_error = 0.005;
    goal.output_prefix = output_dir_ + "/cancelled";
    bool cancelled = false;
    client_.sendGoal(goal, {}, {}, [&](const relaxed_connectivity::ConvertSurfelsFeedbackConstPtr& f) {
      if (!cancelled && f->stage == stage) {
        client_.cancelGoal();
        cancelled = true;
      }
    });
    ASSERT_TRUE(client_.waitForResult(ros::Duration(60.0))) << stage;
    EXPECT_TRUE(cancelled) << stage;
    EXPECT_EQ(client_.getState(), State::PREEMPTED) << stage;
    EXPECT_NE(client_.getResult()->message.find("cancelled during " + stage), std::string::npos)
        << client_.getResult()->message;
  }
  EXPECT_FALSE(std::filesystem::exists(output_dir_ + "/cancelled.obj"));
}

TEST_F(MeshConverterAction, BadGoalsAreAbortedClearlyAndTheNodeKeepsServing) {
  auto expectAborted = [&](const Goal& goal, const std::string& words) {
    EXPECT_EQ(run(goal), State::ABORTED) << words;
    EXPECT_FALSE(client_.getResult()->success);
    EXPECT_NE(client_.getResult()->message.find(words), std::string::npos) << client_.getResult()->message;
  };
  // /diagnostics counts the aborted goals ("mesh_converter: conversion").
  std::mutex diagnostics_mutex;
  int aborted_goals = -1;
  ros::NodeHandle nh;
  ros::Subscriber diagnostics = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
        for (const auto& status : m->status)
          for (const auto& kv : status.values)
            if (status.name == "mesh_converter: conversion" && kv.key == "goals aborted") {
              std::lock_guard<std::mutex> lock(diagnostics_mutex);
              aborted_goals = std::stoi(kv.value);
            }
      });
  auto abortedGoals = [&](int at_least) {  // waits up to 5 s for the count to reach at_least
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(5.0);
    for (;;) {
      {
        std::lock_guard<std::mutex> lock(diagnostics_mutex);
        if (aborted_goals >= at_least || ros::WallTime::now() > end) return aborted_goals;
      }
      ros::WallDuration(0.02).sleep();
    }
  };
  const int aborted_before = abortedGoals(0);
  ASSERT_GE(aborted_before, 0) << "no conversion status on /diagnostics";
  SurfelCloud no_normals = paintedSphere(1000);
  no_normals.normals.clear();
  Goal goal;
  goal.cloud = toCloud(no_normals);
  expectAborted(goal, "normal");
  SurfelCloud nan = paintedSphere(1000);
  nan.positions[7].x() = std::nan("");
  goal.cloud = toCloud(nan);
  expectAborted(goal, "non-finite");
  expectAborted(Goal(), "names no cloud");
  Goal missing;
  missing.input_file = "/nonexistent/cloud.ply";
  expectAborted(missing, "/nonexistent/cloud.ply");
  Goal negative;
  negative.cloud = toCloud(paintedSphere(1000));
  negative.color_error = -1;
  expectAborted(negative, "error parameters");
  EXPECT_EQ(abortedGoals(aborted_before + 5), aborted_before + 5);
  // Still serving.
  Goal good;
  good.cloud = toCloud(paintedSphere(2000));
  good.target_triangles = 200;
  good.output_prefix = output_dir_ + "/after_errors";
  EXPECT_EQ(run(good), State::SUCCEEDED) << client_.getResult()->message;
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "mesh_converter_action_test");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
