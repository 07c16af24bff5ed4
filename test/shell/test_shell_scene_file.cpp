// Thin-shell scene files (config/shell/*.yaml): every shipped scene loads with the expected counts, bad
// files give errors naming file and line, short runs of each scene stay finite, the poster tears and the
// balloon grows.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/shell/shell_scene_reader.h"
#include "relaxed_connectivity/shell/shell_scene_run.h"

using namespace rc;

namespace {

std::string configDir() {
  // The checkout lives beside shared/ (RC_SHARED_DATA_DIR = <root>/shared/data); fall back to this file's
  // tree.
  const std::filesystem::path here =
      std::filesystem::path(__FILE__).parent_path().parent_path().parent_path();
  return (here / "config" / "shell").string();
}

std::string scenePath(const std::string& name) {
  return configDir() + "/" + name + ".yaml";
}

bool dataPresent() {
  return std::filesystem::exists(std::string(RC_SHARED_DATA_DIR) + "/face_mask.off") &&
         std::filesystem::exists(std::string(RC_SHARED_DATA_DIR) + "/maxplanck_bust.off");
}

/// The shipped scene with some keys replaced (a cheaper configuration of the same scene).
ShellScene cheapScene(const std::string& name, const std::function<void(YAML::Node&)>& edit) {
  YAML::Node root = YAML::LoadFile(scenePath(name));
  edit(root);
  root["output"]["every"] = 0;
  std::stringstream text;
  text << root;
  return parseShellScene(text.str(), scenePath(name));
}

std::string errorOf(const std::string& yaml) {
  try {
    parseShellScene(yaml, "bad.yaml");
  } catch (const ShellSceneError& e) {
    return e.what();
  }
  return "";
}

const char* kMinimal =
    "source:\n"
    "  sheet: {size: [4, 4], spacing: 0.1}\n"
    "nodes: {spacing: 0.5}\n"
    "material: {stretch_stiffness: 100, bending_stiffness: 10}\n"
    "dynamics: {time_step: auto}\n"
    "frames: {count: 2, steps_per_frame: 3}\n";

}  // namespace

TEST(ShellSceneFile, EveryShippedSceneLoadsWithTheExpectedCounts) {
  if (!dataPresent()) GTEST_SKIP() << "needs ../shared/data: face_mask.off and maxplanck_bust.off";
  struct Expected {
    size_t surfels, nodes;
    bool plasticity, fracture, balloon, weak;
    size_t pins;
  };
  const std::map<std::string, Expected> expected = {
      {"fig7_4_mask", {40880, 1987, false, false, false, false, 0}},
      {"fig7_5_bust", {9835, 931, true, false, false, false, 0}},
      {"fig7_8_poster", {240000, 11860, false, true, false, true, 2}},
      {"fig7_10_balloon", {24578, 1170, false, true, true, true, 0}},
      {"cantilever_static",
       {2000, 0, false, false, false, false, 0}},  // test_shell_scene_analysis runs these
      {"cantilever_modal", {2000, 0, false, false, false, false, 0}},
      {"hanging_sheet_probes",
       {2500, 0, false, false, false, false, 1}},  // test_shell_probes, shell_probes.test
  };
  size_t seen = 0;
  for (const auto& entry : std::filesystem::directory_iterator(configDir())) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string name = entry.path().stem().string();
    SCOPED_TRACE(name);
    const ShellScene scene = loadShellScene(entry.path().string());
    ASSERT_TRUE(expected.count(name)) << "no expectation for " << name;
    const Expected& e = expected.at(name);
    EXPECT_EQ(scene.name, name);
    EXPECT_EQ(scene.surfels.size(), e.surfels);
    EXPECT_EQ(scene.surfels.normals.size(), e.surfels);
    EXPECT_EQ(scene.nodes.target_count, e.nodes);
    EXPECT_EQ(scene.plasticity, e.plasticity);
    EXPECT_EQ(scene.fracture, e.fracture);
    EXPECT_EQ(scene.balloon.enabled, e.balloon);
    EXPECT_EQ(scene.weak_point.enabled, e.weak);
    EXPECT_EQ(scene.pins.size(), e.pins);
    for (const Vec3& n : scene.surfels.normals) ASSERT_NEAR(n.norm(), 1.0, 1e-9);
    ++seen;
  }
  EXPECT_EQ(seen, expected.size());
  // F.1 parameters.
  const ShellScene poster = loadShellScene(scenePath("fig7_8_poster"));
  EXPECT_EQ(poster.material.stretch_stiffness, 1000.0);
  EXPECT_EQ(poster.material.bending_stiffness, 10000.0);
  EXPECT_EQ(poster.material_options.fracture.stretch_threshold, 0.02);
  EXPECT_EQ(poster.material.damping, 0.3);
  EXPECT_FALSE(poster.surfels.colors.empty());
  const ShellScene bust = loadShellScene(scenePath("fig7_5_bust"));
  EXPECT_EQ(bust.material_options.plasticity.bend_yield, 0.2);
  EXPECT_EQ(bust.material_options.plasticity.bend_creep, 2.0);
}

