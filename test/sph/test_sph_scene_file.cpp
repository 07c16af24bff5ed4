// SPH scene files (config/sph), the scene runner of rc_sph and the particle outputs (PLY, VTK .vtp).
#include "relaxed_connectivity/sph/sph_dam_break_surge.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "../shared_data.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/io/obj_io.h"
#include "relaxed_connectivity/sph/sph_lattice.h"
#include "relaxed_connectivity/sph/sph_output.h"
#include "relaxed_connectivity/sph/sph_scene_builders.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"
#include "scene_file_test_support.h"

namespace rc {
namespace {

namespace fs = std::filesystem;

const std::string kSceneDir = sphSceneDir();

fs::path tempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rc_test_sph_scene_file_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

struct ExpectedCounts {
  size_t fluid, walls, moving, planes, solids, solid_particles;
};

size_t solidParticleCount(const SphParticles& p) {
  size_t n = 0;
  for (size_t i = 0; i < p.size(); ++i) n += p.kinds[i] == SphParticleKind::kFluid && p.phases[i] != 0;
  return n;
}

// Every shipped scene must be listed here (and so loaded by this test).
TEST(SphSceneFile, EveryShippedSceneLoadsWithItsParticleCounts) {
  const std::map<std::string, ExpectedCounts> expected = {
      {"dam_break_2d", {20 * 40, 106 * 53 - 100 * 50, 0, 0, 0, 0}},
      {"hydrostatic_tank_2d", {20 * 20, 26 * 27 - 20 * 24, 0, 0, 0, 0}},
      {"hydrostatic_tank_3d", {10 * 15 * 10, 16 * 19 * 16 - 10 * 16 * 10, 0, 0, 0, 0}},
      {"dam_break_3d", {20 * 30 * 30, 64 * 52 * 34 - 60 * 50 * 30, 0, 5, 0, 0}},
      // 11 hexagonal rows of 10 or 11 particles.
      {"elastic_cube_2d", {0, 0, 0, 3, 1, 115}},
      // Nine dice of 249 fcc points each (thesis: 246).
      {"dice_3d", {0, 0, 0, 5, 9, 9 * 249}},
      // A sphere of radius 4 d on the fcc lattice (temperature; test_sph_scene_thermal.cpp).
      {"melting_block_3d", {0, 0, 0, 5, 1, 381}},
      // 8 x 8 fluid over a 12 x 3 rod; the solid fluid freezes into starts empty.
      {"freezing_rod_2d", {64, 36, 0, 3, 1, 0}},
      {"fig87_plastic_cube_2d", {0, 0, 0, 3, 1, 115}},
      // 16 of the 115 particles are anchored (static boundary kind, phase 1)
      {"fig87_fracturing_cube_2d", {0, 16, 0, 3, 1, 99}},
      // Two 2D squares of 115 particles (test_sph_scene_mesh.cpp).
      {"colliding_blocks_2d", {0, 0, 0, 0, 2, 2 * 115}},
      // The Stanford bunny scan scaled by 8.4 on the fcc lattice of 0.04 m (Table 8.1: 9871).
      {"fig8_4_melting_bunny", {0, 0, 0, 5, 1, 9892}},
      // Thesis Fig. 8.5 in 3D: a 10 x 12 x 10 slime block over a static rod of 20 x 21 particles; the source
      // adds the rest during the run (test_sph_fluid_source.cpp).
      {"fig8_5_freezing_rod", {1200, 420, 0, 5, 1, 0}},
  };
  size_t loaded = 0;
  for (const auto& entry : fs::directory_iterator(kSceneDir)) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string stem = entry.path().stem().string();
    const auto it = expected.find(stem);
    ASSERT_NE(it, expected.end()) << entry.path() << " is not covered by this test";
    if (stem == "fig8_4_melting_bunny") {  // its mesh lives in ../shared/data: the next test
      ++loaded;
      continue;
    }
    const SphScene scene = loadSphScene(entry.path().string());
    EXPECT_EQ(scene.name, stem);
    const size_t solid_particles = solidParticleCount(scene.particles);
    EXPECT_EQ(scene.particles.count(SphParticleKind::kFluid) - solid_particles, it->second.fluid) << stem;
    EXPECT_EQ(solid_particles, it->second.solid_particles) << stem;
    EXPECT_EQ(scene.solids.size(), it->second.solids) << stem;
    EXPECT_EQ(scene.particles.count(SphParticleKind::kStaticBoundary), it->second.walls) << stem;
    EXPECT_EQ(scene.particles.count(SphParticleKind::kMovingBoundary), it->second.moving) << stem;
    EXPECT_EQ(scene.planes.size(), it->second.planes) << stem;
    // Only what a scene uses is switched on.
    EXPECT_EQ(std::count(scene.enabled_physics.begin(), scene.enabled_physics.end(), "elasticity"),
              it->second.solids > 0 ? 1 : 0)
        << stem;
    EXPECT_EQ(scene.surface.enabled,
              std::count(scene.enabled_physics.begin(), scene.enabled_physics.end(), "surface") == 1);
    EXPECT_NO_THROW(scene.config.validate());
    for (const std::string& warning : scene.warnings) std::printf("%s\n", warning.c_str());
    const std::set<std::string> warned = {"dam_break_3d", "fig8_5_freezing_rod"};  // 3D fluid at h = 2 dx
    EXPECT_EQ(scene.warnings.size(), warned.count(stem)) << stem;
    // A term per solid, plus the penalty with enable: [collisions].
    EXPECT_EQ(makeSphSolver(scene).forceTerms().size(),
              it->second.solids + (scene.collisions.enabled ? 1 : 0))
        << stem;
    ++loaded;
  }
  EXPECT_EQ(loaded, expected.size());
  const SphScene d3 = loadSphScene(kSceneDir + "dam_break_3d.yaml");
  EXPECT_EQ(d3.config.dimension, 3);
  EXPECT_NEAR(d3.config.soundSpeed(), 24.3, 1e-12);  // speed_of_sound: K = rho_0 c^2 / Gamma
  EXPECT_EQ(d3.output.every, 2);
  EXPECT_TRUE(d3.output.vtp && !d3.output.ply);
  const SphScene tank = loadSphScene(kSceneDir + "hydrostatic_tank_2d.yaml");
  EXPECT_FALSE(tank.output.enabled());  // no output unless asked for
  EXPECT_EQ(tank.config.pressure_kernel, SphPressureKernel::kPoly6);
  EXPECT_EQ(tank.config.negative_pressure_scale, 0.0);
}

/// The dam break of test_sph_validation.cpp, built by hand.
SphDamBreak2D handDamBreak() {
  return martinMoyceDamBreak(20, 3.0);
}

SphFluidConfig handDamBreakConfig() {
  return martinMoyceDamBreakConfig(handDamBreak());
}

bool sameBits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

// The Fig. 8.4 bunny: the scan scaled by 8.4 on the fcc lattice of 0.04 m (Table 8.1: 9871 particles).
TEST(SphSceneFile, ShippedBunnySceneLoadsWithItsParticleCount) {
  RC_SKIP_WITHOUT_SHARED_DATA("bunny.ply");
  const SphScene scene = loadSphScene(kSceneDir + "fig8_4_melting_bunny.yaml");
  EXPECT_EQ(scene.name, "fig8_4_melting_bunny");
  EXPECT_EQ(solidParticleCount(scene.particles), 9892u);
  EXPECT_EQ(scene.particles.count(SphParticleKind::kFluid), 9892u);
  EXPECT_EQ(scene.particles.count(SphParticleKind::kStaticBoundary), 0u);
  EXPECT_EQ(scene.solids.size(), 1u);
  EXPECT_EQ(scene.planes.size(), 5u);
  EXPECT_NO_THROW(scene.config.validate());
}

TEST(SphSceneFile, DamBreakFileRunsBitwiseLikeTheHandBuiltScene) {
  SphScene scene = loadSphScene(kSceneDir + "dam_break_2d.yaml");
  SphFluidConfig hand_config = handDamBreakConfig();
  SphParticles hand_particles = makeDamBreak2D(handDamBreak(), hand_config);
  EXPECT_EQ(scene.config.smoothing_length, hand_config.smoothing_length);
  EXPECT_EQ(scene.config.stiffness, hand_config.stiffness);
  EXPECT_EQ(scene.config.gravity, hand_config.gravity);
  ASSERT_TRUE(sameBits(scene.particles.positions, hand_particles.positions));
  ASSERT_EQ(scene.particles.masses, hand_particles.masses);
  ASSERT_EQ(scene.particles.kinds, hand_particles.kinds);

  scene.frame_count = 20;
  SphFluidSolver from_file = makeSphSolver(scene);
  int reports = 0;
  SphRunOptions options;  // no out_dir: nothing written
  options.on_frame = [&](const SphFrameReport& r) {
    ++reports;
    EXPECT_EQ(r.frame, reports);
    EXPECT_EQ(r.frame_count, 20);
  };
  const SphRunStats stats = runSphScene(scene, from_file, options);
  EXPECT_EQ(reports, 20);
  EXPECT_TRUE(stats.instability.empty()) << stats.instability;
  EXPECT_TRUE(stats.files.empty());

  SphFluidSolver by_hand(hand_config, hand_particles);
  for (int f = 0; f < 20; ++f) by_hand.advance(0.01);
  EXPECT_EQ(from_file.time(), by_hand.time());
  EXPECT_EQ(from_file.stepCount(), by_hand.stepCount());
  EXPECT_TRUE(sameBits(from_file.particles().positions, by_hand.particles().positions));
  EXPECT_TRUE(sameBits(from_file.particles().velocities, by_hand.particles().velocities));
  EXPECT_EQ(from_file.particles().pressures, by_hand.particles().pressures);

  // Statistics: the counts and step sizes of the run.
  EXPECT_EQ(stats.frames, 20);
  EXPECT_EQ(stats.steps, by_hand.stepCount());
  EXPECT_EQ(stats.particles, 1418u);
  EXPECT_EQ(stats.fluid_particles, 800u);
  EXPECT_NEAR(stats.simulated_time, 0.2, 1e-12);
  EXPECT_NEAR(stats.mean_dt * double(stats.steps), 0.2, 1e-12);
  // Sound-speed limited: cfl h / c, c = sqrt(K / rho_0) at rest (Gamma = 1).
  const double dt_sound = 0.4 * 0.015 / std::sqrt(392.4);
  EXPECT_LE(stats.min_dt, dt_sound * (1 + 1e-12));
  EXPECT_GT(stats.min_dt, 0.5 * dt_sound);
  EXPECT_EQ(stats.mass_drift, 0.0);
  EXPECT_GT(stats.mean_step_us, 0.0);
  EXPECT_GE(stats.max_step_us, stats.mean_step_us);
  // The fluid falls and spreads: the floor and walls stop the fall, so they pushed up on it.
  EXPECT_GT(stats.boundary_impulse.y(), 0.0);
  EXPECT_GT(stats.momentum_end.x(), 0.0);
  // Viscosity and XSPH dissipate (about -20% by t = 0.2 s); nothing adds energy (test_sph_energy.cpp).
  EXPECT_LT(stats.energy_change, 0.0);
  EXPECT_GT(stats.energy_change, -0.5);
  const std::string json = sphRunStatsJson(stats);
  EXPECT_NE(json.find("\"steps\":" + std::to_string(stats.steps)), std::string::npos) << json;
  EXPECT_NE(json.find("\"instability\":\"none\""), std::string::npos) << json;
  EXPECT_EQ(json.find('\n'), std::string::npos);
}

/// The error message of parsing `yaml` (empty if it parses).
const char* kGoodHead =
    "dimension: 2\n"                                    // 1
    "spacing: 0.02\n"                                   // 2
    "solver: {smoothing_ratio: 2.5, stiffness: 1e5}\n"  // 3
    "fluid:\n"                                          // 4
    "  - {lo: [0, 0], hi: [0.2, 0.2]}\n"                // 5
    "frames: {count: 2, time: 0.01}\n";                 // 6

TEST(SphSceneFile, BadInputsNameFileLineAndProblem) {
  ASSERT_EQ(parseError(kGoodHead), "");
  const std::string head = kGoodHead;
  expectErrorAt(head + "colour: red\n", 7, "unknown key 'colour'");
  expectErrorAt(head + "boundary:\n  walls:\n    - {lo: [0, 0], hi: [1, 1], layer: 3}\n", 9,
                "unknown key 'layer'");
  expectErrorAt(head + "moving:\n  - {lo: [0, 0], hi: [0.1, 0.1], spacing: -0.01, velocity: [1, 0]}\n", 8,
                "spacing must be positive");
  expectErrorAt(head + "boundary:\n  planes:\n    - {normal: yes, offset: 0}\n", 9,
                "normal: expected [x, y]");
  expectErrorAt("dimension: 2\nspacing: 0.02\nsolver: {smoothing_ratio: 2.5, stiffness: stiff}\n", 3,
                "stiffness: expected a number, got 'stiff'");
  expectErrorAt(head + "enable: [temperature]\n", 7, "'temperature' needs a 'temperature' block");
  expectErrorAt(head + "enable:\n  - phase_transition\n", 8, "'phase_transition' needs 'temperature'");
  expectErrorAt(head + "enable: [elasticity, elasticity]\n", 7, "listed twice");
  expectErrorAt(head + "enable: [magnetism]\n", 7, "unknown physics 'magnetism'");
  // Values the solver rejects point at their own line.
  expectErrorAt("dimension: 2\nspacing: 0.02\nsolver:\n  smoothing_ratio: 2.5\n  xsph: 1.5\n", 5, "xsph");
  expectErrorAt(head + "output: {particles: {formats: [obj]}}\n", 7, "unknown 'obj'");
  expectErrorAt(head + "boundary: {walls: [{lo: [0, 0], hi: [0.1, 0.3], closed_top: maybe}]}\n", 7,
                "closed_top: expected true or false");
  expectErrorAt(
      "dimension: 2\nspacing: 0.02\nsolver: {smoothing_ratio: 2.5}\nfluid:\n  - {lo: [0, 0], hi: [0, "
      "0.2]}\n",
      5, "hi must exceed lo");
  expectErrorAt("dimension: 3\nsolver: {smoothing_length: 0.1}\nfluid: [{lo: [0, 0], hi: [1, 1]}]\n", 3,
                "expected [x, y, z]");
  expectErrorAt("dimension: 2\nsolver: {smoothing_length: 0.1, gravity: [0, -9.81, 1]}\n", 2,
                "z must be 0 in 2D");
  expectErrorAt(
      "dimension: 2\nspacing: 1e-7\nsolver: {smoothing_ratio: 2}\nfluid: [{lo: [0, 0], hi: [1, 1]}]\n", 4,
      "exceed");
  expectErrorAt("dimension: 2\nsolver: {smoothing_length: 0.1}\nfluid: [{lo: [0, 0], hi: [1, 1]}]\n", 3,
                "missing 'spacing'");
  expectErrorAt(head.substr(0, head.rfind("frames")), 1, "missing 'frames'");
  expectErrorAt("dimension: 4\n", 1, "dimension must be an integer in [2, 3]");
  expectErrorAt("dimension: 2\nsolver: {smoothing_length: 0.1\n", 3, "YAML syntax");
  // Through a file: the message names the file's path.
  const fs::path dir = tempDir("bad");
  const std::string path = (dir / "typo.yaml").string();
  std::ofstream(path) << head << "fraems: 3\n";
  try {
    loadSphScene(path);
    ADD_FAILURE() << "no error";
  } catch (const SphSceneError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ":7:1: scene: unknown key 'fraems'", 0), 0u) << e.what();
  }
  EXPECT_THROW(loadSphScene((dir / "missing.yaml").string()), SphSceneError);
}

