// launch/csg_demo.launch (gui:=false, default dynamic scene): the scene publisher -> csg_renderer pipeline
// delivers colour and depth images of the CSG object, with the scene's tree, and keeps rendering as it moves.
#include <gtest/gtest.h>
#include <relaxed_connectivity/CsgRenderStats.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstring>
#include <mutex>

#include "relaxed_connectivity/render/scene/csg_scene.h"
#include "relaxed_connectivity/ros/surfel_scene_publisher.h"

namespace {

using relaxed_connectivity::CsgRenderStats;
using sensor_msgs::ImageConstPtr;

TEST(CsgDemoLaunch, ImagesOfTheSceneArriveAndMove) {
  const YAML::Node config = YAML::LoadFile(std::string(RC_SOURCE_DIR) + "/config/csg_demo.yaml");
  const uint32_t width = config["csg_renderer"]["width"].as<uint32_t>();
  const uint32_t height = config["csg_renderer"]["height"].as<uint32_t>();
  const rc::CsgScene scene = rc::loadCsgScene(std::string(RC_SOURCE_DIR) + "/config/scenes/orbit.yaml");
  ASSERT_TRUE(scene.isDynamic());
  const std::string expression = rc::patchIdExpression(scene.csgTree());

  ros::NodeHandle nh;
  std::mutex mutex;
  std::vector<ImageConstPtr> images, depths;
  std::vector<CsgRenderStats> stats;
  auto image_sub = nh.subscribe<sensor_msgs::Image>("csg_renderer/image", 10, [&](const ImageConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex);
    images.push_back(m);
  });
  auto depth_sub = nh.subscribe<sensor_msgs::Image>("csg_renderer/depth", 10, [&](const ImageConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex);
    depths.push_back(m);
  });
  auto stats_sub = nh.subscribe<CsgRenderStats>("csg_renderer/stats", 50, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(mutex);
    stats.push_back(*m);
  });

  // Frames rendered with the scene's tree (the first frames may precede the service call).
  auto withSceneTree = [&] {
    size_t n = 0;
    for (const CsgRenderStats& s : stats) n += s.csg == expression;
    return n;
  };
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(60.0);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (withSceneTree() >= 4 && images.size() >= 4 && depths.size() >= 4) break;
    }
    ros::WallDuration(0.02).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_GE(withSceneTree(), 4u) << "csg_renderer did not render the scene's tree \"" << expression << "\"";
  ASSERT_GE(images.size(), 4u);
  ASSERT_GE(depths.size(), 4u);

  const CsgRenderStats& last = stats.back();
  EXPECT_EQ(last.csg, expression);
  EXPECT_EQ(last.patches, scene.patches.size());
  EXPECT_EQ(last.surfels, scene.surfels.size());
  EXPECT_GT(last.clipped_fragments, 0u) << "the ball cuts the box: edge fragments must be clipped";
  EXPECT_EQ(last.rejected_inputs, 0u) << last.last_error;

  for (const ImageConstPtr& im : {images.back(), depths.back()}) {
    EXPECT_EQ(im->header.frame_id, "csg_camera");
    EXPECT_EQ(im->width, width);
    EXPECT_EQ(im->height, height);
    EXPECT_EQ(im->data.size(), size_t(im->step) * height);
  }
  EXPECT_EQ(images.back()->encoding, sensor_msgs::image_encodings::RGB8);
  EXPECT_EQ(depths.back()->encoding, sensor_msgs::image_encodings::TYPE_32FC1);

  // The box fills a good part of the view (seen from about 4.2 m with a 40 degree field of view).
  const sensor_msgs::Image& depth = *depths.back();
  size_t foreground = 0;
  float nearest = INFINITY, farthest = 0;
  for (size_t i = 0; i + 4 <= depth.data.size(); i += 4) {
    float d;
    std::memcpy(&d, &depth.data[i], 4);
    if (!std::isfinite(d)) continue;
    ++foreground;
    nearest = std::min(nearest, d);
    farthest = std::max(farthest, d);
  }
  const double fraction = double(foreground) / (width * height);
  std::printf("[ csg_demo ] %zu frames, foreground fraction %.3f, depth %.3f .. %.3f m, last frame %.1f ms\n",
              stats.size(), fraction, nearest, farthest, 1e3 * (last.prepare_time + last.render_time));
  EXPECT_GT(fraction, 0.05);
  EXPECT_LT(fraction, 0.9);
  const double eye_distance = std::sqrt(2.3 * 2.3 + 2.9 * 2.9 + 1.9 * 1.9);  // the scene camera's eye
  EXPECT_GT(nearest, eye_distance - 1.0);                                    // the box corner nearest the eye
  EXPECT_LT(farthest, eye_distance + 1.0);

  // The ball orbits: successive frames differ.
  size_t differing = 0;
  const sensor_msgs::Image &a = *images[images.size() - 2], &b = *images.back();
  for (size_t i = 0; i + 3 <= a.data.size(); i += 3) differing += std::memcmp(&a.data[i], &b.data[i], 3) != 0;
  EXPECT_GT(differing, 10u);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "csg_demo_launch_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
