// launch/fem_demo.launch (gui:=false, the sliced block of Fig. 9.9): fem_sim publishes the surface marker and
// the node cloud with the simulation's counts, applies the scheduled cuts, pauses, steps exactly, resets to
// the scene's mesh; a polygon given in a rotated tf frame cuts (and separates) exactly as FemSimulation does
// with the transformed polygon, a small polygon only splits; polygons with < 3 points, non-planar or
// non-convex ones and unknown frames are refused with a clear message, change nothing, and the node keeps
// running; the rviz config shows topics the node publishes.
#include <gtest/gtest.h>
#include <relaxed_connectivity/FemCut.h>
#include <relaxed_connectivity/FemStats.h>
#include <relaxed_connectivity/SimulationCommand.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/Marker.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstring>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "launch_test_support.h"
#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/fem/fem_simulation.h"
#include "relaxed_connectivity/ros/fem_simulator.h"

namespace {

using rc::expectRvizTopicsPublished;
using rc::waitFor;

using relaxed_connectivity::FemCut;
using relaxed_connectivity::FemStats;
using relaxed_connectivity::SimulationCommand;

struct Inbox {
  std::mutex mutex;
  sensor_msgs::PointCloud2ConstPtr nodes;
  visualization_msgs::MarkerConstPtr surface;
  FemStats stats;
  int stats_count = 0;
};

/// What the node should publish for a simulation state.
struct Counts {
  size_t bodies = 0, nodes = 0, elements = 0, triangles = 0;
};

Counts countsOf(const rc::FemSimulation& simulation) {
  Counts c;
  c.bodies = size_t(simulation.numBodies());
  c.nodes = size_t(simulation.numNodes());
  c.elements = size_t(simulation.numElements());
  for (int b = 0; b < simulation.numBodies(); ++b)
    c.triangles += simulation.body(b).model().mesh().boundaryTriangles().size();
  return c;
}

/// Waits until the latest stats, node cloud and surface marker all show `expected` (paused).
bool waitForCounts(Inbox& inbox, const Counts& expected) {
  return waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        return inbox.nodes && inbox.surface && !inbox.stats.running &&
               inbox.stats.bodies == expected.bodies && inbox.stats.nodes == expected.nodes &&
               inbox.stats.elements == expected.elements &&
               inbox.stats.surface_triangles == expected.triangles &&
               inbox.nodes->width * inbox.nodes->height == expected.nodes &&
               inbox.surface->points.size() == 3 * expected.triangles &&
               inbox.surface->colors.size() == 3 * expected.triangles;
      },
      10.0);
}

/// Values of the uint32 field `name` of a little-endian cloud.
std::vector<uint32_t> uintField(const sensor_msgs::PointCloud2& cloud, const std::string& name) {
  std::vector<uint32_t> values;
  for (const auto& field : cloud.fields)
    if (field.name == name && field.datatype == sensor_msgs::PointField::UINT32)
      for (size_t i = 0; i < size_t(cloud.width) * cloud.height; ++i) {
        uint32_t value;
        std::memcpy(&value, &cloud.data[i * cloud.point_step + field.offset], sizeof(value));
        values.push_back(value);
      }
  return values;
}