// Settings known to give wrong results load, with a warning that names the line and the reason.
TEST(SphSceneFile, SettingsKnownToGiveWrongResultsWarnWithTheirLine) {
  EXPECT_TRUE(parseSphScene(kGoodHead, "good.yaml").warnings.empty());
  const SphScene spiky = parseSphScene(
      "dimension: 2\nspacing: 0.02\nsolver:\n  smoothing_ratio: 2.5\n  pressure_kernel: spiky\n"
      "fluid:\n  - {lo: [0, 0], hi: [0.2, 0.2]}\nframes: {count: 2, time: 0.01}\n",
      "spiky.yaml");
  ASSERT_EQ(spiky.warnings.size(), 1u);
  EXPECT_EQ(spiky.warnings[0].rfind("spiky.yaml:5:20: warning: solver.pressure_kernel spiky", 0), 0u)
      << spiky.warnings[0];
  EXPECT_EQ(spiky.config.pressure_kernel, SphPressureKernel::kSpiky);  // still as asked
  const std::string three_d =
      "dimension: 3\nspacing: 0.05\nsolver: {smoothing_ratio: RATIO}\nfluid:\n"
      "  - {lo: [0, 0, 0], hi: [0.2, 0.2, 0.2]}\n  - {lo: [1, 0, 0], hi: [1.2, 0.2, 0.2], spacing: 0.02}\n"
      "frames: {count: 2, time: 0.01}\n";
  auto withRatio = [&](const char* ratio) {
    std::string text = three_d;
    text.replace(text.find("RATIO"), 5, ratio);
    return parseSphScene(text, "3d.yaml");
  };
  // h = 2 x 0.05: the first block warns (about 33 neighbours); the second, at h = 5 x 0.02, does not.
  const SphScene coarse = withRatio("2");
  ASSERT_EQ(coarse.warnings.size(), 1u);
  EXPECT_EQ(coarse.warnings[0].rfind(
                "3d.yaml:5:5: warning: fluid[0]: h = 2 x its spacing (about 33 neighbours)", 0),
            0u)
      << coarse.warnings[0];
  EXPECT_NE(coarse.warnings[0].find("smoothing_ratio >= 2.5"), std::string::npos);
  EXPECT_TRUE(withRatio("2.5").warnings.empty());
  // 2D: below h = 2 dx.
  const SphScene sparse = parseSphScene(
      "dimension: 2\nspacing: 0.02\nsolver: {smoothing_ratio: 1.5}\nfluid:\n  - {lo: [0, 0], hi: [0.2, "
      "0.2]}\n"
      "frames: {count: 2, time: 0.01}\n",
      "sparse.yaml");
  ASSERT_EQ(sparse.warnings.size(), 1u);
  EXPECT_NE(sparse.warnings[0].find("sparse.yaml:5:5: warning: fluid[0]: h = 1.5 x its spacing (about 6 "
                                    "neighbours): too few"),
            std::string::npos)
      << sparse.warnings[0];
  // The monitors' keys.
  const SphScene monitors = parseSphScene(
      "dimension: 2\nspacing: 0.02\nsolver: {smoothing_ratio: 2.5, instability_window: 25, "
      "instability_window_growth: 4, max_compression: 0}\nfluid:\n  - {lo: [0, 0], hi: [0.2, 0.2]}\n"
      "frames: {count: 2, time: 0.01}\n",
      "monitors.yaml");
  EXPECT_EQ(monitors.config.instability_window, 25);
  EXPECT_EQ(monitors.config.instability_window_growth, 4.0);
  EXPECT_EQ(monitors.config.max_compression, 0.0);
  expectErrorAt("dimension: 2\nspacing: 0.02\nsolver:\n  smoothing_ratio: 2.5\n  max_compression: -1\n", 5,
                "max_compression");
  expectErrorAt(
      "dimension: 2\nspacing: 0.02\nsolver:\n  smoothing_ratio: 2.5\n  instability_window_growth: 0.5\n", 5,
      "instability_window_growth");
}

