// launch/sph_demo.launch (gui:=false, 2D dam break): sph_sim publishes the scene's particles with their
// fields and a closed fluid surface, runs, pauses, steps exactly, resets to t = 0, rejects a bad scene file
// while it keeps its scene, and loads another scene; the rviz config shows topics the node publishes.
#include <gtest/gtest.h>
#include <relaxed_connectivity/LoadSphScene.h>
#include <relaxed_connectivity/SimulationCommand.h>
#include <relaxed_connectivity/SphProbes.h>
#include <relaxed_connectivity/SphStats.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <unistd.h>
#include <visualization_msgs/Marker.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <mutex>
#include <set>
#include <string>

#include "launch_test_support.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"

namespace {

using rc::expectRvizTopicsPublished;
using rc::waitFor;

using relaxed_connectivity::LoadSphScene;
using relaxed_connectivity::SimulationCommand;
using relaxed_connectivity::SphStats;

struct Inbox {
  std::mutex mutex;
  sensor_msgs::PointCloud2ConstPtr particles;
  visualization_msgs::MarkerConstPtr surface;
  std::vector<SphStats> stats;

  SphStats lastStats() {
    std::lock_guard<std::mutex> lock(mutex);
    return stats.empty() ? SphStats() : stats.back();
  }
};

/// Spins until `done` or the timeout.
/// The first stats message (in arrival order) that satisfies `accept`; it and every message before it are
/// consumed. An empty message if none arrives within 10 s.
template <class Accept>
SphStats waitForStats(Inbox& inbox, Accept&& accept) {
  SphStats found;
  waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        for (size_t k = 0; k < inbox.stats.size(); ++k)
          if (accept(inbox.stats[k])) {
            found = inbox.stats[k];
            inbox.stats.erase(inbox.stats.begin(), inbox.stats.begin() + long(k) + 1);
            return true;
          }
        inbox.stats.clear();
        return false;
      },
      10.0);
  return found;
}

