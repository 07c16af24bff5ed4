// Probes of an SPH run (issue 22): the liquid body's measures against closed forms on a lattice block, the
// point samples inside and outside the fluid, and the scene key writing one CSV row per frame that reads back
// (the elliptical drop's second moments give its semi-axes, test_sph_elliptical_drop.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../csv_test_support.h"
#include "relaxed_connectivity/sph/sph_lattice.h"
#include "relaxed_connectivity/sph/sph_probes.h"
#include "relaxed_connectivity/sph/sph_scene_builders.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"

namespace rc {
namespace {

TEST(SphProbes, BodyMeasuresOfALatticeBlockHaveTheirClosedForms) {
  // 20 x 10 particles of spacing 0.05 on [0, 1] x [0, 0.5], moving at (2, -1), plus a solid particle and a
  // wall particle that the measures leave out.
  const SphKernels kernels(2, 0.15);
  const double dx = 0.05, mass = latticeParticleMass(kernels, 1000, dx);
  SphParticles p;
  addLatticeBox(p, Vec3(0, 0, 0), Vec3(1, 0.5, 0), dx, mass, 2);
  for (Vec3& v : p.velocities) v = Vec3(2, -1, 0);
  p.add(Vec3(5, 5, 0), Vec3(9, 9, 0), mass, SphParticleKind::kFluid);
  p.phases.back() = 1;  // a solid's
  p.add(Vec3(-5, 0, 0), Vec3::Zero(), mass, SphParticleKind::kStaticBoundary);
  const SphBodyMeasures b = measureSphBody(p);
  EXPECT_EQ(b.particles, 200u);
  EXPECT_NEAR(b.mass, 200 * mass, 1e-9 * mass);
  EXPECT_NEAR(b.kinetic_energy, 0.5 * 200 * mass * 5, 1e-9 * b.kinetic_energy);
  EXPECT_LT((b.momentum - 200 * mass * Vec3(2, -1, 0)).norm(), 1e-9 * b.mass);
  EXPECT_LT((b.centre - Vec3(0.5, 0.25, 0)).norm(), 1e-12);
  EXPECT_LT((b.lo - Vec3(0.025, 0.025, 0)).norm(), 1e-12);
  EXPECT_LT((b.hi - Vec3(0.975, 0.475, 0)).norm(), 1e-12);
  // n points spaced dx: variance dx^2 (n^2 - 1) / 12.
  EXPECT_NEAR(b.second_moments(0, 0), dx * dx * (20 * 20 - 1) / 12, 1e-12);
  EXPECT_NEAR(b.second_moments(1, 1), dx * dx * (10 * 10 - 1) / 12, 1e-12);
  EXPECT_NEAR(b.second_moments(0, 1), 0, 1e-12);
  // Point samples: the Shepard average of the particles' values; none within h outside.
  for (size_t i = 0; i < p.size(); ++i) p.densities[i] = 1000 + p.positions[i].y(), p.pressures[i] = 7;
  const SphPointSample inside = sampleSphPoint(p, kernels, Vec3(0.5, 0.25, 0));
  EXPECT_NEAR(inside.pressure, 7, 1e-9);
  EXPECT_NEAR(inside.density, 1000.25, 0.01);  // a linear field, symmetric neighbourhood
  EXPECT_TRUE(std::isnan(sampleSphPoint(p, kernels, Vec3(3, 3, 0)).density));
}

TEST(SphProbes, TheSceneKeyWritesARowPerFrame) {
  // The first step (the sound-speed limit, 4.2 ms) is longer than a frame (2 ms): it ends on the frame.
  const std::string text =
      "name: probed\ndimension: 2\nspacing: 0.05\nsolver: {smoothing_ratio: 3, gravity: [0, 0]}\n"
      "fluid:\n  - {shape: sphere, center: [0, 0], radius: 0.5, velocity: [1, 0]}\n"
      "probes:\n  points: [[0, 0], [4, 4]]\n"
      "frames: {count: 3, time: 0.002}\n";
  const SphScene scene = parseSphScene(text, "probed.yaml");
  ASSERT_TRUE(scene.probes.enabled);
  ASSERT_EQ(scene.probes.points.size(), 2u);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "rc_test_sph_probes";
  std::filesystem::remove_all(dir);
  SphFluidSolver solver = makeSphSolver(scene);
  SphRunOptions options;
  options.out_dir = dir.string();
  const SphRunStats stats = runSphScene(scene, solver, options);
  ASSERT_TRUE(stats.instability.empty()) << stats.instability;
  const std::string path = (dir / "probed_probes.csv").string();
  ASSERT_EQ(std::count(stats.files.begin(), stats.files.end(), path), 1);
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("time,particles,mass,kinetic_energy,momentum_x", 0), 0u) << header;
  EXPECT_NE(header.find(",density_1,pressure_1"), std::string::npos) << header;
  const std::vector<std::vector<std::string>> rows = test::readCsvRows(in);
  ASSERT_EQ(rows.size(), 4u);  // frame 0 and three frames
  for (size_t r = 0; r < rows.size(); ++r) {
    ASSERT_EQ(rows[r].size(), 22u + 4u);
    EXPECT_NEAR(std::stod(rows[r][0]), 0.002 * double(r), 1e-12);  // time
    EXPECT_EQ(std::stoul(rows[r][1]), scene.particles.size());     // particles
    EXPECT_NEAR(std::stod(rows[r][7]), 0.002 * double(r), 2e-4);   // centre_x drifts at 1 m/s
    if (r > 0) {
      EXPECT_NEAR(std::stod(rows[r][22]), 1000, 1);  // density at the centre (measured 1000.0)
    }
    EXPECT_EQ(rows[r][24], "nan");  // no fluid at (4, 4)
    if (r == 0) {
      EXPECT_EQ(rows[r][22], "nan");  // before the first step the particles have no density
    }
  }
  if (!HasFailure()) std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rc