TEST(SphSceneFile, FluidSpheresAndVelocityFields) {
  // A 3D ball spinning about z around its centre, plus a uniform drift.
  const SphScene ball = parseSphScene(
      "dimension: 3\nspacing: 0.1\nsolver: {smoothing_ratio: 2.5}\nfluid:\n"
      "  - {shape: sphere, center: [1, 2, 3], radius: 0.5, velocity: {uniform: [0, 0, 1], rotation: [0, 0, "
      "2]}}\n"
      "frames: {count: 1, time: 0.01}\n",
      "ball.yaml");
  // Cell centres within the radius: about 4/3 pi 0.5^3 / 0.1^3 = 524.
  EXPECT_NEAR(double(ball.particles.size()), 4.0 / 3.0 * M_PI * 125, 40);
  double worst = 0;
  for (size_t i = 0; i < ball.particles.size(); ++i) {
    const Vec3 r = ball.particles.positions[i] - Vec3(1, 2, 3);
    EXPECT_LE(r.norm(), 0.5);
    worst = std::max(worst, (ball.particles.velocities[i] - Vec3(-2 * r.y(), 2 * r.x(), 1)).norm());
  }
  EXPECT_LT(worst, 1e-12);
  // 2D: the rotation is a number (about z); the gradient is a 2 x 2 matrix about a given point.
  const SphScene disc = parseSphScene(
      "dimension: 2\nspacing: 0.05\nsolver: {smoothing_ratio: 3}\nfluid:\n"
      "  - {lo: [0, 0], hi: [1, 1], velocity: {rotation: 1.5, gradient: [[1, 0], [0, -1]], about: [0, 0]}}\n"
      "frames: {count: 1, time: 0.01}\n",
      "disc.yaml");
  for (size_t i = 0; i < disc.particles.size(); ++i) {
    const Vec3& x = disc.particles.positions[i];
    EXPECT_LT((disc.particles.velocities[i] - Vec3(x.x() - 1.5 * x.y(), -x.y() + 1.5 * x.x(), 0)).norm(),
              1e-12);
  }
  // Samples from a file (beside the scene): each particle adds the velocity of the nearest sample.
  const fs::path dir = tempDir("velocity_file");
  std::ofstream(dir / "samples.txt") << "# x y vx vy\n0 0 1 0\n1, 1, 0, 2  # comma separated\n\n";
  std::ofstream(dir / "field.yaml")
      << "dimension: 2\nspacing: 0.05\nsolver: {smoothing_ratio: 3}\nfluid:\n"
         "  - {lo: [0, 0], hi: [1, 1], velocity: {uniform: [0, 1], file: samples.txt}}\n"
         "frames: {count: 1, time: 0.01}\n";
  const SphScene sampled = loadSphScene((dir / "field.yaml").string());
  for (size_t i = 0; i < sampled.particles.size(); ++i) {
    const Vec3& x = sampled.particles.positions[i];
    if (std::abs(x.x() + x.y() - 1) < 1e-9) continue;  // as near to both samples
    const Vec3 expected = x.x() + x.y() < 1 ? Vec3(1, 1, 0) : Vec3(0, 3, 0);
    EXPECT_EQ(sampled.particles.velocities[i], expected) << x.transpose();
  }
  std::ofstream(dir / "bad.txt") << "0 0 1 0\n0 0 1\n";
  std::ofstream(dir / "bad.yaml") << "dimension: 2\nspacing: 0.05\nsolver: {smoothing_ratio: 3}\nfluid:\n"
                                     "  - {lo: [0, 0], hi: [1, 1], velocity: {file: bad.txt}}\n"
                                     "frames: {count: 1, time: 0.01}\n";
  try {
    loadSphScene((dir / "bad.yaml").string());
    ADD_FAILURE() << "no error";
  } catch (const SphSceneError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.txt:2: expected 4 numbers (x y vx vy), got 3"),
              std::string::npos)
        << e.what();
  }
  const std::string head = "dimension: 2\nspacing: 0.05\nsolver: {smoothing_ratio: 3}\nfluid:\n";
  const std::string tail = "frames: {count: 1, time: 0.01}\n";
  expectErrorAt(head + "  - {shape: sphere, lo: [0, 0], center: [0, 0], radius: 1}\n" + tail, 5,
                "not with shape: sphere");
  expectErrorAt(head + "  - {shape: ball, center: [0, 0], radius: 1}\n" + tail, 5, "unknown 'ball'");
  expectErrorAt(head + "  - {shape: sphere, center: [0, 0], radius: -1}\n" + tail, 5,
                "radius must be positive");
  expectErrorAt(head + "  - {lo: [0, 0], hi: [1, 1], velocity: {gradient: [[1, 0]]}}\n" + tail, 5,
                "expected 2 rows");
  expectErrorAt(head + "  - {lo: [0, 0], hi: [1, 1], velocity: {spin: 1}}\n" + tail, 5, "unknown key 'spin'");
}