TEST(SphDemoLaunch, ParticlesSurfaceAndServices) {
  const std::string dir = std::string(RC_SOURCE_DIR) + "/config/sph/";
  const rc::SphScene scene = rc::loadSphScene(dir + "dam_break_2d.yaml");
  ros::NodeHandle nh;
  Inbox inbox;
  auto particles_sub = nh.subscribe<sensor_msgs::PointCloud2>("sph_sim/particles", 2,
                                                              [&](const sensor_msgs::PointCloud2ConstPtr& m) {
                                                                std::lock_guard<std::mutex> lock(inbox.mutex);
                                                                inbox.particles = m;
                                                              });
  auto surface_sub = nh.subscribe<visualization_msgs::Marker>(
      "sph_sim/surface", 2, [&](const visualization_msgs::MarkerConstPtr& m) {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        inbox.surface = m;
      });
  auto stats_sub =
      nh.subscribe<SphStats>("sph_sim/stats", 100, [&](const relaxed_connectivity::SphStatsConstPtr& m) {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        inbox.stats.push_back(*m);
      });

  // Particles with the scene's count and fields, a surface, and a running simulation.
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        return inbox.particles && inbox.surface && inbox.stats.size() > 3;
      },
      60.0));
  {
    std::lock_guard<std::mutex> lock(inbox.mutex);
    EXPECT_EQ(inbox.particles->width * inbox.particles->height, scene.particles.size());
    EXPECT_EQ(inbox.particles->header.frame_id, "world");
    std::set<std::string> fields;
    for (const auto& field : inbox.particles->fields) fields.insert(field.name);
    for (const char* name : {"x", "y", "z", "velocity", "density", "pressure", "kind"})
      EXPECT_EQ(fields.count(name), 1u) << name;
    EXPECT_EQ(inbox.surface->type, visualization_msgs::Marker::TRIANGLE_LIST);
    EXPECT_GT(inbox.surface->points.size(), 30u);
    EXPECT_EQ(inbox.surface->points.size() % 3, 0u);
  }
  EXPECT_TRUE(inbox.lastStats().running);
  EXPECT_GT(inbox.lastStats().time, 0.0);

  ros::ServiceClient command = nh.serviceClient<SimulationCommand>("sph_sim/command");
  ros::ServiceClient load = nh.serviceClient<LoadSphScene>("sph_sim/load_scene");
  ASSERT_TRUE(command.waitForExistence(ros::Duration(10)));
  ASSERT_TRUE(load.waitForExistence(ros::Duration(10)));

  // Pause, then exactly 5 steps.
  SimulationCommand pause;
  pause.request.command = "pause";
  ASSERT_TRUE(command.call(pause));
  EXPECT_TRUE(pause.response.success) << pause.response.message;
  const SphStats paused = waitForStats(inbox, [](const SphStats& m) { return !m.running; });
  EXPECT_FALSE(paused.running);
  EXPECT_EQ(paused.scene, "dam_break_2d");
  SimulationCommand step;
  step.request.command = "step";
  step.request.steps = 5;
  ASSERT_TRUE(command.call(step));
  EXPECT_TRUE(step.response.success) << step.response.message;
  const SphStats stepped =
      waitForStats(inbox, [&](const SphStats& m) { return !m.running && m.step > paused.step; });
  EXPECT_EQ(stepped.step, paused.step + 5);
  EXPECT_GT(stepped.time, paused.time);
  EXPECT_GT(stepped.dt, 0.0);
  EXPECT_FALSE(stepped.dt_limit.empty());
  EXPECT_TRUE(stepped.instability.empty()) << stepped.instability;
  // One frame: at least the scene's frame time further, by at most one step more.
  rc::callCommand(command, "frame", 1);
  const SphStats framed =
      waitForStats(inbox, [&](const SphStats& m) { return !m.running && m.step > stepped.step; });
  const double frame_time = scene.frame_time;
  EXPECT_GE(framed.time, stepped.time + frame_time - 1e-12);
  EXPECT_LT(framed.time, stepped.time + frame_time + 2.0 * framed.dt);
  // ~save: the particles as PLY (read back); another extension is refused.
  EXPECT_EQ(rc::savedPointCount(nh, "sph_sim/save", ".stl", "supported: .ply .vtp"), framed.particles);

  // Reset to t = 0; unknown commands are refused.
  SimulationCommand reset;
  reset.request.command = "reset";
  ASSERT_TRUE(command.call(reset));
  EXPECT_TRUE(reset.response.success);
  const SphStats after_reset = waitForStats(inbox, [](const SphStats& m) { return m.step == 0; });
  EXPECT_EQ(after_reset.step, 0u);
  EXPECT_EQ(after_reset.time, 0.0);
  SimulationCommand unknown;
  unknown.request.command = "fly";
  ASSERT_TRUE(command.call(unknown));
  EXPECT_FALSE(unknown.response.success);
  EXPECT_NE(unknown.response.message.find("fly"), std::string::npos);

  // A bad scene file is reported with its line and the node keeps its scene.
  const std::string bad = "/tmp/sph_demo_launch_bad.yaml";
  {
    std::ofstream out(bad);
    out << "dimension: 2\nspacing: -1\n";
  }
  LoadSphScene load_bad;
  load_bad.request.path = bad;
  ASSERT_TRUE(load.call(load_bad));
  EXPECT_FALSE(load_bad.response.success);
  EXPECT_NE(load_bad.response.message.find("sph_demo_launch_bad.yaml:"), std::string::npos)
      << load_bad.response.message;
  EXPECT_EQ(load_bad.response.particles, scene.particles.size());
  std::remove(bad.c_str());

  // Another scene: the particle count follows.
  const rc::SphScene tank = rc::loadSphScene(dir + "hydrostatic_tank_2d.yaml");
  LoadSphScene load_tank;
  load_tank.request.path = dir + "hydrostatic_tank_2d.yaml";
  load_tank.request.start = false;
  ASSERT_TRUE(load.call(load_tank));
  EXPECT_TRUE(load_tank.response.success) << load_tank.response.message;
  EXPECT_EQ(load_tank.response.particles, tank.particles.size());
  const SphStats loaded = waitForStats(inbox, [](const SphStats& m) { return m.scene != "dam_break_2d"; });
  EXPECT_EQ(loaded.particles, tank.particles.size());
  EXPECT_FALSE(loaded.running);
}

