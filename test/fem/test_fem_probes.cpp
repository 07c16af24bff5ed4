// Probes of dynamic FEM scenes (key probes): a free-falling block's mass-weighted mean displacement follows
// the implicit Euler free fall exactly (internal forces cancel: the centre of mass falls by g h^2 n (n + 1) /
// 2 after n steps), its momentum is M g t, a face probe holds the face's nodes; one CSV row at the start and
// per frame; bad keys named with their line.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../csv_test_support.h"
#include "fem_scene_test_support.h"
#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/fem/fem_scene_run.h"
#include "relaxed_connectivity/fem/fem_simulation.h"

namespace rc {
namespace {

const std::string kFalling =
    "name: falling\n"
    "material: {youngs_modulus: 500, poisson_ratio: 0.3, density: 2}\n"
    "mesh: {type: hex_grid, lo: [0, 0, 0], hi: [1, 0.5, 0.5], cells: [4, 2, 2]}\n"
    "dynamics: {time_step: 0.01, gravity: [0, 0, -9.81], solver: {type: ldlt}}\n"
    "frames: {count: 5, steps_per_frame: 4}\n"
    "output: {vtu: false}\n"
    "probes:\n"
    "  - {name: all, lo: [0, 0, 0], hi: [1, 0.5, 0.5]}\n"
    "  - {name: end_face, lo: [1, 0, 0], hi: [1, 0.5, 0.5]}\n";

TEST(FemProbes, AFallingBlocksMeanDisplacementIsTheDiscreteFreeFall) {
  const FemScene scene = parseFemScene(kFalling, "falling.yaml", ".");
  ASSERT_EQ(scene.probes.size(), 2u);
  const std::string dir = ::testing::TempDir() + "fem_probes";
  std::filesystem::remove_all(dir);
  FemRunOptions options;
  options.out_dir = dir;
  const FemRunStats stats = runFemScene(scene, options);
  ASSERT_TRUE(stats.error.empty()) << stats.error;
  std::ifstream csv(dir + "/falling_probes.csv");
  const auto rows = test::readCsvRows(csv);
  ASSERT_EQ(rows.size(), 1u + 6u);  // header, the start, 5 frames
  const std::vector<std::string>& header = rows[0];
  ASSERT_EQ(header.size(), 7u + 2u * 9u);
  const auto column = [&](const std::string& name) {
    for (size_t c = 0; c < header.size(); ++c)
      if (header[c] == name) return c;
    ADD_FAILURE() << "no column " << name;
    return size_t(0);
  };
  const double h = 0.01, g = 9.81, mass = 2 * 0.25;
  for (size_t r = 1; r < rows.size(); ++r) {
    const double t = std::stod(rows[r][column("time")]);
    const double n = std::round(t / h);
    EXPECT_NEAR(t, 0.04 * double(r - 1), 1e-12);
    EXPECT_NEAR(std::stod(rows[r][column("all_uz")]), -g * h * h * n * (n + 1) / 2, 1e-12) << "t " << t;
    EXPECT_NEAR(std::stod(rows[r][column("all_ux")]), 0.0, 1e-12);
    EXPECT_NEAR(std::stod(rows[r][column("momentum_z")]), -mass * g * t, 1e-9);
    EXPECT_NEAR(std::stod(rows[r][column("all_mass")]), mass, 1e-12);
    EXPECT_EQ(rows[r][column("all_nodes")], "45");                   // 5 x 3 x 3
    EXPECT_EQ(rows[r][column("end_face_nodes")], "9");               // the x = 1 face
    EXPECT_LT(std::stod(rows[r][column("elastic_energy")]), 1e-20);  // falls undeformed
  }
  EXPECT_NE(std::find(stats.files.begin(), stats.files.end(), dir + "/falling_probes.csv"),
            stats.files.end());
}

TEST(FemProbes, AConstantLoadInADynamicRunGivesMomentumFt) {
  // No gravity, a total force of 0.3 along y on the end face (loads in a dynamic run: constant nodal forces):
  // internal forces cancel, so the momentum is F t exactly (implicit Euler, no mass damping).
  std::string yaml = kFalling;
  yaml.replace(yaml.find("gravity: [0, 0, -9.81]"), 22, "gravity: [0, 0, 0]");
  yaml.replace(yaml.find("name: falling"), 13, "name: pushed");
  yaml += "loads:\n  - {lo: [1, 0, 0], hi: [1, 0.5, 0.5], force: [0, 0.3, 0]}\n";
  const FemScene scene = parseFemScene(yaml, "pushed.yaml", ".");
  ASSERT_EQ(scene.loads.size(), 1u);
  const auto rows = runFemSceneProbes(scene, "fem_probes_pushed");
  ASSERT_EQ(rows.size(), 1u + 6u);
  const auto column = [&](const std::string& name) {
    for (size_t c = 0; c < rows[0].size(); ++c)
      if (rows[0][c] == name) return c;
    ADD_FAILURE() << "no column " << name;
    return size_t(0);
  };
  for (size_t r = 1; r < rows.size(); ++r) {
    const double t = std::stod(rows[r][column("time")]);
    EXPECT_NEAR(std::stod(rows[r][column("momentum_y")]), 0.3 * t, 1e-9) << t;
    EXPECT_NEAR(std::stod(rows[r][column("momentum_z")]), 0.0, 1e-12);
  }
  EXPECT_GT(std::stod(rows.back()[column("end_face_uy")]),
            std::stod(rows.back()[column("all_uy")]));  // pulled end leads
}

TEST(FemProbes, LoadsSetWhileRunning) {
  // FemSimulation::setLoads (what fem_sim's ~load calls): the count of nodes per load, non-finite loads
  // refused (nothing changes), and clearing the loads stops the push (momentum constant after).
  std::string yaml = kFalling;
  yaml.replace(yaml.find("gravity: [0, 0, -9.81]"), 22, "gravity: [0, 0, 0]");
  FemSimulation sim(parseFemScene(yaml, "free.yaml", "."));
  FemLoad push;
  push.lo = Vec3(1, 0, 0), push.hi = Vec3(1, 0.5, 0.5), push.force = Vec3(0.2, 0, 0);
  FemLoad nowhere = push;
  nowhere.lo = Vec3(5, 5, 5), nowhere.hi = Vec3(6, 6, 6);
  EXPECT_EQ(sim.setLoads({push, nowhere}), (std::vector<size_t>{9, 0}));  // the end face's 3 x 3 nodes
  FemLoad bad = push;
  bad.force.x() = std::nan("");
  EXPECT_THROW(sim.setLoads({bad}), std::invalid_argument);
  EXPECT_EQ(sim.scene().loads.size(), 2u);
  auto momentum_x = [&] {
    double p = 0;
    for (int b = 0; b < sim.numBodies(); ++b) p += sim.body(b).linearMomentum().x();
    return p;
  };
  for (int s = 0; s < 5; ++s) sim.step();
  EXPECT_NEAR(momentum_x(), 0.2 * 0.05, 1e-9);
  sim.setLoads({});
  for (int s = 0; s < 5; ++s) sim.step();
  EXPECT_NEAR(momentum_x(), 0.2 * 0.05, 1e-9);  // no force since
}

TEST(FemProbes, BadProbesAreNamedWithTheirLine) {
  const std::string head = kFalling.substr(0, kFalling.find("probes:"));  // 6 lines
  expectFemSceneErrorAt(head + "probes:\n  - {name: a, lo: [5, 5, 5], hi: [6, 6, 6]}\n", 8, "holds no node");
  expectFemSceneErrorAt(head + "probes:\n  - {name: a b, lo: [0, 0, 0], hi: [1, 1, 1]}\n", 8,
                        "letters, digits");
  expectFemSceneErrorAt(head +
                            "probes:\n  - {name: a, lo: [0, 0, 0], hi: [1, 1, 1]}\n  - {name: a, lo: [0, 0, "
                            "0], hi: [1, 1, 1]}\n",
                        9, "is taken");
  expectFemSceneErrorAt(head + "probes:\n  - {lo: [0, 0, 0], hi: [1, 1, 1]}\n", 8, "name");
  expectFemSceneErrorAt(
      "analysis: static\nmaterial: {youngs_modulus: 1, poisson_ratio: 0}\n"
      "mesh: {type: hex_grid, lo: [0, 0, 0], hi: [1, 1, 1], cells: [1, 1, 1]}\n"
      "held:\n  - {lo: [0, 0, 0], hi: [0, 1, 1]}\nprobes:\n  - {name: a, lo: [0, 0, 0], hi: [1, 1, 1]}\n",
      7, "only with analysis: dynamic");
}

}  // namespace
}  // namespace rc