TEST(SphSceneFile, FluidFromAClosedMesh) {
  // An octahedron |x| + |y| + |z| <= 1 as an OBJ beside the scene, scaled by 0.5 and moved to (2, 1, 0).
  const fs::path dir = tempDir("fluid_mesh");
  TriangleMesh octahedron;
  const Vec3 corners[] = {Vec3(1, 0, 0),  Vec3(-1, 0, 0), Vec3(0, 1, 0),
                          Vec3(0, -1, 0), Vec3(0, 0, 1),  Vec3(0, 0, -1)};
  for (const Vec3& c : corners) octahedron.vertices.positions.push_back(c);
  for (uint32_t x : {0u, 1u})
    for (uint32_t y : {2u, 3u})
      for (uint32_t z : {4u, 5u}) {
        const bool flip = ((x == 1) != (y == 3)) != (z == 5);  // outward orientation
        octahedron.triangles.push_back(flip ? Triangle{x, z, y} : Triangle{x, y, z});
      }
  writeObjMesh((dir / "octahedron.obj").string(), octahedron);
  const std::string scene_path = (dir / "drop.yaml").string();
  std::ofstream(scene_path) << "dimension: 3\nspacing: 0.025\nsolver: {smoothing_ratio: 2.5}\nfluid:\n"
                               "  - {shape: mesh, mesh: octahedron.obj, scale: 0.5, translation: [2, 1, 0]}\n"
                               "frames: {count: 1, time: 0.01}\n";
  const SphScene scene = loadSphScene(scene_path);
  // Volume 4/3 r^3 with r = 0.5: 0.1667 m^3 over 0.025^3 = 10,667 cells.
  EXPECT_NEAR(double(scene.particles.size()), 4.0 / 3.0 * 0.125 / std::pow(0.025, 3), 200);
  for (const Vec3& x : scene.particles.positions) EXPECT_LE((x - Vec3(2, 1, 0)).cwiseAbs().sum(), 0.5 + 1e-9);
  const std::string head = "dimension: 3\nspacing: 0.025\nsolver: {smoothing_ratio: 2.5}\nfluid:\n";
  expectErrorAt(head + "  - {lo: [0, 0, 0], hi: [1, 1, 1], mesh: octahedron.obj}\n", 5,
                "only with shape: mesh");
}

TEST(SphSceneFile, MovingBoxesPlanesAndPerBoxSpacing) {
  const SphScene scene = parseSphScene(
      "dimension: 3\n"
      "spacing: 0.05\n"
      "solver: {smoothing_ratio: 2, speed_of_sound: 10, gamma: 2, rest_density: 500}\n"
      "fluid: [{lo: [0, 0, 0], hi: [0.2, 0.2, 0.2], velocity: [1, 0, 0]}]\n"
      "boundary:\n"
      "  boxes: [{lo: [0, -0.1, 0], hi: [0.2, 0, 0.2], spacing: 0.025}]\n"
      "  planes: [{normal: [0, 2, 0], point: [0, -0.1, 0], restitution: 0.5, friction: 0.25}]\n"
      "  box_planes: [{lo: [0, -1, 0], hi: [1, 1, 1], closed_top: true}]\n"
      "moving: [{lo: [-0.1, 0, 0], hi: [0, 0.2, 0.2], velocity: [0.5, 0, 0]}]\n"
      "frames: {count: 3, time: 0.005}\n"
      "output: {particles: {every: 3, formats: [ply, vtp]}}\n",
      "ok.yaml");
  EXPECT_EQ(scene.name, "ok");
  EXPECT_DOUBLE_EQ(scene.config.stiffness, 10.0 * 10.0 * 500.0 / 2.0);
  EXPECT_DOUBLE_EQ(scene.config.smoothing_length, 0.1);
  const SphParticles& p = scene.particles;
  ASSERT_EQ(p.count(SphParticleKind::kFluid), 64u);
  ASSERT_EQ(p.count(SphParticleKind::kStaticBoundary), 8u * 4u * 8u);
  ASSERT_EQ(p.count(SphParticleKind::kMovingBoundary), 2u * 4u * 4u);
  const SphKernels kernels(3, 0.1);
  for (size_t i = 0; i < p.size(); ++i) {
    const bool fine = p.kinds[i] == SphParticleKind::kStaticBoundary;
    EXPECT_DOUBLE_EQ(p.masses[i], latticeParticleMass(kernels, 500.0, fine ? 0.025 : 0.05));
    const Vec3 v = p.kinds[i] == SphParticleKind::kFluid            ? Vec3(1, 0, 0)
                   : p.kinds[i] == SphParticleKind::kMovingBoundary ? Vec3(0.5, 0, 0)
                                                                    : Vec3::Zero();
    EXPECT_EQ(p.velocities[i], v);
  }
  ASSERT_EQ(scene.planes.size(), 1u + 6u);
  EXPECT_EQ(scene.planes[0].normal, Vec3(0, 1, 0));
  EXPECT_DOUBLE_EQ(scene.planes[0].offset, -0.1);
  EXPECT_EQ(scene.planes[0].restitution, 0.5);
  EXPECT_EQ(scene.planes[0].friction, 0.25);
  EXPECT_EQ(scene.planes.back().normal, Vec3(0, -1, 0));  // closed top
  EXPECT_EQ(scene.output.every, 3);
  EXPECT_TRUE(scene.output.ply && scene.output.vtp);
}

