// The thermal model on the solver's neighbour rows of the step (SphFluidSolver::neighborsCurrent) against
// its own neighbour search: the same pairs and the same temperatures.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_scene_builders.h"
#include "relaxed_connectivity/sph/sph_thermal.h"

namespace rc {
namespace {

SphFluidConfig blobConfig() {
  SphFluidConfig c;
  c.dimension = 2;
  c.smoothing_length = 2.2 * 0.02;
  c.stiffness = 1e5;
  c.viscosity = 0.5;
  c.fixed_dt = 2e-4;
  return c;
}

/// A jittered 2D block of fluid, optionally on a floor of static boundary particles.
SphParticles blob(bool with_floor) {
  const SphFluidConfig c = blobConfig();
  const double dx = 0.02;
  const SphKernels kernels(2, c.smoothing_length);
  SphParticles p;
  addLatticeBox(p, Vec3(0, 0.05, 0), Vec3(0.3, 0.3, 0), dx, latticeParticleMass(kernels, c.rest_density, dx),
                2);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (size_t i = 0; i < p.size(); ++i) {
    p.velocities[i] = 0.2 * Vec3(uni(rng), uni(rng), 0.0);
    p.positions[i] += 0.002 * Vec3(uni(rng), uni(rng), 0.0);
  }
  if (with_floor)
    for (int k = -3; k <= 18; ++k)
      for (int row = 0; row < 2; ++row)
        p.add(Vec3(k * dx, 0.03 - row * dx, 0.0), Vec3::Zero(), p.masses[0],
              SphParticleKind::kStaticBoundary);
  return p;
}

SphThermalModel makeModel(size_t n) {
  SphThermalConfig config;
  config.conductivity = 5e3;
  config.heat_capacity = 10.0;
  SphThermalModel model(config);
  model.setTemperature(0, n, 20.0);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (double& t : model.temperatures()) t = 20.0 + 80.0 * uni(rng);
  return model;
}

/// Steps two twin solvers, one model on the solver's rows and one on its own search.
void compareRowsWithOwnSearch(bool with_floor, bool expect_bitwise) {
  SphFluidSolver rows_solver(blobConfig(), blob(with_floor));
  SphFluidSolver search_solver(blobConfig(), blob(with_floor));
  const size_t n = rows_solver.particles().size();
  SphThermalModel rows_model = makeModel(n), search_model = makeModel(n);
  // A heater: the first boundary particle (or the first particle) is held hot.
  const size_t heater = with_floor ? n - 1 : 0;
  rows_model.holdTemperature({heater}, 500.0);
  search_model.holdTemperature({heater}, 500.0);
  for (int step = 0; step < 30; ++step) {
    const double dt = rows_solver.step().dt;
    search_solver.step();
    ASSERT_TRUE(rows_solver.neighborsCurrent());
    const SphThermalStats& a = rows_model.step(rows_solver, dt);
    search_model.step(search_solver.particles(), search_solver.kernels(), dt);
    const SphThermalStats& b = search_model.lastStats();
    ASSERT_EQ(a.participants, b.participants);
    ASSERT_EQ(a.pairs, b.pairs);
    ASSERT_EQ(a.substeps, b.substeps);
  }
  double max_diff = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double ta = rows_model.temperatures()[i], tb = search_model.temperatures()[i];
    if (expect_bitwise) {
      ASSERT_EQ(ta, tb) << "particle " << i;
    }
    max_diff = std::max(max_diff, std::abs(ta - tb));
  }
  EXPECT_LE(max_diff, 1e-10);
  EXPECT_GT(rows_model.lastStats().pairs, 6 * rows_model.lastStats().participants);
}

TEST(SphThermalRows, FluidOnlyMatchesOwnSearchBitForBit) {
  compareRowsWithOwnSearch(false, true);
}

TEST(SphThermalRows, WithBoundaryParticlesMatchesOwnSearch) {
  compareRowsWithOwnSearch(true, false);
}

TEST(SphThermalRows, EditedPositionsInvalidateTheRows) {
  SphFluidSolver solver(blobConfig(), blob(false));
  EXPECT_FALSE(solver.neighborsCurrent());  // no forces yet
  solver.step();
  EXPECT_TRUE(solver.neighborsCurrent());
  uint32_t count = 0;
  const size_t s = 0;
  const uint32_t* row = solver.neighborRow(s, count);
  ASSERT_GT(count, 0u);
  const std::vector<uint32_t>& order = solver.neighborGrid().order();
  const double h = solver.config().smoothing_length;
  for (uint32_t e = 0; e < count; ++e)
    EXPECT_LT((solver.particles().positions[order[row[e]]] - solver.particles().positions[order[s]]).norm(),
              h);
  solver.particles().positions[5].x() += 1e-9;
  EXPECT_FALSE(solver.neighborsCurrent());
}

}  // namespace
}  // namespace rc