TEST(ShellSceneFile, BadFilesNameFileLineAndProblem) {
  EXPECT_EQ(errorOf(kMinimal), "");
  // Syntax error on line 2.
  EXPECT_NE(
      errorOf("source:\n  sheet: {size: [4, 4], spacing: 0.1\nnodes: {spacing: 0.5}\n").find("bad.yaml:"),
      std::string::npos);
  const std::string unknown = errorOf(std::string(kMinimal) + "gravity: [0, 0, -1]\n");
  EXPECT_EQ(unknown.rfind("bad.yaml:7:1:", 0), 0u) << unknown;
  EXPECT_NE(unknown.find("unknown key 'gravity'"), std::string::npos) << unknown;
  std::string negative = kMinimal;
  negative.replace(negative.find("stretch_stiffness: 100"), 22, "stretch_stiffness: -5");
  const std::string neg = errorOf(negative);
  EXPECT_EQ(neg.rfind("bad.yaml:4:", 0), 0u) << neg;
  EXPECT_NE(neg.find("material.stretch_stiffness"), std::string::npos) << neg;
  const std::string missing = errorOf("source:\n  file: nowhere/none.off\nnodes: {count: 10}\n");
  EXPECT_EQ(missing.rfind("bad.yaml:2:9:", 0), 0u) << missing;
  const std::string both = errorOf(std::string(kMinimal) + "weak_point: {center: [0, 0, 0], radius: 1}\n");
  EXPECT_NE(both.find("needs a 'fracture' block"), std::string::npos) << both;
  std::string frames = kMinimal;
  frames.replace(frames.find("steps_per_frame: 3"), 18, "steps_per_frame: 3, time: 0.1");
  EXPECT_EQ(errorOf(frames).rfind("bad.yaml:6:", 0), 0u) << errorOf(frames);
  const std::string speed =
      errorOf(std::string(kMinimal) + "fracture: {stretch_threshold: 0.1, max_crack_speed: 0}\n");
  EXPECT_EQ(speed.rfind("bad.yaml:7:", 0), 0u) << speed;
  EXPECT_NE(speed.find("fracture.max_crack_speed"), std::string::npos) << speed;
  const std::string vent = errorOf(std::string(kMinimal) + "balloon: {pressure: 1, vent_time: -1}\n");
  EXPECT_NE(vent.find("balloon.vent_time"), std::string::npos) << vent;
  std::string balance = kMinimal;
  balance.replace(balance.find("bending_stiffness: 10}"), 22, "bending_stiffness: 10, balance_membrane: 3}");
  EXPECT_NE(errorOf(balance).find("material.balance_membrane"), std::string::npos) << errorOf(balance);
  std::string fit = kMinimal;
  fit.replace(fit.find("bending_stiffness: 10}"), 22, "bending_stiffness: 10, bending_fit: 0}");
  EXPECT_NE(errorOf(fit).find("material.bending_fit must be positive"), std::string::npos) << errorOf(fit);
  fit.replace(fit.find("bending_fit: 0}"), 15, "bending_fit: 0.05}");
  EXPECT_EQ(errorOf(fit), "");
  EXPECT_EQ(parseShellScene(fit, "fit.yaml").material.bending_fit, 0.05);
  EXPECT_THROW(loadShellScene("/nonexistent/scene.yaml"), ShellSceneError);
}