geometry_msgs::Point point(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

TEST(FemDemoLaunch, SurfaceNodesCommandsAndCuts) {
  const rc::FemScene scene =
      rc::loadFemScene(std::string(RC_SOURCE_DIR) + "/config/fem/fig9_9_sliced_block.yaml");
  const Counts initial = countsOf(rc::FemSimulation(scene));
  ASSERT_EQ(initial.nodes, 64u);  // 3 x 3 x 3 hexahedra
  ASSERT_EQ(initial.elements, 27u);
  ASSERT_EQ(initial.triangles, 6u * 9u * 2u);

  ros::NodeHandle nh;
  Inbox inbox;
  auto nodes_sub = nh.subscribe<sensor_msgs::PointCloud2>("fem_sim/nodes", 2,
                                                          [&](const sensor_msgs::PointCloud2ConstPtr& m) {
                                                            std::lock_guard<std::mutex> lock(inbox.mutex);
                                                            inbox.nodes = m;
                                                          });
  auto surface_sub = nh.subscribe<visualization_msgs::Marker>(
      "fem_sim/surface", 2, [&](const visualization_msgs::MarkerConstPtr& m) {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        inbox.surface = m;
      });
  auto stats_sub =
      nh.subscribe<FemStats>("fem_sim/stats", 100, [&](const relaxed_connectivity::FemStatsConstPtr& m) {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        inbox.stats = *m;
        ++inbox.stats_count;
      });

  // Running: the surface and nodes arrive, the first scheduled cut separates a slice off.
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        return inbox.nodes && inbox.surface && inbox.stats.running && inbox.stats.scheduled_cuts >= 1;
      },
      60.0));
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_GE(inbox.stats.bodies, 2u);
    EXPECT_GE(inbox.stats.time, scene.cuts.at(0).time);
    EXPECT_TRUE(inbox.stats.error.empty()) << inbox.stats.error;
    EXPECT_EQ(inbox.nodes->header.frame_id, "world");
    EXPECT_EQ(inbox.surface->header.frame_id, "world");
    EXPECT_EQ(inbox.surface->type, visualization_msgs::Marker::TRIANGLE_LIST);
    std::set<std::string> fields;
    for (const auto& field : inbox.nodes->fields) fields.insert(field.name);
    for (const char* name : {"x", "y", "z", "velocity", "displacement", "body"})
      EXPECT_EQ(fields.count(name), 1u) << name;
  }

  ros::ServiceClient command = nh.serviceClient<SimulationCommand>("fem_sim/command");
  ros::ServiceClient cut = nh.serviceClient<FemCut>("fem_sim/cut");
  ASSERT_TRUE(command.waitForExistence(ros::Duration(10)));
  ASSERT_TRUE(cut.waitForExistence(ros::Duration(10)));
  auto call = [&](const std::string& name, uint32_t steps = 0) {
    return rc::callCommand(command, name, steps);
  };

  // Pause and reset: the scene's mesh at t = 0 in all three outputs.
  call("pause");
  call("reset");
  ASSERT_TRUE(waitForCounts(inbox, initial));
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_EQ(inbox.stats.step, 0u);
    EXPECT_EQ(inbox.stats.time, 0.0);
    EXPECT_EQ(inbox.stats.scheduled_cuts, 0u);
  }

  // Exactly 3 steps.
  call("step", 3);
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        return inbox.stats.step == 3;
      },
      10.0));
  EXPECT_NEAR(inbox.stats.time, 3 * scene.dynamics.time_step, 1e-12);
  SimulationCommand unknown;
  unknown.request.command = "fly";
  ASSERT_TRUE(command.call(unknown));
  EXPECT_FALSE(unknown.response.success);
  EXPECT_NE(unknown.response.message.find("fly"), std::string::npos);

  // A square in the frame `cutter` (rotated 80 degrees about y, at the block's centre): through the whole
  // block, so it splits every crossed element and separates the block into two bodies.
  Eigen::Isometry3d world_T_cutter = Eigen::Isometry3d::Identity();
  world_T_cutter.translate(Eigen::Vector3d(0.5, 0.45, 0.5));
  world_T_cutter.rotate(Eigen::AngleAxisd(80.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()));
  tf2_ros::StaticTransformBroadcaster broadcaster;
  geometry_msgs::TransformStamped tf = tf2::eigenToTransform(world_T_cutter);
  tf.header.frame_id = "world";
  tf.header.stamp = ros::Time::now();
  tf.child_frame_id = "cutter";
  broadcaster.sendTransform(tf);
  ros::WallDuration(0.5).sleep();  // let the node's tf listener receive the static transform

  const std::vector<rc::Vec3> square = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  rc::FemSimulation expected(scene);
  std::vector<rc::Vec3> square_world;
  for (const rc::Vec3& p : square) square_world.push_back(world_T_cutter * p);
  const rc::FemCutReport expected_report = expected.applyCut(rc::femCutFromPolygon(square_world, 1e-6));
  const Counts after_cut = countsOf(expected);
  ASSERT_EQ(expected_report.bodies_separated, 1);
  ASSERT_EQ(after_cut.bodies, 2u);
  ASSERT_GT(after_cut.elements, initial.elements);
  ASSERT_GT(after_cut.nodes, initial.nodes);

  FemCut slice;
  slice.request.header.frame_id = "cutter";
  for (const rc::Vec3& p : square) slice.request.polygon.push_back(point(p.x(), p.y(), p.z()));
  ASSERT_TRUE(cut.call(slice));
  EXPECT_TRUE(slice.response.success) << slice.response.message;
  EXPECT_EQ(slice.response.bodies_cut, 1u);
  EXPECT_EQ(slice.response.bodies_separated, 1u);
  EXPECT_EQ(slice.response.split_elements, uint32_t(expected_report.split_elements));
  EXPECT_EQ(slice.response.new_nodes, uint32_t(expected_report.new_nodes));
  EXPECT_EQ(slice.response.duplicated_nodes, uint32_t(expected_report.duplicated_nodes));
  EXPECT_EQ(slice.response.bodies, after_cut.bodies);
  EXPECT_EQ(slice.response.nodes, after_cut.nodes);
  EXPECT_EQ(slice.response.elements, after_cut.elements);
  ASSERT_TRUE(waitForCounts(inbox, after_cut));
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    const std::vector<uint32_t> body = uintField(*inbox.nodes, "body");
    ASSERT_EQ(body.size(), after_cut.nodes);
    EXPECT_EQ(std::count(body.begin(), body.end(), 0u), expected.body(0).model().mesh().numNodes());
    EXPECT_EQ(std::count(body.begin(), body.end(), 1u), expected.body(1).model().mesh().numNodes());
    EXPECT_EQ(inbox.stats.interactive_cuts, 1u);
  }

  // A small triangle in the plane z = 0.5 (given in `world`) inside the element [2/3, 1]^2 x [1/3, 2/3]: only
  // that element is split, no body is separated.
  const std::vector<rc::Vec3> triangle = {{0.72, 0.72, 0.5}, {0.9, 0.75, 0.5}, {0.8, 0.9, 0.5}};
  const rc::FemCutReport expected_partial = expected.applyCut(rc::femCutFromPolygon(triangle, 1e-6));
  const Counts after_partial = countsOf(expected);
  ASSERT_EQ(expected_partial.bodies_separated, 0);
  ASSERT_EQ(expected_partial.split_elements, 1);
  FemCut partial;
  partial.request.header.frame_id = "world";
  for (const rc::Vec3& p : triangle) partial.request.polygon.push_back(point(p.x(), p.y(), p.z()));
  ASSERT_TRUE(cut.call(partial));
  EXPECT_TRUE(partial.response.success) << partial.response.message;
  EXPECT_EQ(partial.response.bodies_separated, 0u);
  EXPECT_EQ(partial.response.split_elements, uint32_t(expected_partial.split_elements));
  EXPECT_EQ(partial.response.elements, after_partial.elements);
  ASSERT_TRUE(waitForCounts(inbox, after_partial));

  // Refused: the message says why, nothing changes.
  auto refused = [&](FemCut request, const std::string& expected_text) {
    ASSERT_TRUE(cut.call(request));
    EXPECT_FALSE(request.response.success);
    EXPECT_NE(request.response.message.find(expected_text), std::string::npos) << request.response.message;
    EXPECT_EQ(request.response.nodes, after_partial.nodes);
    EXPECT_EQ(request.response.elements, after_partial.elements);
  };
  FemCut two_points;
  two_points.request.header.frame_id = "world";
  two_points.request.polygon = {point(0, 0, 0.5), point(1, 1, 0.5)};
  refused(two_points, "at least 3");
  FemCut bent;
  bent.request.header.frame_id = "world";
  bent.request.polygon = {point(-1, -1, 0.5), point(2, -1, 0.5), point(2, 2, 0.8), point(-1, 2, 0.5)};
  refused(bent, "not planar");
  FemCut arrow;
  arrow.request.header.frame_id = "world";
  arrow.request.polygon = {point(-1, -1, 0.5), point(0.5, 0.2, 0.5), point(2, -1, 0.5), point(0.5, 2, 0.5)};
  refused(arrow, "not convex");
  FemCut unknown_frame = slice;
  unknown_frame.request.header.frame_id = "no_such_frame";
  refused(unknown_frame, "no transform from 'no_such_frame' to 'world'");
  FemCut no_frame = slice;
  no_frame.request.header.frame_id = "";
  refused(no_frame, "frame_id is empty");

  // Reset restores the scene's counts.
  call("reset");
  ASSERT_TRUE(waitForCounts(inbox, initial));
  EXPECT_EQ(inbox.stats.interactive_cuts, 0u);

  // Progressive (9.3.2): a blade quad down to z = 0.5 leaves an internal crack (one body), the next quad down
  // through the ground plane completes the cut (two bodies); both as the core does with the same polygons.
  rc::FemSimulation progressive(scene);
  const std::vector<std::vector<rc::Vec3>> quads = {
      {{0.5, -0.2, 1.1}, {0.5, 1.2, 1.1}, {0.5, 1.2, 0.5}, {0.5, -0.2, 0.5}},
      {{0.5, -0.2, 0.5}, {0.5, 1.2, 0.5}, {0.5, 1.2, -0.1}, {0.5, -0.2, -0.1}}};
  for (size_t q = 0; q < quads.size(); ++q) {
    const rc::FemCutReport report =
        progressive.applyPolygonCuts({rc::femCutFromPolygon(quads[q], 1e-6).region});
    const Counts counts = countsOf(progressive);
    ASSERT_EQ(counts.bodies, q == 0 ? 1u : 2u);
    ASSERT_GT(report.crack_faces, 0);
    FemCut blade;
    blade.request.header.frame_id = "world";
    blade.request.progressive = true;
    for (const rc::Vec3& p : quads[q]) blade.request.polygon.push_back(point(p.x(), p.y(), p.z()));
    ASSERT_TRUE(cut.call(blade));
    EXPECT_TRUE(blade.response.success) << blade.response.message;
    EXPECT_EQ(blade.response.crack_faces, uint32_t(report.crack_faces)) << "quad " << q;
    EXPECT_EQ(blade.response.split_elements, uint32_t(report.split_elements)) << "quad " << q;
    EXPECT_EQ(blade.response.duplicated_nodes, uint32_t(report.duplicated_nodes)) << "quad " << q;
    EXPECT_EQ(blade.response.bodies, counts.bodies);
    EXPECT_EQ(blade.response.nodes, counts.nodes);
    EXPECT_EQ(blade.response.elements, counts.elements);
    ASSERT_TRUE(waitForCounts(inbox, counts)) << "quad " << q;
  }

  // Still running: reset, start.
  call("reset");
  ASSERT_TRUE(waitForCounts(inbox, initial));
  call("start");
  const int seen = inbox.stats_count;
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        return inbox.stats.running && inbox.stats_count > seen + 3 && inbox.stats.time > 0.0;
      },
      10.0));
}

// The polygon's plane: Newell normal, centroid, a closing copy of the first point dropped.
TEST(FemDemoLaunch, CutFromPolygon) {
  const rc::FemSceneCut cut =
      rc::femCutFromPolygon({{0, 0, 1}, {2, 0, 1}, {2, 2, 1}, {0, 2, 1}, {0, 0, 1}}, 1e-6);
  EXPECT_NEAR(cut.point.x(), 1.0, 1e-15);
  EXPECT_NEAR(cut.point.y(), 1.0, 1e-15);
  EXPECT_NEAR(cut.point.z(), 1.0, 1e-15);
  EXPECT_NEAR(std::abs(cut.normal.z()), 1.0, 1e-15);
  EXPECT_EQ(cut.region.size(), 4u);
  EXPECT_THROW(rc::femCutFromPolygon({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}, 1e-6), std::invalid_argument);
}

// config/rviz/fem_demo.rviz shows topics that fem_sim publishes.
TEST(FemDemoLaunch, RvizConfigShowsPublishedTopics) {
  expectRvizTopicsPublished(std::string(RC_SOURCE_DIR) + "/config/rviz/fem_demo.rviz", 2);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "fem_demo_launch_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