TEST(SphSceneFile, UnstableRunIsReportedWithItsStep) {
  // The dam break with 25 x the sound-speed step (test_sph_fluid.cpp): unstable within a few steps.
  SphScene scene = loadSphScene(kSceneDir + "dam_break_2d.yaml");
  scene.config.fixed_dt = 25.0 * scene.config.cfl * scene.config.smoothing_length / scene.config.soundSpeed();
  scene.output = SphParticleOutput();
  SphFluidSolver solver = makeSphSolver(scene);
  const SphRunStats stats = runSphScene(scene, solver);
  ASSERT_FALSE(stats.instability.empty());
  EXPECT_GT(stats.instability_step, 0u);
  EXPECT_EQ(stats.instability_step, stats.steps);
  EXPECT_NE(stats.instability.find("step " + std::to_string(stats.instability_step) + " "), std::string::npos)
      << stats.instability;
  EXPECT_LT(stats.frames, scene.frame_count);
  const std::string json = sphRunStatsJson(stats);
  EXPECT_NE(json.find("\"instability_step\":" + std::to_string(stats.instability_step)), std::string::npos);
  EXPECT_EQ(json.find("\"instability\":\"none\""), std::string::npos);
}

/// Attribute `name` of the `in` text: the value, or "" if absent.
std::string xmlAttribute(const std::string& tag, const std::string& name) {
  const std::regex re(name + "=\"([^\"]*)\"");
  std::smatch m;
  return std::regex_search(tag, m, re) ? m[1].str() : "";
}

/// Checks a .vtp file: structure, array names, types, lengths (ascii token counts or appended byte counts).
void checkVtp(const std::string& path, size_t n, bool appended) {
  std::ifstream in(path, std::ios::binary);
  ASSERT_TRUE(in) << path;
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string file = buf.str();
  const size_t appended_at = file.find("<AppendedData");
  const std::string xml = file.substr(0, appended_at);
  EXPECT_EQ(xml.rfind("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\"", 0), 0u);
  EXPECT_NE(file.find("</VTKFile>"), std::string::npos);
  const std::regex piece_re("<Piece [^>]*>");
  std::smatch piece;
  ASSERT_TRUE(std::regex_search(xml, piece, piece_re));
  EXPECT_EQ(xmlAttribute(piece[0].str(), "NumberOfPoints"), std::to_string(n));
  EXPECT_EQ(xmlAttribute(piece[0].str(), "NumberOfVerts"), std::to_string(n));
  for (const char* section : {"<PointData", "</PointData>", "<Points>", "</Points>", "<Verts>", "</Verts>"})
    EXPECT_NE(xml.find(section), std::string::npos) << section;
  const std::map<std::string, std::pair<std::string, size_t>> expected = {
      {"velocity", {"Float32", 3}}, {"density", {"Float32", 1}}, {"pressure", {"Float32", 1}},
      {"kind", {"UInt8", 1}},       {"Points", {"Float64", 3}},  {"connectivity", {"Int64", 1}},
      {"offsets", {"Int64", 1}}};
  const std::map<std::string, size_t> type_size = {
      {"Float32", 4}, {"Float64", 8}, {"Int64", 8}, {"UInt8", 1}};
  const std::regex array_re("<DataArray [^>]*>");
  size_t arrays = 0;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), array_re); it != std::sregex_iterator(); ++it) {
    const std::string tag = (*it)[0].str();
    const std::string name = xmlAttribute(tag, "Name");
    ASSERT_TRUE(expected.count(name)) << tag;
    const auto& [type, components] = expected.at(name);
    EXPECT_EQ(xmlAttribute(tag, "type"), type) << name;
    const std::string nc = xmlAttribute(tag, "NumberOfComponents");
    EXPECT_EQ(nc.empty() ? size_t(1) : size_t(std::stoul(nc)), components) << name;
    const size_t values = n * components;
    if (appended) {
      EXPECT_EQ(xmlAttribute(tag, "format"), "appended");
      ASSERT_NE(appended_at, std::string::npos);
      const size_t data = file.find('_', appended_at) + 1;
      const size_t at = data + std::stoull(xmlAttribute(tag, "offset"));
      ASSERT_LE(at + 8, file.size());
      uint64_t bytes = 0;
      std::memcpy(&bytes, file.data() + at, 8);
      EXPECT_EQ(bytes, values * type_size.at(type)) << name;
      EXPECT_LE(at + 8 + bytes, file.size());
      if (name == "offsets" && n > 0) {  // vertex cells 1, 2, ..., n
        int64_t last = 0;
        std::memcpy(&last, file.data() + at + 8 + bytes - 8, 8);
        EXPECT_EQ(last, int64_t(n));
      }
    } else {
      EXPECT_EQ(xmlAttribute(tag, "format"), "ascii");
      const size_t body = xml.find('>', it->position()) + 1;
      const std::string text = xml.substr(body, xml.find("</DataArray>", body) - body);
      std::istringstream tokens(text);
      size_t count = 0;
      for (std::string t; tokens >> t;) ++count;
      EXPECT_EQ(count, values) << name;
    }
    ++arrays;
  }
  EXPECT_EQ(arrays, expected.size());
}

TEST(SphSceneFile, OutputsParseBack) {
  SphScene scene = loadSphScene(kSceneDir + "dam_break_2d.yaml");
  scene.frame_count = 2;
  scene.output.every = 2;
  scene.output.ply = scene.output.vtp = true;
  const fs::path dir = tempDir("out");
  SphFluidSolver solver = makeSphSolver(scene);
  SphRunOptions options;
  options.out_dir = (dir / "frames").string();
  const SphRunStats stats = runSphScene(scene, solver, options);
  ASSERT_TRUE(stats.instability.empty());
  // Frames 0 and 2, ply + vtp, and the collection.
  const fs::path frames = dir / "frames";
  std::vector<std::string> expected_files = {
      (frames / "dam_break_2d_0000.ply").string(), (frames / "dam_break_2d_0000.vtp").string(),
      (frames / "dam_break_2d.pvd").string(), (frames / "dam_break_2d_0002.ply").string(),
      (frames / "dam_break_2d_0002.vtp").string()};
  EXPECT_EQ(stats.files, expected_files);
  EXPECT_FALSE(fs::exists(frames / "dam_break_2d_0001.ply"));

  const SphParticles& p = solver.particles();
  const SurfelCloud cloud = readCloud((frames / "dam_break_2d_0002.ply").string());
  ASSERT_EQ(cloud.size(), p.size());
  const Attribute* velocity = cloud.attributes.find("velocity");
  const Attribute* density = cloud.attributes.find("density");
  const Attribute* pressure = cloud.attributes.find("pressure");
  const Attribute* kind = cloud.attributes.find("kind");
  ASSERT_TRUE(velocity && density && pressure && kind);
  EXPECT_EQ(velocity->count, 3u);
  EXPECT_EQ(kind->type, ScalarType::kUInt8);
  double max_speed = 0.0;
  for (size_t i = 0; i < p.size(); ++i) {
    EXPECT_NEAR((cloud.positions[i] - p.positions[i]).norm(), 0.0, 1e-6);  // float32
    for (uint32_t k = 0; k < 3; ++k) EXPECT_FLOAT_EQ(velocity->get(i, k), float(p.velocities[i][k]));
    EXPECT_FLOAT_EQ(density->get(i), float(p.densities[i]));
    EXPECT_FLOAT_EQ(pressure->get(i), float(p.pressures[i]));
    EXPECT_EQ(kind->get(i), double(uint8_t(p.kinds[i])));
    max_speed = std::max(max_speed, p.velocities[i].norm());
  }
  EXPECT_GT(max_speed, 0.0);  // frame 2 is not the rest state

  checkVtp((frames / "dam_break_2d_0002.vtp").string(), p.size(), true);
  checkVtp((frames / "dam_break_2d_0000.vtp").string(), p.size(), true);
  const std::string ascii = (dir / "ascii.vtp").string();
  writeSphVtp(ascii, p, VtpEncoding::kAscii);
  checkVtp(ascii, p.size(), false);
  // The collection lists both frames with their times.
  std::ifstream pvd((frames / "dam_break_2d.pvd").string());
  std::stringstream text;
  text << pvd.rdbuf();
  EXPECT_NE(text.str().find("timestep=\"0\" part=\"0\" file=\"dam_break_2d_0000.vtp\""), std::string::npos);
  EXPECT_NE(text.str().find("timestep=\"0.02\" part=\"0\" file=\"dam_break_2d_0002.vtp\""), std::string::npos)
      << text.str();
}