// Mesh sources are sampled at random: the radii cover the gaps between neighbouring surfels (3.3), so the
// rendered surface has no holes. Probes: the midpoints between each surfel and its 6 nearest neighbours.
TEST(ShellSceneFile, MeshSurfelsCoverTheGapsBetweenNeighbours) {
  if (!dataPresent()) GTEST_SKIP() << "needs ../shared/data: face_mask.off and maxplanck_bust.off";
  const ShellScene scene = loadShellScene(scenePath("fig7_5_bust"));
  const SurfelCloud& c = scene.surfels;
  ASSERT_EQ(c.radii.size(), c.size());
  const double max_r = *std::max_element(c.radii.begin(), c.radii.end());
  const double min_r = *std::min_element(c.radii.begin(), c.radii.end());
  const KdTree tree(c.positions);
  std::vector<Neighbor> knn(7), near;
  size_t probes = 0, uncovered = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    tree.knn(c.positions[i], 7, knn.data());
    for (size_t m = 1; m < 7; ++m) {
      const Vec3 y = 0.5 * (c.positions[i] + c.positions[knn[m].index]);
      tree.radius(y, max_r * 1.01, near);
      bool covered = false;
      for (const Neighbor& nb : near) {
        const Vec3 d = y - c.positions[nb.index];
        const Vec3& n = c.normals[nb.index];
        covered = covered || (d - n * n.dot(d)).norm() <= c.radii[nb.index];
      }
      ++probes;
      uncovered += !covered;
    }
  }
  std::printf("bust surfels: radii %.3f .. %.3f, %zu of %zu neighbour midpoints uncovered\n", min_r, max_r,
              uncovered, probes);
  EXPECT_EQ(uncovered, 0u);
  EXPECT_GT(max_r, 1.5 * min_r);  // per-surfel radii, larger in the voids of the random sampling
}

TEST(ShellSceneFile, ShortRunsOfEverySceneStayFinite) {
  if (!dataPresent()) GTEST_SKIP() << "needs ../shared/data: face_mask.off and maxplanck_bust.off";
  const std::map<std::string, std::function<void(YAML::Node&)>> cheap = {
      {"fig7_4_mask",
       [](YAML::Node& n) {
         n["source"]["sample_count"] = 3000;
         n["nodes"]["count"] = 250;
       }},
      {"fig7_5_bust",
       [](YAML::Node& n) {
         n["source"]["sample_count"] = 3000;
         n["nodes"]["count"] = 300;
       }},
      {"fig7_8_poster",
       [](YAML::Node& n) {
         n["source"]["sheet"]["spacing"] = 1.0;
         n["nodes"]["count"] = 400;
       }},
      {"fig7_10_balloon",
       [](YAML::Node& n) {
         n["source"]["sphere"]["count"] = 4000;
         n["nodes"]["count"] = 400;
       }},
  };
  for (const auto& [name, edit] : cheap) {
    SCOPED_TRACE(name);
    ShellScene scene = cheapScene(name, edit);
    scene.frame_count = 3;
    ShellRunOptions options;
    options.write_files = false;
    const ShellRunStats stats = runShellScene(scene, options);
    std::printf("%s\n", shellRunStatsJson(stats).c_str());
    EXPECT_TRUE(stats.instability.empty()) << stats.instability;
    EXPECT_EQ(stats.frames, 3);
    EXPECT_GT(stats.steps, 0u);
    EXPECT_NEAR(double(stats.nodes), double(scene.nodes.target_count), 0.05 * scene.nodes.target_count);
    EXPECT_TRUE(std::isfinite(stats.mean_radius_end));
  }
}

TEST(ShellSceneFile, SimulationKeepsSurfelsFiniteAndOnTheNodes) {
  if (!dataPresent()) GTEST_SKIP() << "needs ../shared/data: face_mask.off and maxplanck_bust.off";
  ShellScene scene = cheapScene("fig7_4_mask", [](YAML::Node& n) {
    n["source"]["sample_count"] = 3000;
    n["nodes"]["count"] = 250;
  });
  ShellSimulation sim(scene);
  const double z0 = sim.solver().positions()[0].z();
  for (int f = 0; f < 5; ++f) sim.advanceFrame();
  EXPECT_TRUE(std::isfinite(sim.maxCoordinate()));
  EXPECT_TRUE(std::isfinite(sim.maxSpeed()));
  EXPECT_LT(sim.solver().positions()[0].z(), z0);  // falling
  ASSERT_EQ(sim.surfels().size(), 3000u);
  // Skinned surfels follow the nodes: each lies near its nearest node's displacement.
  double worst = 0.0;
  const ShellNodes& nodes = sim.solver().nodes();
  for (size_t s = 0; s < sim.surfels().size(); s += 37) {
    const Vec3& rest = scene.surfels.positions[s];
    size_t best = 0;
    for (size_t i = 0; i < nodes.size(); ++i)
      if ((nodes.rest_positions[i] - rest).squaredNorm() < (nodes.rest_positions[best] - rest).squaredNorm())
        best = i;
    const Vec3 moved = sim.solver().positions()[best] - nodes.rest_positions[best];
    worst = std::max(worst, (sim.surfels().positions[s] - rest - moved).norm());
    EXPECT_NEAR(sim.surfels().normals[s].norm(), 1.0, 1e-9);
  }
  std::printf("mask: surfel displacement vs nearest node, worst difference %.4f\n", worst);
  EXPECT_LT(worst, 0.5);  // node spacing is about 1 unit; the shell drops as a whole
}