/// Loads a scene paused and asks for `steps` steps (both services must succeed).
void loadPausedAndStep(ros::ServiceClient& load, ros::ServiceClient& command, const std::string& path,
                       uint32_t steps) {
  LoadSphScene request;
  request.request.path = path;
  request.request.start = false;
  ASSERT_TRUE(load.call(request));
  ASSERT_TRUE(request.response.success) << request.response.message;
  SimulationCommand step;
  step.request.command = "step";
  step.request.steps = steps;
  ASSERT_TRUE(command.call(step));
  ASSERT_TRUE(step.response.success) << step.response.message;
}

// A scene with temperature (Fig. 8.5 in 2D): each step runs heat conduction and freezing as rc_sph does;
// the particles carry temperature and phase, and the stats count the frozen particles (16 of 64 after 480
// steps in rc_sph).
TEST(SphDemoLaunch, TemperatureScenesFreezeAndPublishTemperatureAndPhase) {
  ros::NodeHandle nh;
  Inbox inbox;
  ros::Subscriber particles_sub = nh.subscribe<sensor_msgs::PointCloud2>(
      "sph_sim/particles", 1, [&](const sensor_msgs::PointCloud2ConstPtr& m) {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        inbox.particles = m;
      });
  ros::Subscriber stats_sub =
      nh.subscribe<SphStats>("sph_sim/stats", 100, [&](const relaxed_connectivity::SphStatsConstPtr& m) {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        inbox.stats.push_back(*m);
      });
  const std::string dir = std::string(RC_SOURCE_DIR) + "/config/sph/";
  ros::ServiceClient load = nh.serviceClient<LoadSphScene>("sph_sim/load_scene");
  ros::ServiceClient command = nh.serviceClient<SimulationCommand>("sph_sim/command");
  ASSERT_TRUE(load.waitForExistence(ros::Duration(30.0)));
  // A paused node publishes only after a command: connect first.
  ASSERT_TRUE(waitFor(
      [&] { return particles_sub.getNumPublishers() > 0 && stats_sub.getNumPublishers() > 0; }, 30.0));
  ASSERT_NO_FATAL_FAILURE(loadPausedAndStep(load, command, dir + "freezing_rod_2d.yaml", 480));
  const SphStats stepped =
      waitForStats(inbox, [](const SphStats& m) { return m.scene == "freezing_rod_2d" && m.step == 480; });
  EXPECT_EQ(stepped.step, 480u);
  EXPECT_GT(stepped.frozen, 5u);
  EXPECT_LE(stepped.frozen, 64u);
  EXPECT_EQ(stepped.melted, 0u);
  EXPECT_TRUE(stepped.instability.empty()) << stepped.instability;
  sensor_msgs::PointCloud2ConstPtr cloud;
  waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(inbox.mutex);
        if (inbox.particles && inbox.particles->width * inbox.particles->height == 100u)
          for (const auto& field : inbox.particles->fields)
            if (field.name == "phase") cloud = inbox.particles;
        return cloud != nullptr;
      },
      10.0);
  ASSERT_TRUE(cloud) << "no particles with a phase field";
  // Count the particles of phase 1 (the rod's 36 seeds plus the frozen ones) and the temperature range.
  int phase_offset = -1, temperature_offset = -1;
  for (const auto& field : cloud->fields) {
    if (field.name == "phase") {
      phase_offset = int(field.offset);
      EXPECT_EQ(field.datatype, sensor_msgs::PointField::UINT8);
    }
    if (field.name == "temperature") {
      temperature_offset = int(field.offset);
      EXPECT_EQ(field.datatype, sensor_msgs::PointField::FLOAT32);
    }
  }
  ASSERT_GE(temperature_offset, 0);
  size_t solid = 0;
  float coldest = 1e9f, warmest = -1e9f;
  for (size_t i = 0; i < cloud->width * cloud->height; ++i) {
    const uint8_t* point = &cloud->data[i * cloud->point_step];
    solid += point[phase_offset] == 1;
    float t;
    std::memcpy(&t, point + temperature_offset, sizeof t);
    coldest = std::min(coldest, t);
    warmest = std::max(warmest, t);
  }
  EXPECT_EQ(solid, 36u + stepped.frozen);
  EXPECT_FLOAT_EQ(coldest, -20.0f);  // the held rod
  EXPECT_LE(warmest, 20.0f);
  EXPECT_GT(warmest, 0.0f);
}