TEST(SphSceneFile, PhysicsKeysNeedTheirEnableEntry) {
  const std::string head = kGoodHead;
  expectErrorAt(head + "solids:\n  - {lo: [0, 0.3], hi: [0.1, 0.4]}\n", 8, "solids: needs 'elasticity'");
  expectErrorAt(head + "output:\n  surface: {every: 1}\n", 8, "output.surface: needs 'surface'");
  expectErrorAt(head + "enable: [surface]\n", 7, "'surface' needs a 3D scene");
  const std::string elastic = head + "enable: [elasticity]\nsolids:\n";  // solids from line 9
  expectErrorAt(elastic + "  - {lo: [0, 0.3], hi: [0.1, 0.4], model: strain, goal_stiffness: 1e4}\n", 9,
                "goal_stiffness: applies to model goal_position");
  expectErrorAt(elastic + "  - {lo: [0, 0.3], hi: [0.1, 0.4], youngs_modulus: 1e4}\n", 9,
                "youngs_modulus: applies to model strain");
  expectErrorAt(elastic + "  - {lo: [0, 0.3], hi: [0.1, 0.4], model: rubber}\n", 9, "unknown 'rubber'");
  expectErrorAt(elastic + "  - {shape: cone, lo: [0, 0.3], hi: [0.1, 0.4]}\n", 9, "unknown shape 'cone'");
  expectErrorAt(elastic + "  - {shape: sphere, lo: [0, 0.3], hi: [0.1, 0.4]}\n", 9, "unknown key 'lo'");
  expectErrorAt(
      elastic +
          "  - {lo: [0, 0.3], hi: [0.1, 0.4], phase: 2}\n  - {lo: [0, 0.5], hi: [0.1, 0.6], phase: 2}\n",
      10, "phase: 2 is already used");
  expectErrorAt(elastic + "  - {lo: [0, 0.3], hi: [0.1, 0.4], phase: 0}\n", 9,
                "phase must be an integer in [1, 255]");
  expectErrorAt(elastic + "  - {lo: [0, 0.3], hi: [0.1, 0.4], model: strain, poisson_ratio: 0.7}\n", 9,
                "poisson_ratio");
  expectErrorAt(elastic + "  - {lo: [0, 0.3], hi: [0.1, 0.4], rotation: {axis: [1, 0], angle: 10}}\n", 9,
                "must be [0, 0, 1] in 2D");
  expectErrorAt(elastic + "  - {lo: [0, 0.3], hi: [0.1, 0.4], spacing: 0.05}\n", 9,
                "lattice spacing must be below the smoothing length");
  expectErrorAt("dimension: 2\nspacing: 0.02\nsolver: {smoothing_ratio: 2}\nframes: {count: 1, time: 0.01}\n",
                1, "missing 'fluid'");
}

TEST(SphSceneFile, SolidsAreSampledOnTheLatticeWithTheirOwnPhase) {
  const SphScene scene = parseSphScene(
      "dimension: 2\n"
      "spacing: 0.02\n"
      "enable: [elasticity]\n"
      "solver: {smoothing_ratio: 2, rest_density: 1, stiffness: 20}\n"
      "solids:\n"
      "  - {shape: sphere, center: [0, 0.5], radius: 0.1, velocity: [1, 0], phase: 7,\n"
      "     rotation: {angle: 90}}\n"
      "  - {lo: [0.3, 0], hi: [0.5, 0.2], spacing: 0.025, model: strain, youngs_modulus: 2e5,\n"
      "     poisson_ratio: 0.25}\n"
      "frames: {count: 1, time: 0.01}\n",
      "solids.yaml");
  ASSERT_EQ(scene.solids.size(), 2u);
  const SphSceneSolid& disc = scene.solids[0];
  const SphSceneSolid& block = scene.solids[1];
  EXPECT_EQ(disc.phase, 7);
  EXPECT_EQ(block.phase, 1);  // the first unused id
  EXPECT_EQ(disc.elastic.model, SphElasticModel::kGoalPosition);
  EXPECT_EQ(disc.elastic.goal_stiffness, SphElasticConfig().goal_stiffness);
  EXPECT_EQ(block.elastic.model, SphElasticModel::kStrain);
  EXPECT_EQ(block.elastic.youngs_modulus, 2e5);
  EXPECT_EQ(block.elastic.poisson_ratio, 0.25);
  EXPECT_EQ(block.elastic.lattice_spacing, 0.025);
  EXPECT_NEAR((disc.orientation - Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()).toRotationMatrix()).norm(), 0.0,
              1e-15);
  // The disc: the hexagonal lattice points of radius 0.1 around its centre, rotated by 90 degrees.
  const SphLattice lattice(2, 0.02);
  const std::vector<Vec3> local = sampleLatticeSphere(lattice, Vec3::Zero(), 0.1);
  ASSERT_EQ(disc.count, local.size());
  EXPECT_EQ(disc.first, 0u);
  EXPECT_EQ(block.first, disc.count);
  const SphParticles& p = scene.particles;
  ASSERT_EQ(p.size(), disc.count + block.count);
  const SphKernels kernels(2, 0.04);
  for (size_t i = 0; i < disc.count; ++i) {
    EXPECT_NEAR((p.positions[i] - Vec3(0, 0.5, 0) - disc.orientation * local[i]).norm(), 0.0, 1e-15);
    EXPECT_EQ(p.phases[i], 7);
    EXPECT_EQ(p.kinds[i], SphParticleKind::kFluid);
    EXPECT_EQ(p.velocities[i], Vec3(1, 0, 0));
    EXPECT_DOUBLE_EQ(p.masses[i], lattice.particleMass(kernels, 1.0));
  }
  const std::vector<Vec3> block_local =
      sampleLatticeBox(SphLattice(2, 0.025), Vec3(-0.1, -0.1, 0), Vec3(0.1, 0.1, 0), SphLatticeFrame());
  EXPECT_EQ(block.count, block_local.size());
  for (size_t i = block.first; i < p.size(); ++i) {
    EXPECT_EQ(p.phases[i], 1);
    EXPECT_GE(p.positions[i].x(), 0.3 - 1e-12);
    EXPECT_LE(p.positions[i].x(), 0.5 + 1e-12);
  }
  EXPECT_EQ(makeSphSolver(scene).forceTerms().size(), 2u);
}

