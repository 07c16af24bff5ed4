// Modal analysis from scene files (analysis: modal): a cantilever's first bending frequencies against
// Euler-Bernoulli; the two bending directions of a square section converge to each other; the modes are
// mass-orthonormal; held regions that leave a rigid motion free are reported.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "fem_scene_test_support.h"
#include "relaxed_connectivity/fem/fem_modal.h"
#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/fem/fem_scene_run.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"

namespace rc {
namespace {

#define REQUIRE_SPECTRA() \
  if (!femModalAvailable()) GTEST_SKIP() << "this build has no Spectra (libspectra-dev)"

std::string cantilever(int n, int modes) {
  return "analysis: modal\nmodes: " + std::to_string(modes) +
         "\nmaterial: {youngs_modulus: 1000, poisson_ratio: 0, density: 1, vertex_sample_blend: 0.5, "
         "face_sample_blend: 0.5}\n"
         "mesh: {type: hex_grid, lo: [0, 0, 0], hi: [10, 1, 1], cells: [" +
         std::to_string(10 * n) + ", " + std::to_string(n) + ", " + std::to_string(n) +
         "]}\nheld:\n  - {lo: [0, 0, 0], hi: [0, 1, 1]}\n";
}

TEST(FemModal, CantileverBendingFrequenciesFollowEulerBernoulli) {
  REQUIRE_SPECTRA();
  // Euler-Bernoulli: f_1 = 1.8751^2 / (2 pi) sqrt(E I / (rho A L^4)), I = 1 / 12: 0.05108 Hz (shear and
  // rotary inertia, which it neglects, lower the frequency a little at L / h = 10).
  const double beta = 1.87510407, exact = beta * beta / (2 * M_PI) * std::sqrt(1000.0 / 12 / 1e4);
  double previous_split = 1;
  for (int n : {2, 4}) {
    const FemScene scene = parseFemScene(cantilever(n, 4), "cantilever.yaml", ".");
    const FemModalResult r = solveFemModal(scene);
    ASSERT_EQ(r.frequencies.size(), 4);
    const double error = std::abs(r.frequencies[0] - exact) / exact;
    std::printf(
        "cantilever %d x %d x %d: f = %.5f %.5f %.5f %.5f Hz (Euler-Bernoulli f1 %.5f), error %.2f %%, %.2f "
        "s\n",
        10 * n, n, n, r.frequencies[0], r.frequencies[1], r.frequencies[2], r.frequencies[3], exact,
        100 * error, r.seconds);
    // Measured: f1 0.47 % and 0.53 % below Euler-Bernoulli; the two bending directions of the square section
    // split by 2.4 % and 0.6 % (the quads' triangulation is not symmetric under y <-> z) and converge.
    EXPECT_LT(error, 0.015);
    const double split = (r.frequencies[1] - r.frequencies[0]) / r.frequencies[0];
    EXPECT_LT(split, previous_split);
    previous_split = split;
    // Mass-orthonormal: phi_i^T M phi_j = delta_ij.
    const LinearElasticModel model(*scene.mesh, 1000, 0, 1, scene.quadrature);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        double dot = 0;
        for (int d = 0; d < model.numDofs(); ++d)
          dot += r.modes(d, i) * model.lumpedMasses()[d / 3] * r.modes(d, j);
        EXPECT_NEAR(dot, i == j ? 1.0 : 0.0, 1e-8) << i << " " << j;
      }
  }
  EXPECT_LT(previous_split, 0.01);
}

TEST(FemModal, SceneRunsReportFrequenciesAndRefuseFreeBodies) {
  REQUIRE_SPECTRA();
  const FemRunStats stats = runFemScene(parseFemScene(cantilever(2, 3), "cantilever.yaml", "."));
  ASSERT_TRUE(stats.error.empty()) << stats.error;
  ASSERT_EQ(stats.frequencies.size(), 3u);
  EXPECT_NE(femRunStatsJson(stats).find("\"analysis\":\"modal\",\"frequencies\":["), std::string::npos);
  // Holding only z leaves the body free to slide and turn in its plane: frequency ~0, reported.
  std::string free_body = cantilever(1, 3);
  free_body.replace(free_body.find("hi: [0, 1, 1]}"), 14, "hi: [0, 1, 1], components: z}");
  const FemRunStats free_run = runFemScene(parseFemScene(free_body, "free.yaml", "."));
  EXPECT_NE(free_run.error.find("rigid motion free"), std::string::npos) << free_run.error;
}

TEST(FemModal, BadKeysAreNamed) {
  const std::string head =
      "material: {youngs_modulus: 1000, poisson_ratio: 0.3}\n"
      "mesh: {type: hex_grid, lo: [0, 0, 0], hi: [1, 1, 1], cells: [1, 1, 1]}\n";
  expectFemSceneErrorAt(head +
                            "analysis: modal\nheld: [{lo: [0, 0, 0], hi: [1, 1, 0]}]\nloads: [{lo: [0, 0, "
                            "1], hi: [1, 1, 1], force: [1, 0, 0]}]\n",
                        5, "not with analysis: modal");
  expectFemSceneErrorAt(head + "analysis: static\nheld: [{lo: [0, 0, 0], hi: [1, 1, 0]}]\nmodes: 3\n", 5,
                        "only with analysis: modal");
  expectFemSceneErrorAt(
      head + "analysis: modal\nheld: [{lo: [0, 0, 0], hi: [1, 1, 0], displacement: [0, 0, 1]}]\n", 4,
      "not with analysis: modal");
  expectFemSceneErrorAt(head + "analysis: modal\n", 1, "analysis: modal needs 'held' regions");
}

}  // namespace
}  // namespace rc