// A scene with probes: ~probes carries the liquid's measures and the point samples each frame, as rc_sph's
// CSV does (test_sph_probes.cpp).
TEST(SphDemoLaunch, ScenesWithProbesPublishThem) {
  ros::NodeHandle nh;
  std::mutex mutex;
  std::vector<relaxed_connectivity::SphProbes> received;
  ros::Subscriber probes_sub = nh.subscribe<relaxed_connectivity::SphProbes>(
      "sph_sim/probes", 100, [&](const relaxed_connectivity::SphProbesConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        received.push_back(*m);
      });
  ros::ServiceClient load = nh.serviceClient<LoadSphScene>("sph_sim/load_scene");
  ros::ServiceClient command = nh.serviceClient<SimulationCommand>("sph_sim/command");
  ASSERT_TRUE(load.waitForExistence(ros::Duration(30.0)));
  ASSERT_TRUE(waitFor([&] { return probes_sub.getNumPublishers() > 0; }, 30.0));
  const std::string path = "/tmp/sph_demo_launch_probes.yaml";
  std::ofstream(path) << "name: probed_drop\ndimension: 2\nspacing: 0.05\n"
                         "solver: {smoothing_ratio: 3, gravity: [0, 0]}\n"
                         "fluid:\n  - {shape: sphere, center: [0, 0], radius: 0.5, velocity: [1, 0]}\n"
                         "probes: {points: [[0, 0], [4, 4]]}\nframes: {count: 10, time: 0.002}\n";
  const rc::SphScene scene = rc::loadSphScene(path);
  ASSERT_NO_FATAL_FAILURE(loadPausedAndStep(load, command, path, 5));
  relaxed_connectivity::SphProbes stepped;
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& m : received)
          if (m.scene == "probed_drop" && m.time > 0) stepped = m;
        return stepped.time > 0;
      },
      10.0));
  std::remove(path.c_str());
  EXPECT_EQ(stepped.particles, scene.particles.size());
  EXPECT_GT(stepped.mass, 0.0);
  EXPECT_NEAR(stepped.momentum.x, stepped.mass, 1e-6 * stepped.mass);  // at 1 m/s, no forces on a free drop
  EXPECT_NEAR(stepped.centre.x, stepped.time, 1e-6);
  ASSERT_EQ(stepped.points.size(), 2u);
  ASSERT_EQ(stepped.densities.size(), 2u);
  EXPECT_NEAR(stepped.densities[0], 1000.0, 1.0);
  EXPECT_TRUE(std::isnan(stepped.densities[1]));
  EXPECT_NEAR(stepped.second_moments[0], stepped.second_moments[4], 1e-3);  // a disc
}

// config/rviz/sph_demo.rviz shows topics that sph_sim publishes.
TEST(SphDemoLaunch, RvizConfigShowsPublishedTopics) {
  expectRvizTopicsPublished(std::string(RC_SOURCE_DIR) + "/config/rviz/sph_demo.rviz", 2);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sph_demo_launch_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