TEST(ShellSceneFile, PosterTearsFromTheWeakPoint) {
  ShellScene scene = cheapScene("fig7_8_poster", [](YAML::Node& n) {
    n["source"]["sheet"]["spacing"] = 1.0;
    n["nodes"]["count"] = 500;
    n["weak_point"]["radius"] = 8.0;
  });
  scene.frame_count = 100;
  ShellSimulation sim(scene);
  int frame = 0;
  while (sim.crackCount() == 0 && frame < scene.frame_count) {
    sim.advanceFrame();
    ++frame;
  }
  std::printf("poster: first crack after %d frames (t %.3f), %zu cracks, %zu nodes\n", frame,
              sim.solver().time(), sim.crackCount(), sim.solver().nodes().size());
  ASSERT_GT(sim.crackCount(), 0u);
  const ShellCrack& first = sim.material()->cracks()[0];
  std::printf("poster: first crack at (%.2f, %.2f), weak point (%.1f, %.1f), skinning fallbacks %zu\n",
              first.center.x(), first.center.y(), scene.weak_point.center.x(), scene.weak_point.center.y(),
              sim.skinningFallbacks());
  EXPECT_TRUE(first.stretch);
  EXPECT_LT((first.center - scene.weak_point.center).norm(), scene.weak_point.radius);
  // Discontinuity surfels come in pairs with opposite normals.
  sim.animateSurface();
  ASSERT_EQ(sim.crackSurfels().size(), 2 * sim.crackCount());
  EXPECT_LT(sim.crackSurfels().normals[0].dot(sim.crackSurfels().normals[1]), -0.9);  // each follows its side
  EXPECT_TRUE(std::isfinite(sim.maxCoordinate()));
}

TEST(ShellSceneFile, BalloonGrowsUnderTheRampedPressure) {
  ShellScene scene = cheapScene("fig7_10_balloon", [](YAML::Node& n) {
    n["source"]["sphere"]["count"] = 4000;
    n["nodes"]["count"] = 400;
  });
  EXPECT_DOUBLE_EQ(scene.balloon.pressureAt(0.0), 0.0);
  EXPECT_DOUBLE_EQ(scene.balloon.pressureAt(1.0), 0.75);
  EXPECT_DOUBLE_EQ(scene.balloon.pressureAt(10.0), 6.0);
  // Venting: from the tear on the pressure decays with vent_time.
  EXPECT_DOUBLE_EQ(scene.balloon.vent_time, 0.3);
  EXPECT_DOUBLE_EQ(scene.balloon.pressureAt(2.0, -1.0), 1.5);  // not torn
  EXPECT_DOUBLE_EQ(scene.balloon.pressureAt(2.0, 3.0), 1.5);   // before the tear
  EXPECT_NEAR(scene.balloon.pressureAt(3.6, 3.0), 2.25 * std::exp(-2.0), 1e-15);
  EXPECT_TRUE(scene.balance_membrane);
  EXPECT_DOUBLE_EQ(scene.material_options.fracture.max_crack_speed, 10.0);
  scene.frame_count = 25;
  ShellRunOptions options;
  options.write_files = false;
  const ShellRunStats stats = runShellScene(scene, options);
  std::printf("%s\n", shellRunStatsJson(stats).c_str());
  EXPECT_TRUE(stats.instability.empty()) << stats.instability;
  EXPECT_NEAR(stats.mean_radius_start, 10.0, 0.05);
  EXPECT_GT(stats.mean_radius_end, 1.005 * stats.mean_radius_start);  // p = 0.75 at 1 s: ~0.9 % strain
  ASSERT_TRUE(stats.membrane_balanced);
  EXPECT_LT(stats.membrane_balance.residual_after, 1e-6 * stats.membrane_balance.residual_before);
}
