// Scenes with temperature and phase transitions (enable: [temperature, phase_transition], thesis 8.2.4):
// loading and errors, the melting block (Fig. 8.4) and the rod fluid freezes onto (Fig. 8.5), the per-step
// thermal hook of the scene runner and the temperature / phase fields of the particle files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"
#include "relaxed_connectivity/sph/sph_thermal.h"
#include "scene_file_test_support.h"

namespace rc {
namespace {

namespace fs = std::filesystem;

const std::string kSceneDir = sphSceneDir();

double kFluidMass(const SphParticles& p) {
  double m = 0.0;
  for (size_t i = 0; i < p.size(); ++i)
    if (p.kinds[i] == SphParticleKind::kFluid) m += p.masses[i];
  return m;
}

TEST(SphSceneThermal, ScenesLoadWithTheirThermalSetup) {
  const SphScene melt = loadSphScene(kSceneDir + "melting_block_3d.yaml");
  ASSERT_TRUE(melt.thermal.enabled);
  EXPECT_EQ(melt.particles.size(), 381u);
  ASSERT_EQ(melt.solids.size(), 1u);
  EXPECT_EQ(melt.solids[0].count, 381u);
  ASSERT_EQ(melt.thermal.planes.size(), 1u);
  EXPECT_EQ(melt.thermal.planes[0].temperature, 100.0);
  EXPECT_EQ(melt.thermal.planes[0].distance, 0.03);
  EXPECT_TRUE(melt.thermal.config.melting);
  EXPECT_FALSE(melt.thermal.config.freezing);
  EXPECT_EQ(melt.thermal.config.melting_temperature, 10.0);
  EXPECT_EQ(melt.thermal.config.rest_density, melt.config.rest_density);
  ASSERT_EQ(melt.thermal.initial.size(), 1u);
  EXPECT_EQ(melt.thermal.initial[0].count, 381u);

  const SphScene rod = loadSphScene(kSceneDir + "freezing_rod_2d.yaml");
  ASSERT_TRUE(rod.thermal.enabled);
  EXPECT_EQ(rod.particles.size(), 100u);
  ASSERT_EQ(rod.thermal.held.size(), 1u);
  EXPECT_EQ(rod.thermal.held[0].indices.size(), 36u);
  EXPECT_EQ(rod.thermal.held[0].temperature, -20.0);
  for (size_t i : rod.thermal.held[0].indices) {
    EXPECT_EQ(rod.particles.kinds[i], SphParticleKind::kStaticBoundary);
    EXPECT_EQ(rod.particles.phases[i], 1);  // the seed fluid freezes onto
  }
  ASSERT_EQ(rod.solids.size(), 1u);
  EXPECT_EQ(rod.thermal.freezing_solid, 0);
  EXPECT_EQ(rod.solids[0].count, 0u);
  EXPECT_EQ(rod.solids[0].phase, 1);
  EXPECT_EQ(rod.solids[0].elastic.goal_stiffness, 8.0e5);
  EXPECT_TRUE(rod.thermal.config.freezing);
  EXPECT_EQ(rod.thermal.config.freezing_phase, 1);
  ASSERT_EQ(rod.thermal.initial.size(), 1u);
  EXPECT_EQ(rod.thermal.initial[0].count, 64u);
  EXPECT_EQ(rod.thermal.initial[0].temperature, 20.0);
  // The model made for the run: held rod, fluid at 20, the freezing solid attached.
  SphFluidSolver solver = makeSphSolver(rod);
  const auto model = makeSphThermal(rod, solver);
  ASSERT_NE(model, nullptr);
  EXPECT_TRUE(model->isHeld(rod.thermal.held[0].indices[0]));
  EXPECT_EQ(model->temperatures()[rod.thermal.held[0].indices[0]], -20.0);
  EXPECT_EQ(model->temperatures()[0], 20.0);
  const SphScene plain = loadSphScene(kSceneDir + "elastic_cube_2d.yaml");
  SphFluidSolver plain_solver = makeSphSolver(plain);
  EXPECT_EQ(makeSphThermal(plain, plain_solver), nullptr);
}

const char* kHead =
    "dimension: 2\n"                                                    // 1
    "spacing: 0.02\n"                                                   // 2
    "solver: {smoothing_ratio: 2.0, stiffness: 20, rest_density: 1}\n"  // 3
    "fluid:\n"                                                          // 4
    "  - {lo: [0, 0], hi: [0.2, 0.2]}\n"                                // 5
    "frames: {count: 2, time: 0.01}\n";                                 // 6

TEST(SphSceneThermal, BadThermalKeysNameFileAndLine) {
  const std::string head = kHead;
  const std::string temp = head + "enable: [temperature]\n";  // line 7
  ASSERT_EQ(parseError(temp + "temperature: {conductivity: 2}\n"), "");
  expectErrorAt(head + "temperature: {conductivity: 2}\n", 7, "needs 'temperature' in the scene's 'enable'");
  expectErrorAt(temp + "temperature:\n  conductivity: -1\n", 9, "must be");
  expectErrorAt(temp + "temperature:\n  conductivty: 1\n", 9, "unknown key 'conductivty'");
  expectErrorAt(temp + "temperature:\n  heated_planes:\n    - {normal: [0, 0], distance: 0.1}\n", 10,
                "normal must be non-zero");
  expectErrorAt(temp + "temperature:\n  held:\n    - {lo: [5, 5], hi: [6, 6], temperature: 0}\n", 10,
                "no particles inside the box");
  expectErrorAt(temp + "temperature:\n  held:\n    - {lo: [0, 0], hi: [1, 1]}\n", 10,
                "missing 'temperature'");
  expectErrorAt(temp + "temperature:\n  held:\n    - {lo: [0, 0], hi: [1, 1], temperature: 0, phase: 1}\n",
                10, "needs 'phase_transition'");
  // Per-box temperatures need the entry.
  expectErrorAt(
      "dimension: 2\nspacing: 0.02\nsolver: {smoothing_ratio: 2.0, stiffness: 20}\nfluid:\n"
      "  - {lo: [0, 0], hi: [0.2, 0.2], temperature: 3}\nframes: {count: 2, time: 0.01}\n",
      5, "needs 'temperature'");
  // phase_transition needs temperature and elasticity, a block, and a solid to freeze into.
  const std::string both =
      head + "enable: [temperature, elasticity, phase_transition]\ntemperature: {}\n";  // 7-8
  expectErrorAt(head + "enable: [temperature, phase_transition]\n", 7, "needs 'elasticity'");
  expectErrorAt(both, 7, "needs a 'phase_transition' block");
  expectErrorAt(both + "phase_transition: {seed: 3}\n", 9, "give 'melting' and / or 'freezing'");
  expectErrorAt(both + "phase_transition:\n  freezing: {rate: 1, temperature: 0, phase: 2}\n", 10,
                "no solid of the scene; give its 'material'");
  expectErrorAt(both + "phase_transition:\n  freezing: {rate: -1, temperature: 0, phase: 2, material: {}}\n",
                10, "must be");
  expectErrorAt(
      both + "phase_transition:\n  freezing:\n    temperature: 0\n    phase: 2\n    material: {model: x}\n",
      13, "unknown 'x'");
  expectErrorAt(both + "phase_transition:\n  melting: {temperature: 1, phase: 4}\n", 10,
                "no solid has phase 4");
  expectErrorAt(both + "phase_transition:\n  melting: {rate: 1}\n", 10, "missing 'temperature'");
  const std::string good =
      both + "phase_transition:\n  seed: 7\n  freezing: {temperature: -1, phase: 2, material: {}}\n";
  ASSERT_EQ(parseError(good), "");
  const SphScene scene = parseSphScene(good, "good.yaml");
  EXPECT_EQ(scene.thermal.config.seed, 7u);
  EXPECT_EQ(scene.thermal.config.freezing_temperature, -1.0);
  ASSERT_EQ(scene.solids.size(), 1u);
  EXPECT_EQ(scene.solids[0].elastic.lattice_spacing, 0.02);  // the scene's spacing
}

struct MeltRun {
  SphRunStats stats;
  std::vector<uint8_t> phases;
  std::vector<Vec3> positions;
  std::vector<double> temperatures;
};

MeltRun runScene(const std::string& file, int frames, uint64_t seed, int threads) {
  SphScene scene = loadSphScene(kSceneDir + file);
  scene.frame_count = frames;
  scene.config.num_threads = threads;
  scene.thermal.config.seed = seed;
  SphFluidSolver solver = makeSphSolver(scene);
  SphRunOptions options;
  options.thermal = makeSphThermal(scene, solver);
  MeltRun run;
  run.stats = runSphScene(scene, solver, options);
  run.phases = solver.particles().phases;
  run.positions = solver.particles().positions;
  run.temperatures = options.thermal->temperatures();
  return run;
}

// Fig. 8.4: the sphere lands on the heated floor and melts from the bottom; mass is conserved exactly.
TEST(SphSceneThermal, MeltingBlockMeltsNearTheHeatedFloor) {
  const SphScene scene = loadSphScene(kSceneDir + "melting_block_3d.yaml");
  const double mass = kFluidMass(scene.particles);
  const MeltRun run = runScene("melting_block_3d.yaml", 6, 1, 0);
  ASSERT_TRUE(run.stats.instability.empty()) << run.stats.instability;
  size_t melted = 0;
  double melted_y = 0.0, all_y = 0.0;
  for (size_t i = 0; i < scene.particles.size(); ++i) {
    all_y += scene.particles.positions[i].y();
    if (run.phases[i] != 0) continue;
    ++melted;
    melted_y += scene.particles.positions[i].y();
  }
  melted_y /= double(std::max<size_t>(melted, 1));
  all_y /= double(scene.particles.size());
  std::printf(
      "melting block: %zu of %zu particles melted after %.2f s (%llu steps); mean start height of the "
      "melted %.4f m vs all %.4f m; T in [%.2f, %.2f]\n",
      melted, scene.particles.size(), run.stats.simulated_time, (unsigned long long)run.stats.steps, melted_y,
      all_y, run.stats.min_temperature, run.stats.max_temperature);
  EXPECT_EQ(run.stats.melted, melted);
  EXPECT_EQ(run.stats.frozen, 0u);
  EXPECT_GT(melted, 20u);
  EXPECT_LT(melted, scene.particles.size());
  EXPECT_LT(melted_y, all_y - 0.02);  // the bottom melts first
  // Melted particles are the hot ones and sit low; unmelted solid particles above are cooler.
  for (size_t i = 0; i < run.phases.size(); ++i)
    if (run.phases[i] == 0) {
      EXPECT_GT(run.temperatures[i], 10.0 - 1e-9);  // melted above T_m (8.35), kept warm by the floor
      EXPECT_LT(run.positions[i].y(), 0.12);
    }
  EXPECT_LE(run.stats.max_temperature, 100.0);
  EXPECT_GE(run.stats.min_temperature, 0.0);
  EXPECT_GT(run.stats.heat_end, run.stats.heat_start);  // the floor heats
  // Mass: no particle appears or disappears and masses are unchanged (exact).
  EXPECT_EQ(run.stats.mass_drift, 0.0);
  EXPECT_EQ(run.positions.size(), scene.particles.size());
  SphParticles end = scene.particles;
  end.positions = run.positions;
  EXPECT_EQ(kFluidMass(end), mass);
  // Deterministic for a fixed seed and any thread count; another seed changes the outcome.
  const MeltRun again = runScene("melting_block_3d.yaml", 6, 1, 1);
  EXPECT_EQ(again.phases, run.phases);
  EXPECT_EQ(0,
            std::memcmp(again.positions.data(), run.positions.data(), run.positions.size() * sizeof(Vec3)));
  EXPECT_EQ(again.temperatures, run.temperatures);
  const MeltRun other = runScene("melting_block_3d.yaml", 6, 2, 0);
  EXPECT_NE(other.phases, run.phases);
}

// Fig. 8.5: fluid dropped on the cooled rod freezes onto it.
TEST(SphSceneThermal, FluidFreezesOntoTheCooledRod) {
  const SphScene scene = loadSphScene(kSceneDir + "freezing_rod_2d.yaml");
  const MeltRun run = runScene("freezing_rod_2d.yaml", 15, 1, 0);
  ASSERT_TRUE(run.stats.instability.empty()) << run.stats.instability;
  const double h = scene.config.smoothing_length;
  size_t frozen = 0, fluid = 0;
  double max_distance = 0.0;
  for (size_t i = 0; i < scene.particles.size(); ++i) {
    if (scene.particles.kinds[i] != SphParticleKind::kFluid) continue;
    if (run.phases[i] == 0) {
      ++fluid;
      continue;
    }
    ASSERT_EQ(run.phases[i], 1);
    ++frozen;
    // Distance to the rod box [-0.12, 0.12] x [0.2, 0.26].
    const Vec3& x = run.positions[i];
    const double dx = std::max({-0.12 - x.x(), 0.0, x.x() - 0.12});
    const double dy = std::max({0.2 - x.y(), 0.0, x.y() - 0.26});
    max_distance = std::max(max_distance, std::hypot(dx, dy));
    EXPECT_LT(run.temperatures[i], 20.0);
  }
  std::printf(
      "freezing rod: %zu of 64 fluid particles froze after %.2f s, farthest %.4f m (%.2f h) from the "
      "rod; %zu still fluid; T in [%.2f, %.2f]\n",
      frozen, run.stats.simulated_time, max_distance, max_distance / h, fluid, run.stats.min_temperature,
      run.stats.max_temperature);
  EXPECT_EQ(run.stats.frozen, frozen);
  EXPECT_GT(frozen, 5u);
  EXPECT_GT(fluid, 0u);
  EXPECT_LT(max_distance, 3.0 * h);  // frozen onto the rod (and onto particles frozen there)
  EXPECT_EQ(run.stats.mass_drift, 0.0);
  EXPECT_GE(run.stats.min_temperature, -20.0);
  const MeltRun again = runScene("freezing_rod_2d.yaml", 15, 1, 0);
  EXPECT_EQ(again.phases, run.phases);
  EXPECT_EQ(again.temperatures, run.temperatures);
}

// The thermal hook runs after every solver step, including the shortened last step of each frame, and an
// empty hook leaves advance() bitwise unchanged.
TEST(SphSceneThermal, ThermalModelStepsWithEverySolverStep) {
  SphScene scene = loadSphScene(kSceneDir + "freezing_rod_2d.yaml");
  scene.frame_count = 3;
  scene.frame_time = 0.0101;  // not a multiple of the step: every frame ends on a shortened step
  SphFluidSolver solver = makeSphSolver(scene);
  SphRunOptions options;
  options.thermal = makeSphThermal(scene, solver);
  const SphRunStats stats = runSphScene(scene, solver, options);
  EXPECT_EQ(options.thermal->stepCount(), stats.steps);
  EXPECT_DOUBLE_EQ(stats.simulated_time, 3 * 0.0101);

  SphFluidSolver a = makeSphSolver(scene), b = makeSphSolver(scene);
  a.advance(0.0101);
  size_t calls = 0;
  double dt_sum = 0.0;
  b.advance(0.0101, [&](const SphStepStats& st) {
    ++calls;
    dt_sum += st.dt;
  });
  EXPECT_EQ(calls, b.stepCount());
  EXPECT_NEAR(dt_sum, 0.0101, 1e-15);
  EXPECT_EQ(a.time(), b.time());
  EXPECT_EQ(0, std::memcmp(a.particles().positions.data(), b.particles().positions.data(),
                           a.particles().size() * sizeof(Vec3)));
}

TEST(SphSceneThermal, ParticleFilesCarryTemperatureAndPhase) {
  SphScene scene = loadSphScene(kSceneDir + "freezing_rod_2d.yaml");
  scene.frame_count = 1;
  scene.output.ply = true;
  const fs::path dir = fs::temp_directory_path() / "rc_test_sph_scene_thermal";
  fs::remove_all(dir);
  SphFluidSolver solver = makeSphSolver(scene);
  SphRunOptions options;
  options.out_dir = dir.string();
  const SphRunStats stats = runSphScene(scene, solver, options);
  const std::string json = sphRunStatsJson(stats);
  for (const char* key : {"\"heat_start\"", "\"heat_end\"", "\"min_temperature\"", "\"max_temperature\"",
                          "\"melted\"", "\"frozen\""})
    EXPECT_NE(json.find(key), std::string::npos) << key;
  auto read = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  const std::string vtp = read(dir / "freezing_rod_2d_0001.vtp");
  EXPECT_NE(vtp.find("Name=\"temperature\""), std::string::npos);
  EXPECT_NE(vtp.find("Name=\"phase\""), std::string::npos);
  const std::string ply = read(dir / "freezing_rod_2d_0001.ply");
  EXPECT_NE(ply.find("property float temperature"), std::string::npos);
  EXPECT_NE(ply.find("property uchar phase"), std::string::npos);
  // Without temperature the files keep their fields.
  SphScene cube = loadSphScene(kSceneDir + "elastic_cube_2d.yaml");
  cube.frame_count = 1;
  SphFluidSolver cube_solver = makeSphSolver(cube);
  const SphRunStats cube_stats = runSphScene(cube, cube_solver, options);
  EXPECT_EQ(read(dir / "elastic_cube_2d_0001.vtp").find("temperature"), std::string::npos);
  EXPECT_EQ(sphRunStatsJson(cube_stats).find("heat_start"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rc
