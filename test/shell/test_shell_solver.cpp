// Thin-shell dynamics (thesis 7.2.2): momentum, the stable step law, instability detection, determinism,
// pinned nodes and the ground plane.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <random>

#include "relaxed_connectivity/shell/shell_solver.h"
#include "shell_test_support.h"

namespace rc {
namespace {

using shell_test::sheetNodes;
using shell_test::sphereNodes;
using shell_test::wobble;

ShellMaterial material(double ks, double kb) {
  ShellMaterial m;
  m.stretch_stiffness = ks;
  m.bending_stiffness = kb;
  return m;
}

std::vector<Vec3> randomVelocities(size_t n, double scale, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> d(0.0, scale);
  std::vector<Vec3> v(n);
  for (Vec3& p : v) p = Vec3(d(rng), d(rng), d(rng));
  return v;
}

TEST(ShellSolver, ConservesMomentumWithoutExternalForces) {
  ShellSolver solver(sphereNodes(0.3, 6000), material(10.0, 1.0), ShellSolverOptions());
  solver.setPositions(wobble(solver.nodes().rest_positions, 0.03));
  solver.setVelocities(randomVelocities(solver.nodes().size(), 0.1, 3));
  const std::vector<double>& m = solver.energy().masses();
  auto momenta = [&](Vec3* p, Vec3* l) {
    p->setZero(), l->setZero();
    for (size_t i = 0; i < m.size(); ++i) {
      *p += m[i] * solver.velocities()[i];
      *l += m[i] * solver.positions()[i].cross(solver.velocities()[i]);
    }
  };
  Vec3 p0, l0, p1, l1;
  momenta(&p0, &l0);
  ShellStepReport first = solver.step(), last;
  for (int s = 0; s < 300; ++s) last = solver.step();
  momenta(&p1, &l1);
  const double e0 = first.kinetic + first.elastic.total(), e1 = last.kinetic + last.elastic.total();
  std::printf("300 steps dt %.3e: |dP| %.2e (|P| %.2e), |dL| %.2e (|L| %.2e), energy %.5e -> %.5e\n", last.dt,
              (p1 - p0).norm(), p0.norm(), (l1 - l0).norm(), l0.norm(), e0, e1);
  EXPECT_LT((p1 - p0).norm(), 1e-12 * (1.0 + p0.norm()));
  EXPECT_LT((l1 - l0).norm(), 1e-10 * (1.0 + l0.norm()));
  EXPECT_NEAR(e1, e0, 0.02 * e0);
}

// Largest eigenvalue of M^-1 H at rest by power iteration with finite-difference Hessian products.
double largestSquaredFrequency(const ShellEnergy& energy) {
  const std::vector<Vec3>& x0 = energy.nodes().rest_positions;
  std::vector<Vec3> v = randomVelocities(x0.size(), 1.0, 11), xp(x0.size()), xm(x0.size()), gp, gm;
  double lambda = 0.0;
  for (int it = 0; it < 300; ++it) {
    double norm = 0.0;
    for (const Vec3& p : v) norm += p.squaredNorm();
    norm = std::sqrt(norm);
    const double eps = 1e-6;
    for (size_t i = 0; i < v.size(); ++i)
      v[i] /= norm, xp[i] = x0[i] + eps * v[i], xm[i] = x0[i] - eps * v[i];
    energy.evaluate(xp, &gp);
    energy.evaluate(xm, &gm);
    double dot = 0.0;
    for (size_t i = 0; i < v.size(); ++i) {
      const Vec3 w = (gp[i] - gm[i]) / (2 * eps * energy.masses()[i]);
      dot += w.dot(v[i]);
      v[i] = w;
    }
    lambda = dot;
  }
  return lambda;
}

TEST(ShellSolver, StableStepScalesLinearlyForMembraneAndQuadraticallyForBending) {
  double bound[2][2], exact[2][2], h[2];  // [membrane, bending][h, h/2]
  const double spacing[2] = {0.1, 0.05};
  for (int d = 0; d < 2; ++d) {
    const ShellNodes nodes = sheetNodes(1.0, spacing[d], 150);
    h[d] = nodes.spacing;
    const ShellFibers fibers = buildShellFibers(nodes);
    for (int kind = 0; kind < 2; ++kind) {
      ShellEnergy energy(nodes, fibers, kind == 0 ? material(1.0, 0.0) : material(0.0, 1.0));
      const ShellStableStep st = energy.stableStep(nodes.rest_positions);
      bound[kind][d] = kind == 0 ? st.membrane : st.bending;
      exact[kind][d] = 2.0 / std::sqrt(largestSquaredFrequency(energy));
      EXPECT_LE(bound[kind][d], exact[kind][d] * 1.0001) << "the bound must be a safe step";
    }
    std::printf("h=%.3f: membrane step bound %.4e exact %.4e, bending step bound %.4e exact %.4e\n",
                nodes.spacing, bound[0][d], exact[0][d], bound[1][d], exact[1][d]);
  }
  auto order = [&](const double* v) { return std::log(v[0] / v[1]) / std::log(h[0] / h[1]); };
  const double mem_order = order(exact[0]), bend_order = order(exact[1]);
  const double mem_bound_order = order(bound[0]), bend_bound_order = order(bound[1]);
  std::printf("step order in h: membrane %.2f (bound %.2f), bending %.2f (bound %.2f)\n", mem_order,
              mem_bound_order, bend_order, bend_bound_order);
  EXPECT_NEAR(mem_order, 1.0, 0.25);
  EXPECT_NEAR(bend_order, 2.0, 0.25);
  EXPECT_NEAR(mem_bound_order, 1.0, 0.25);
  EXPECT_NEAR(bend_bound_order, 2.0, 0.25);
}

TEST(ShellSolver, TooLargeStepIsReportedWithStepAndCause) {
  ShellSolverOptions options;
  {
    ShellSolver probe(sphereNodes(0.3, 6000), material(10.0, 1.0), options);
    options.time_step = 4.0 * probe.energy().stableStep(probe.nodes().rest_positions).combined;
  }
  ShellSolver solver(sphereNodes(0.3, 6000), material(10.0, 1.0), options);
  solver.setPositions(wobble(solver.nodes().rest_positions, 0.02));
  size_t failed_at = 0;
  std::string cause;
  try {
    for (int s = 0; s < 2000; ++s) solver.step();
  } catch (const ShellInstabilityError& e) {
    failed_at = e.step();
    cause = e.what();
  }
  std::printf("4x stable step: %s\n", cause.c_str());
  EXPECT_GT(failed_at, 0u);
  EXPECT_NE(cause.find("step " + std::to_string(failed_at)), std::string::npos);
  EXPECT_TRUE(cause.find("blow-up") != std::string::npos || cause.find("non-finite") != std::string::npos);

  // The automatic step stays stable over the same span.
  ShellSolver stable(sphereNodes(0.3, 6000), material(10.0, 1.0), ShellSolverOptions());
  stable.setPositions(wobble(stable.nodes().rest_positions, 0.02));
  EXPECT_NO_THROW(for (int s = 0; s < 300; ++s) stable.step());
}

TEST(ShellSolver, DeterministicForAnyThreadCount) {
  const ShellNodes nodes = sheetNodes(1.0, 0.019, 260);
  ASSERT_GE(nodes.size(), 2048u) << "large enough for the parallel loops";
  std::vector<Vec3> result[2];
  for (int t = 0; t < 2; ++t) {
    omp_set_num_threads(t + 1);
    ShellSolverOptions options;
    options.gravity = Vec3(0, 0, -9.81);
    ShellSolver solver(nodes, material(100.0, 0.1), options);
    solver.setPositions(wobble(nodes.rest_positions, 0.002));
    for (int s = 0; s < 5; ++s) solver.step();
    result[t] = solver.positions();
  }
  for (size_t i = 0; i < nodes.size(); ++i) ASSERT_EQ(result[0][i], result[1][i]) << "node " << i;
}

TEST(ShellSolver, PinnedNodesHoldAndTheGroundStopsTheFall) {
  ShellSolverOptions options;
  options.gravity = Vec3(0, 0, -9.81);
  options.ground = true;
  options.ground_point = Vec3(0, 0, -0.3);
  ShellMaterial m = material(200.0, 0.5);
  m.damping = 2.0;
  ShellSolver solver(sheetNodes(1.0, 0.1, 100), m, options);
  const size_t pinned = 0;
  solver.pin(pinned);
  double lowest = INFINITY, t = 0.0;
  while (t < 1.5) {
    const ShellStepReport r = solver.step();
    t = r.time;
    for (const Vec3& p : solver.positions()) lowest = std::min(lowest, p.z());
  }
  double max_speed = 0.0;
  for (const Vec3& v : solver.velocities()) max_speed = std::max(max_speed, v.norm());
  std::printf("after %.2f s (%zu steps): lowest z %.4f, max speed %.3e\n", t, solver.stepCount(), lowest,
              max_speed);
  EXPECT_EQ(solver.positions()[pinned], solver.nodes().rest_positions[pinned]);
  EXPECT_GE(lowest, -0.3 - 1e-12);
  EXPECT_LT(lowest, -0.29);  // the free part reached the ground
}

TEST(ShellSolver, RejectsBadOptions) {
  ShellSolverOptions options;
  options.step_safety = 1.5;
  EXPECT_THROW(ShellSolver(sphereNodes(0.3, 6000), material(1.0, 1.0), options), std::invalid_argument);
  SurfelCloud no_normals;
  no_normals.positions.push_back(Vec3::Zero());
  ShellNodeOptions node_options;
  node_options.spacing = 0.1;
  EXPECT_THROW(selectShellNodes(no_normals, node_options), std::invalid_argument);
}

}  // namespace
}  // namespace rc