Vec3 centerOfMass(const SphParticles& p, Vec3* velocity) {
  double m = 0.0;
  Vec3 x = Vec3::Zero(), v = Vec3::Zero();
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.kinds[i] != SphParticleKind::kFluid) continue;
    m += p.masses[i];
    x += p.masses[i] * p.positions[i];
    v += p.masses[i] * p.velocities[i];
  }
  *velocity = v / m;
  return x / m;
}

TEST(SphSceneFile, ElasticCubeBouncesAndKeepsItsShape) {
  // Fig. 8.7 (a): the cube falls 3 cm, hits the floor at about t = 0.08 s and bounces.
  const SphScene scene = loadSphScene(kSceneDir + "elastic_cube_2d.yaml");
  ASSERT_EQ(scene.solids.size(), 1u);
  EXPECT_EQ(scene.solids[0].elastic.model, SphElasticModel::kGoalPosition);
  EXPECT_EQ(scene.solids[0].elastic.goal_stiffness, 8.0e5);
  EXPECT_EQ(scene.solids[0].elastic.lattice_spacing, 0.02);
  const std::vector<Vec3> rest = scene.particles.positions;
  Vec3 v0;
  const Vec3 c0 = centerOfMass(scene.particles, &v0);
  SphFluidSolver solver = makeSphSolver(scene);
  std::vector<double> height, rise_speed;
  double worst_shape = 0.0;  // max change of a particle's distance to the centre of mass, in spacings
  SphRunOptions options;
  options.on_frame = [&](const SphFrameReport&) {
    Vec3 v;
    const Vec3 c = centerOfMass(solver.particles(), &v);
    height.push_back(c.y());
    rise_speed.push_back(v.y());
    for (size_t i = 0; i < rest.size(); ++i)
      worst_shape = std::max(
          worst_shape, std::abs((solver.particles().positions[i] - c).norm() - (rest[i] - c0).norm()) / 0.02);
  };
  const SphRunStats stats = runSphScene(scene, solver, options);
  std::printf(
      "elastic cube: %llu steps, mean dt %.3g, max strain %.3g, shape change %.3g dx, elastic energy %.3g, "
      "energy change %.3g\n",
      (unsigned long long)stats.steps, stats.mean_dt, stats.max_strain, worst_shape, stats.elastic_energy,
      stats.energy_change);
  for (size_t f = 0; f < height.size(); ++f)
    std::printf("  frame %zu: y %.4f  vy %.3f\n", f + 1, height[f], rise_speed[f]);
  EXPECT_TRUE(stats.instability.empty()) << stats.instability;
  ASSERT_EQ(stats.frames, 20);
  EXPECT_EQ(stats.solids, 1u);
  EXPECT_EQ(stats.solid_particles, 115u);
  EXPECT_EQ(stats.fluid_particles, 0u);
  EXPECT_GT(stats.steps, 200u);
  EXPECT_LT(stats.steps, 1000u);
  // The first bounce: the frame at which the centre of mass rises again.
  const size_t turn =
      std::find_if(rise_speed.begin(), rise_speed.end(), [](double v) { return v > 0; }) - rise_speed.begin();
  ASSERT_GT(turn, 0u);
  ASSERT_LT(turn, rise_speed.size());
  const double lowest = *std::min_element(height.begin(), height.begin() + turn + 1);
  const double top = *std::max_element(height.begin() + turn, height.end());
  const double fastest_up = *std::max_element(rise_speed.begin() + turn, rise_speed.end());
  EXPECT_LT(lowest, c0.y() - 0.04);   // it fell 3 cm onto the floor and was squashed
  EXPECT_GT(fastest_up, 0.3);         // it bounced ...
  EXPECT_GT(top, lowest + 0.015);     // ... up from the floor
  EXPECT_LT(top, c0.y() - 0.01);      // but not back to where it started
  EXPECT_GT(stats.max_strain, 0.05);  // the impact deforms it ...
  EXPECT_LT(stats.max_strain, 0.3);   // ... elastically: no particle leaves its neighbourhood
  EXPECT_LT(worst_shape, 1.0);
  EXPECT_LT(stats.energy_change, 0.0);  // plane hits and XSPH dissipate; nothing adds energy
  EXPECT_TRUE(std::isfinite(stats.elastic_energy));
  EXPECT_GE(stats.elastic_energy, 0.0);
  const std::string json = sphRunStatsJson(stats);
  EXPECT_NE(json.find("\"elastic_energy\":"), std::string::npos) << json;
  EXPECT_NE(json.find("\"solids\":1,"), std::string::npos) << json;
}

TEST(SphSceneFile, CollisionsNeedElasticityTwoSolidsAndAContactWithinH) {
  const std::string head = "dimension: 2\nspacing: 0.02\nsolver: {smoothing_ratio: 2}\n";  // lines 1-3
  const std::string two =
      "solids:\n"                                            // 5
      "  - {lo: [0, 0], hi: [0.1, 0.1]}\n"                   // 6
      "  - {lo: [0.2, 0], hi: [0.3, 0.1], spacing: 0.03}\n"  // 7
      "frames: {count: 1, time: 0.01}\n";                    // 8
  const SphScene ok = parseSphScene(head + "enable: [elasticity, collisions]\n" + two, "ok.yaml");
  EXPECT_TRUE(ok.collisions.enabled);
  EXPECT_EQ(ok.collisions.config.contact_distance, 0.02);  // the smallest lattice spacing
  EXPECT_EQ(makeSphSolver(ok).forceTerms().size(), 3u);
  const SphScene given = parseSphScene(
      head + "enable: [elasticity, collisions]\n" + two + "collisions: {stiffness: 5.0e4, damping: 2}\n",
      "ok.yaml");
  EXPECT_EQ(given.collisions.config.stiffness, 5.0e4);
  EXPECT_EQ(given.collisions.config.damping, 2.0);
  expectErrorAt(head + "enable: [collisions]\n" + two, 4, "'collisions' needs 'elasticity'");
  expectErrorAt(head + "enable: [elasticity]\n" + two + "collisions: {stiffness: 1}\n", 9,
                "needs 'collisions' in the scene's 'enable' list");
  expectErrorAt(head + "enable: [elasticity, collisions]\nsolids:\n  - {lo: [0, 0], hi: [0.1, 0.1]}\n" +
                    "frames: {count: 1, time: 0.01}\ncollisions: {stiffness: 1}\n",
                8, "need two or more solids");
  expectErrorAt(head + "enable: [elasticity, collisions]\n" + two + "collisions: {contact_distance: 0.05}\n",
                9, "exceeds the smoothing length");
  expectErrorAt(head + "enable: [elasticity, collisions]\n" + two + "collisions: {stiffness: -1}\n", 9,
                "stiffness");
}

