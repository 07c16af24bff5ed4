// The threaded assembly of the spring Laplacian (SphImplicitGoalSolver::setThreads, n >= 4096) gives bit
// for bit the serial system and solution, and a bad spring throws on any thread count.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <stdexcept>

#include "relaxed_connectivity/sph/sph_implicit_goal_solver.h"

namespace rc {
namespace {

struct RandomSystem {
  std::vector<Vec3> x, v, f0;
  std::vector<double> m;
  std::vector<std::vector<SphGoalSpring>> springs;
};

RandomSystem randomSystem(size_t n) {
  RandomSystem r;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> offset(-300, 300);
  std::uniform_real_distribution<double> u(0.1, 1.0);
  r.x.resize(n), r.v.resize(n), r.f0.resize(n), r.m.resize(n), r.springs.resize(n);
  for (size_t s = 0; s < n; ++s) {
    r.x[s] = Vec3(u(rng), u(rng), u(rng));
    r.v[s] = Vec3(u(rng), u(rng), u(rng));
    r.f0[s] = Vec3(u(rng), u(rng), u(rng));
    r.m[s] = u(rng);
    for (int k = 0; k < 30; ++k) {
      const long j = long(s) + offset(rng);
      if (j >= 0 && j < long(n) && j != long(s)) r.springs[s].push_back({uint32_t(j), u(rng)});
    }
  }
  return r;
}

TEST(SphImplicitGoalSolverThreads, ThreadedAssemblyIsBitwiseTheSerialOne) {
  const size_t n = 6000;  // above the threading threshold of 4096
  const RandomSystem r = randomSystem(n);
  std::vector<Vec3> product[2], dv[2];
  for (int threads = 1; threads <= 2; ++threads) {
    SphImplicitGoalSolver solver;
    solver.setThreads(threads);
    solver.setSystem(r.x, r.m, r.springs);
    solver.applyStiffness(r.v, product[threads - 1]);
    dv[threads - 1].assign(n, Vec3::Zero());
    const SphImplicitGoalResult result = solver.solve(r.f0, r.v, 0.01, 1e-8, 200, dv[threads - 1]);
    EXPECT_TRUE(result.converged);
  }
  EXPECT_EQ(0, std::memcmp(product[0].data(), product[1].data(), n * sizeof(Vec3)));
  EXPECT_EQ(0, std::memcmp(dv[0].data(), dv[1].data(), n * sizeof(Vec3)));
}

TEST(SphImplicitGoalSolverThreads, SpringToNoParticleThrowsOnAnyThreadCount) {
  RandomSystem r = randomSystem(6000);
  r.springs[4500].push_back({uint32_t(6005), 1.0});
  for (int threads = 1; threads <= 2; ++threads) {
    SphImplicitGoalSolver solver;
    solver.setThreads(threads);
    EXPECT_THROW(solver.setSystem(r.x, r.m, r.springs), std::invalid_argument);
  }
}

}  // namespace
}  // namespace rc
