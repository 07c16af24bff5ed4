// Static analysis from scene files (analysis: static, held regions with any components, loads, a body force):
// uniaxial stress from rollers reproduced exactly with its reactions; a cantilever's tip deflection against
// Timoshenko beam theory; the reaction of a column under its own weight equals the weight; bad keys named.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "fem_scene_test_support.h"
#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/fem/fem_scene_run.h"
#include "relaxed_connectivity/fem/fem_static.h"

namespace rc {
namespace {

const char* kRollers =
    "name: rollers\n"
    "analysis: static\n"
    "material: {youngs_modulus: 1000, poisson_ratio: 0.3}\n"
    "mesh: {type: hex_grid, lo: [0, 0, 0], hi: [2, 1, 1.5], cells: [4, 3, 3]}\n"
    "held:\n"
    "  - {lo: [0, 0, 0], hi: [0, 1, 1.5], components: x}\n"
    "  - {lo: [0, 0, 0], hi: [2, 0, 1.5], components: y}\n"
    "  - {lo: [0, 0, 0], hi: [2, 1, 0], components: z}\n"
    "  - {lo: [2, 0, 0], hi: [2, 1, 1.5], components: x, displacement: [0.002, 0, 0]}\n";

TEST(FemStaticScene, RollersGiveUniaxialStressWithItsReactions) {
  const FemScene scene = parseFemScene(kRollers, "rollers.yaml", ".");
  ASSERT_EQ(scene.analysis, FemAnalysis::kStatic);
  ASSERT_EQ(scene.held.size(), 4u);
  EXPECT_EQ(scene.held[0].nodes.size(), 4u * 4u);  // the x = 0 face of the 5 x 4 x 4 nodes
  const FemRunStats stats = runFemScene(scene);
  ASSERT_TRUE(stats.error.empty()) << stats.error;
  // u = (1e-3 x, -0.3e-3 y, -0.3e-3 z): the corner (2, 1, 1.5) moves farthest.
  EXPECT_NEAR(stats.max_displacement, std::hypot(2e-3, 0.3e-3, 0.45e-3), 1e-15);
  ASSERT_EQ(stats.held_reactions.size(), 4u);
  EXPECT_NEAR(stats.held_reactions[3].x(), 1000 * 1e-3 * 1.5, 1e-10);  // E strain A
  EXPECT_NEAR(stats.held_reactions[0].x(), -1.5, 1e-10);
  EXPECT_NEAR(stats.held_reactions[1].y(), 0, 1e-10);  // symmetry planes carry no load
  EXPECT_NE(femRunStatsJson(stats).find("\"analysis\":\"static\",\"max_displacement\":"), std::string::npos);
  // The dynamics stepper (the fem_sim node) refuses a static scene instead of ignoring its held regions.
  EXPECT_THROW(FemSimulation simulation(scene), std::invalid_argument);
}

TEST(FemStaticScene, CantileverTipFollowsTimoshenko) {
  // L = 10, h = b = 1, E = 1000, nu = 0, tip force 0.01 down over the end face: Euler-Bernoulli F L^3 / (3 E
  // I) = 0.04, plus shear F L / (kappa G A) = 2.4e-4 (kappa = 5/6).
  const double exact = 0.01 * 1000 / (3 * 1000 / 12.0) + 0.01 * 10 / (5.0 / 6 * 500 * 1);
  double previous_error = 1;
  for (int n : {2, 4}) {
    const std::string text =
        "analysis: static\nmaterial: {youngs_modulus: 1000, poisson_ratio: 0, "
        "vertex_sample_blend: 0.5, face_sample_blend: 0.5}\n"
        "mesh: {type: hex_grid, lo: [0, 0, 0], hi: [10, 1, 1], cells: [" +
        std::to_string(10 * n) + ", " + std::to_string(n) + ", " + std::to_string(n) +
        "]}\nheld:\n  - {lo: [0, 0, 0], hi: [0, 1, 1]}\n"
        "loads:\n  - {lo: [10, 0, 0], hi: [10, 1, 1], force: [0, -0.01, 0]}\n";
    const FemStaticResult result = solveFemStatic(parseFemScene(text, "cantilever.yaml", "."));
    const double tip = -result.load_displacements[0].y(), error = std::abs(tip - exact) / exact;
    std::printf(
        "cantilever %d x %d x %d hexahedra: tip %.5f (Timoshenko %.5f), error %.2f %%, reaction %.4f\n",
        10 * n, n, n, tip, exact, 100 * error, result.held_reactions[0].y());
    EXPECT_NEAR(result.held_reactions[0].y(), 0.01, 1e-12);  // the wall carries the tip force
    EXPECT_LT(error, previous_error);                        // converges
    previous_error = error;
  }
  // Measured 3.71 % at 20 x 2 x 2 and 1.02 % at 40 x 4 x 4 (sample blends 0.5 / 0.5; the tip force spread
  // equally over the end face's nodes).
  EXPECT_LT(previous_error, 0.02);
}

TEST(FemStaticScene, AColumnCarriesItsWeight) {
  const FemScene scene = parseFemScene(
      "analysis: static\nmaterial: {youngs_modulus: 1e5, poisson_ratio: 0.25, density: 2}\n"
      "mesh: {type: tet_grid, lo: [0, 0, 0], hi: [1, 1, 3], cells: [2, 2, 6]}\n"
      "held:\n  - {lo: [0, 0, 0], hi: [1, 1, 0]}\nbody_acceleration: [0, 0, -9.81]\n",
      "column.yaml", ".");
  const FemStaticResult result = solveFemStatic(scene);
  EXPECT_NEAR(result.held_reactions[0].z(), 2 * 3 * 9.81, 1e-9);  // rho V g, up
  EXPECT_NEAR(result.held_reactions[0].x(), 0, 1e-9);
}

TEST(FemStaticScene, BadKeysAreNamed) {
  const std::string head =
      "material: {youngs_modulus: 1000, poisson_ratio: 0.3}\n"
      "mesh: {type: hex_grid, lo: [0, 0, 0], hi: [1, 1, 1], cells: [1, 1, 1]}\n";
  expectFemSceneErrorAt(
      head + "dynamics: {time_step: 0.01}\nframes: {count: 1}\nbody_acceleration: [0, 0, -1]\n", 5,
      "body_acceleration: only with analysis: static");
  expectFemSceneErrorAt(
      head + "analysis: static\nheld: [{lo: [0, 0, 0], hi: [1, 1, 0], path: [[0, 0, 0, 0]]}]\n", 4,
      "path: only with analysis: dynamic");
  expectFemSceneErrorAt(head +
                            "analysis: static\nheld: [{lo: [0, 0, 0], hi: [1, 1, 0]}]\n"
                            "loads: [{lo: [0, 0, 1], hi: [1, 0, 1], traction: [0, 0, 1]}]\n",
                        5, "no boundary face lies in the box");
  expectFemSceneErrorAt(
      head +
          "analysis: static\nheld: [{lo: [0, 0, 0], hi: [1, 1, 0]}]\n"
          "loads: [{lo: [0, 0, 1], hi: [1, 1, 1], traction: [0, 0, 1], force: [0, 0, 1]}]\n",
      5, "give force or traction, not both");
  expectFemSceneErrorAt(head + "analysis: static\n", 1, "needs 'held' regions");
  expectFemSceneErrorAt(head + "analysis: static\nheld: [{lo: [5, 5, 5], hi: [6, 6, 6]}]\n", 4,
                        "holds no node");
  expectFemSceneErrorAt(head + "analysis: static\nheld: [{lo: [0, 0, 0], hi: [1, 1, 0], components: xw}]\n",
                        4, "letters of xyz");
  expectFemSceneErrorAt(head +
                            "analysis: static\nheld:\n  - {lo: [0, 0, 0], hi: [1, 1, 0]}\n"
                            "  - {lo: [0, 0, 0], hi: [1, 0, 1], components: y}\n",
                        6, "already holds y");
  expectFemSceneErrorAt(head + "analysis: quasi\n", 3, "unknown 'quasi'");
  expectFemSceneErrorAt(
      head + "analysis: static\nheld: [{lo: [0, 0, 0], hi: [1, 1, 0]}]\nground: {normal: [0, 0, 1]}\n", 5,
      "only with analysis: dynamic");
  // Held regions that leave a rigid motion free: the run reports it.
  const FemRunStats free_run = runFemScene(parseFemScene(
      head + "analysis: static\nheld: [{lo: [0, 0, 0], hi: [1, 1, 0], components: z}]\n", "free.yaml", "."));
  EXPECT_NE(free_run.error.find("singular"), std::string::npos) << free_run.error;
}

}  // namespace
}  // namespace rc