TEST(SphSceneFile, ImplicitGoalAndContactSpringsAreSceneKeys) {
  const std::string head =
      "dimension: 2\nspacing: 0.02\nsolver: {smoothing_ratio: 2}\nenable: [elasticity, collisions]\n";
  const std::string tail = "frames: {count: 1, time: 0.01}\n";
  const SphScene scene = parseSphScene(head +
                                           "solids:\n"
                                           "  - {lo: [0, 0], hi: [0.1, 0.1], implicit_goal: true, "
                                           "implicit_step_factor: 4, implicit_tolerance: 0.01}\n"
                                           "  - {lo: [0.2, 0], hi: [0.3, 0.1]}\n" +
                                           tail + "collisions: {implicit: true}\n",
                                       "implicit.yaml");
  EXPECT_EQ(scene.solids[0].elastic.implicit_tolerance, 0.01);
  EXPECT_EQ(scene.solids[1].elastic.implicit_tolerance, 1e-4);  // the default
  EXPECT_TRUE(scene.solids[0].elastic.implicit_goal);
  EXPECT_EQ(scene.solids[0].elastic.implicit_step_factor, 4.0);
  EXPECT_FALSE(scene.solids[1].elastic.implicit_goal);  // off unless asked for
  EXPECT_EQ(scene.solids[1].elastic.implicit_step_factor, 0.0);
  EXPECT_TRUE(scene.collisions.config.implicit);
  EXPECT_TRUE(scene.collisions.config.couple_global_implicit);  // on unless switched off
  const SphScene uncoupled =
      parseSphScene(head +
                        "solids:\n"
                        "  - {lo: [0, 0], hi: [0.1, 0.1]}\n"
                        "  - {lo: [0.2, 0], hi: [0.3, 0.1]}\n" +
                        tail + "collisions: {implicit: true, couple_global_implicit: false}\n",
                    "uncoupled.yaml");
  EXPECT_FALSE(uncoupled.collisions.config.couple_global_implicit);
  expectErrorAt(head +
                    "solids:\n"
                    "  - {lo: [0, 0], hi: [0.1, 0.1], model: strain, implicit_goal: true}\n"
                    "  - {lo: [0.2, 0], hi: [0.3, 0.1]}\n" +
                    tail,
                6, "applies to model goal_position");
  expectErrorAt(head +
                    "solids:\n"
                    "  - {lo: [0, 0], hi: [0.1, 0.1], implicit_step_factor: -1}\n"
                    "  - {lo: [0.2, 0], hi: [0.3, 0.1]}\n" +
                    tail,
                6, "implicit_step_factor");
  for (const char* bad : {"0", "1", "-0.1"})
    expectErrorAt(head +
                      "solids:\n"
                      "  - {lo: [0, 0], hi: [0.1, 0.1], implicit_tolerance: " +
                      bad +
                      "}\n"
                      "  - {lo: [0.2, 0], hi: [0.3, 0.1]}\n" +
                      tail,
                  6, "implicit_tolerance");
}

TEST(SphSceneFile, DiceAreNineSeparateStiffSolidsAndWriteSurfaces) {
  SphScene scene = loadSphScene(kSceneDir + "dice_3d.yaml");
  ASSERT_EQ(scene.solids.size(), 9u);
  std::set<int> phases;
  const SphParticles& p = scene.particles;
  for (const SphSceneSolid& die : scene.solids) {
    EXPECT_EQ(die.count, 249u);
    EXPECT_EQ(die.elastic.model, SphElasticModel::kGoalPosition);
    EXPECT_EQ(die.elastic.goal_stiffness, 2.4e7);   // appendix F.2
    EXPECT_TRUE(die.elastic.global_implicit_goal);  // dt up to 30x the explicit limit
    EXPECT_EQ(die.elastic.implicit_step_factor, 30.0);
    EXPECT_NEAR((die.orientation.transpose() * die.orientation - Eigen::Matrix3d::Identity()).norm(), 0.0,
                1e-14);
    phases.insert(die.phase);
    for (size_t i = die.first; i < die.first + die.count; ++i) ASSERT_EQ(p.phases[i], die.phase);
  }
  EXPECT_EQ(phases.size(), 9u);
  // Thesis 8.2.6 / Fig. 8.8: penalty collisions (8.37) between the dice.
  EXPECT_TRUE(scene.collisions.enabled);
  EXPECT_EQ(scene.collisions.config.stiffness, 1.0e7);
  EXPECT_EQ(scene.collisions.config.contact_distance, 0.07);
  EXPECT_TRUE(scene.collisions.config.implicit);
  // No two dice overlap at the start: particles of different dice are more than a spacing apart, and all lie
  // above the floor.
  double closest = 1e9;
  for (size_t i = 0; i < p.size(); ++i) {
    EXPECT_GT(p.positions[i].y(), 0.0);
    for (size_t j = i + 1; j < p.size(); ++j)
      if (p.phases[i] != p.phases[j]) closest = std::min(closest, (p.positions[i] - p.positions[j]).norm());
  }
  EXPECT_GT(closest, 0.07);
  EXPECT_TRUE(scene.surface.enabled);
  EXPECT_EQ(scene.surface.every, 2);
  EXPECT_TRUE(scene.surface.obj && !scene.surface.ply);
  EXPECT_EQ(scene.surface.config.cell_size, 0.035);
  EXPECT_EQ(scene.surface.config.smoothing_length, 0.14);
  // Two short frames at the capped step 30 x 0.4 sqrt(2 / K_e): stable, the dice hardly deform; the surface
  // is written for frame 0 only (every 2).
  scene.frame_count = 2;
  scene.frame_time = 0.01;
  const fs::path dir = tempDir("dice");
  SphFluidSolver solver = makeSphSolver(scene);
  SphRunOptions options;
  options.out_dir = dir.string();
  const SphRunStats stats = runSphScene(scene, solver, options);
  EXPECT_TRUE(stats.instability.empty()) << stats.instability;
  EXPECT_EQ(stats.solids, 9u);
  EXPECT_EQ(stats.solid_particles, 9u * 249u);
  const double cap = 30.0 * 0.4 * std::sqrt(2.0 / 2.4e7);  // 3.46e-3 s: 3 steps per frame, the last shorter
  EXPECT_EQ(stats.steps, 6u);
  EXPECT_NEAR(stats.min_dt, cap, 1e-12);  // the shortened last steps not counted
  EXPECT_LT(stats.max_strain, 0.01);
  EXPECT_TRUE(fs::exists(dir / "dice_3d_surface_0000.obj"));
  EXPECT_FALSE(fs::exists(dir / "dice_3d_surface_0001.obj"));
  EXPECT_TRUE(fs::exists(dir / "dice_3d_surface_0002.obj"));
  EXPECT_TRUE(fs::exists(dir / "dice_3d_0001.vtp"));
  // Each die's cube skin (8.38), 4 x 4 quads per face, every second frame like the surface.
  ASSERT_EQ(scene.skins.size(), 9u);
  for (size_t k = 0; k < 9; ++k) {
    EXPECT_EQ(scene.skins[k].solid, k);
    EXPECT_EQ(scene.skins[k].every, 2);
    EXPECT_EQ(scene.skins[k].rest.vertices.size(), 6u * 16u + 2u);
    EXPECT_EQ(scene.skins[k].skin.orphanCount(), 0u);
    EXPECT_TRUE(fs::exists(dir / ("dice_3d_skin" + std::to_string(k) + "_0002.obj")));
  }
  EXPECT_FALSE(fs::exists(dir / "dice_3d_skin0_0001.obj"));
  EXPECT_EQ(stats.files.size(), 3u + 1u + 2u + 2u * 9u);  // 3 vtp, the pvd, 2 surfaces, 2 x 9 skins
  // The surface is closed (every edge in two triangles) and encloses the dice.
  const TriangleMesh mesh = readObjMesh((dir / "dice_3d_surface_0002.obj").string());
  ASSERT_GT(mesh.triangles.size(), 1000u);
  EXPECT_EQ(openEdges(mesh), 0u);
  double lowest = 1e9;
  for (const Vec3& x : mesh.vertices.positions) lowest = std::min(lowest, x.y());
  EXPECT_LT(lowest, 0.11);
  EXPECT_GT(lowest, -0.07);
}

}  // namespace
}  // namespace rc
