// Held degrees of freedom in the implicit warped dynamics (WarpedDynamics::setHeld / setHeldTargets): a
// damped clamped bar settles on the static solution (LinearElasticModel::solveStatic) with its reactions,
// rollers keep a plane exactly, prescribed motions are followed exactly, every solver agrees, and held nodes
// take no ground contact.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "relaxed_connectivity/fem/cholmod_solver.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace rc {
namespace {

using Solver = WarpedDynamicsOptions::Solver;

PolyhedralMesh bar() {
  return PolyhedralMesh::hexahedralGrid(Vec3(0, 0, 0), Vec3(4, 1, 1), 8, 2, 2);
}

LinearElasticModel barModel() {
  return LinearElasticModel(bar(), 1000.0, 0.3, 1.0);
}

// The dof mask holding the listed components of the nodes with x <= x_max (+ round-off).
std::vector<char> holdEnd(const PolyhedralMesh& mesh, double x_max,
                          std::array<bool, 3> components = {true, true, true}) {
  std::vector<char> mask(size_t(3 * mesh.numNodes()), 0);
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.node(i).x() <= x_max + 1e-12)
      for (int k = 0; k < 3; ++k) mask[size_t(3 * i + k)] = components[size_t(k)];
  return mask;
}

std::vector<Solver> solvers() {
  std::vector<Solver> list = {Solver::kConjugateGradient, Solver::kSimplicialLDLT};
  if (cholmodAvailable()) {
    list.push_back(Solver::kCholmod);
    list.push_back(Solver::kCholmodPcg);
  }
  return list;
}

TEST(FemHeldDynamics, DampedClampedBarSettlesOnTheStaticSolutionWithItsReactions) {
  const LinearElasticModel reference = barModel();
  const Vec3 gravity(0, 0, -9.81);
  const int n = reference.mesh().numNodes();
  Eigen::VectorXd weight(3 * n);
  double total_mass = 0.0;
  for (int i = 0; i < n; ++i) {
    weight.segment<3>(3 * i) = reference.lumpedMasses()[i] * gravity;
    total_mass += reference.lumpedMasses()[i];
  }
  std::vector<DisplacementConstraint> clamp;
  for (int i = 0; i < n; ++i)
    if (reference.mesh().node(i).x() <= 1e-12) clamp.push_back({i, Vec3::Zero(), {true, true, true}});
  const Eigen::VectorXd u_static = reference.solveStatic(weight, clamp);
  const double tip = u_static.cwiseAbs().maxCoeff();
  ASSERT_GT(tip, 0.05);  // a visible deflection

  for (Solver solver : solvers()) {
    SCOPED_TRACE(int(solver));
    WarpedDynamicsOptions options;
    options.time_step = 0.05;
    options.stiffness_warping = false;  // the linear problem solveStatic solves
    options.mass_damping = 2.0;
    options.gravity = gravity;
    options.solver = solver;
    options.cg_tolerance = 1e-12;
    WarpedDynamics sim(barModel(), options);
    sim.setHeld(holdEnd(sim.model().mesh(), 0.0));
    EXPECT_EQ(sim.numHeldDofs(), 3 * 9);
    for (int s = 0; s < 600; ++s) sim.step();
    const Eigen::VectorXd u = sim.positions() - sim.restPositions();
    EXPECT_LT((u - u_static).cwiseAbs().maxCoeff(), 1e-7 * tip);
    EXPECT_LT(sim.velocities().cwiseAbs().maxCoeff(), 1e-7);
    Vec3 reaction = Vec3::Zero();
    for (int i = 0; i < n; ++i) {
      if (sim.restPositions()[3 * i] > 1e-12) {
        EXPECT_EQ(sim.heldReactions().segment<3>(3 * i), Vec3::Zero());
        continue;
      }
      EXPECT_EQ(sim.positions().segment<3>(3 * i), sim.restPositions().segment<3>(3 * i));
      reaction += sim.heldReactions().segment<3>(3 * i);
    }
    // The clamp carries the bar's weight.
    EXPECT_NEAR(reaction.z(), -total_mass * gravity.z(), 1e-6 * total_mass * 9.81);
    EXPECT_NEAR(reaction.x(), 0.0, 1e-6 * total_mass * 9.81);
    EXPECT_NEAR(reaction.y(), 0.0, 1e-6 * total_mass * 9.81);
  }
}

TEST(FemHeldDynamics, RollersKeepAPlaneExactlyUnderLargeRotations) {
  // A thin slab spun in its plane with every node's z held: the slab stays in z = rest z to round-off while
  // it rotates (warped stiffness) and deforms.
  auto spunSlab = []() {
    WarpedDynamicsOptions options;
    options.time_step = 0.01;
    auto sim = std::make_unique<WarpedDynamics>(
        LinearElasticModel(PolyhedralMesh::hexahedralGrid(Vec3(-1, -1, 0), Vec3(1, 1, 0.1), 6, 6, 1), 200.0,
                           0.3, 1.0),
        options);
    Eigen::VectorXd v(sim->numDofs());
    for (int i = 0; i < sim->numNodes(); ++i) {
      const Vec3 r = sim->restPositions().segment<3>(3 * i);
      v.segment<3>(3 * i) = Vec3(-3.0 * r.y(), 3.0 * r.x(), 0.0) + Vec3(0.5, 0, 0) * r.x() * r.x();
    }
    sim->setVelocities(v);
    return sim;
  };
  const auto held_slab = spunSlab(), free_slab = spunSlab();
  WarpedDynamics& sim = *held_slab;
  const int n = sim.numNodes();
  // Without the rollers the fan-triangulated faces warp the slab out of its plane.
  std::vector<char> mask(size_t(3 * n), 0);
  for (int i = 0; i < n; ++i) mask[size_t(3 * i + 2)] = 1;
  sim.setHeld(mask);
  double max_offset = 0.0, free_offset = 0.0, turned = 0.0;
  for (int s = 0; s < 100; ++s) {
    sim.step();
    free_slab->step();
    for (int i = 0; i < n; ++i) {
      max_offset =
          std::max(max_offset, std::abs(sim.positions()[3 * i + 2] - sim.restPositions()[3 * i + 2]));
      free_offset =
          std::max(free_offset, std::abs(free_slab->positions()[3 * i + 2] - sim.restPositions()[3 * i + 2]));
    }
  }
  std::printf("largest out-of-plane offset: %.3g with rollers, %.3g without\n", max_offset, free_offset);
  const Vec3 corner = sim.positions().segment<3>(0);
  turned = std::atan2(corner.y(), corner.x()) - std::atan2(-1.0, -1.0);
  EXPECT_LT(max_offset, 1e-14);
  EXPECT_GT(free_offset, 1e-6);
  EXPECT_GT(std::abs(turned), 1.0);  // radians: a large rotation happened
  EXPECT_TRUE(sim.positions().allFinite());
}

TEST(FemHeldDynamics, PrescribedMotionIsFollowedAndItsReactionMatchesTheStaticOne) {
  // One end clamped, the other pulled along x by u(t) = 0.1 t / T (T = 1), then held; with damping the bar
  // settles on the static solution with the same prescribed displacement and its reactions.
  const LinearElasticModel reference = barModel();
  const int n = reference.mesh().numNodes();
  std::vector<DisplacementConstraint> constraints;
  for (int i = 0; i < n; ++i) {
    const double x = reference.mesh().node(i).x();
    if (x <= 1e-12) constraints.push_back({i, Vec3::Zero(), {true, true, true}});
    if (x >= 4.0 - 1e-12) constraints.push_back({i, Vec3(0.1, 0, 0), {true, false, false}});
  }
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(3 * n);
  const Eigen::VectorXd u_static = reference.solveStatic(zero, constraints);
  const Eigen::VectorXd r_static = reference.reactions(u_static, zero);

  for (Solver solver : solvers()) {
    SCOPED_TRACE(int(solver));
    WarpedDynamicsOptions options;
    options.time_step = 0.02;
    options.stiffness_warping = false;
    options.mass_damping = 3.0;
    options.solver = solver;
    options.cg_tolerance = 1e-12;
    WarpedDynamics sim(barModel(), options);
    std::vector<char> mask = holdEnd(sim.model().mesh(), 0.0);
    for (int i = 0; i < n; ++i)
      if (sim.restPositions()[3 * i] >= 4.0 - 1e-12) mask[size_t(3 * i)] = 1;
    sim.setHeld(mask);
    double max_miss = 0.0;
    for (int s = 0; s < 800; ++s) {
      const double t = (s + 1) * options.time_step;
      Eigen::VectorXd targets = sim.restPositions();
      for (int i = 0; i < n; ++i)
        if (sim.restPositions()[3 * i] >= 4.0 - 1e-12) targets[3 * i] += 0.1 * std::min(t, 1.0);
      sim.setHeldTargets(targets);
      sim.step();
      for (int d = 0; d < 3 * n; ++d)
        if (mask[size_t(d)]) max_miss = std::max(max_miss, std::abs(sim.positions()[d] - targets[d]));
    }
    EXPECT_LT(max_miss, 1e-14);
    const Eigen::VectorXd u = sim.positions() - sim.restPositions();
    EXPECT_LT((u - u_static).cwiseAbs().maxCoeff(), 1e-7);
    for (int d = 0; d < 3 * n; ++d)
      if (mask[size_t(d)])
        EXPECT_NEAR(sim.heldReactions()[d], r_static[d], 1e-6 * r_static.cwiseAbs().maxCoeff());
  }
}

TEST(FemHeldDynamics, ChangingTheHeldSetKeepsEverySolverOnOneTrajectory) {
  // Gravity, a ground, a clamp released after 20 steps and a roller added: the CHOLMOD-preconditioned solver
  // must refactorise on the change and follow LDLT.
  if (!cholmodAvailable()) GTEST_SKIP() << "no CHOLMOD";
  std::vector<Eigen::VectorXd> runs;
  for (Solver solver : {Solver::kSimplicialLDLT, Solver::kCholmodPcg}) {
    WarpedDynamicsOptions options;
    options.time_step = 0.01;
    options.gravity = Vec3(0, 0, -9.81);
    options.ground.enabled = true;
    options.ground.offset = -0.3;
    options.solver = solver;
    options.cg_tolerance = 1e-12;
    WarpedDynamics sim(barModel(), options);
    sim.setHeld(holdEnd(sim.model().mesh(), 0.0));
    for (int s = 0; s < 60; ++s) {
      if (s == 20) sim.setHeld(holdEnd(sim.model().mesh(), 0.5, {false, true, false}));
      sim.step();
    }
    runs.push_back(sim.positions());
  }
  EXPECT_LT((runs[0] - runs[1]).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(FemHeldDynamics, HeldNodesTakeNoGroundContact) {
  // The clamped end lies below the ground plane: it stays where it is held (no projection, no contact).
  WarpedDynamicsOptions options;
  options.time_step = 0.01;
  options.ground.enabled = true;
  options.ground.offset = 0.5;  // half the bar is below
  WarpedDynamics sim(barModel(), options);
  sim.setHeld(holdEnd(sim.model().mesh(), 0.0));
  StepStatistics stats;
  for (int s = 0; s < 5; ++s) stats = sim.step();
  for (int i = 0; i < sim.numNodes(); ++i) {
    const Vec3 rest = sim.restPositions().segment<3>(3 * i);
    if (rest.x() <= 1e-12) EXPECT_EQ(sim.positions().segment<3>(3 * i), rest);
  }
  EXPECT_GT(stats.contact_nodes, 0);  // the free nodes below the plane are in contact
  for (int i = 0; i < sim.numNodes(); ++i)
    if (sim.restPositions()[3 * i] > 1e-12) EXPECT_GE(sim.positions()[3 * i + 2], 0.5 - 1e-9);
}

TEST(FemHeldDynamics, BadMasksAndTargetsAreRefused) {
  WarpedDynamics sim(barModel());
  EXPECT_THROW(sim.setHeld(std::vector<char>(5, 1)), std::invalid_argument);
  sim.setHeld(holdEnd(sim.model().mesh(), 0.0));
  Eigen::VectorXd targets = sim.restPositions();
  targets[0] = std::nan("");
  EXPECT_THROW(sim.setHeldTargets(targets), std::invalid_argument);
  EXPECT_THROW(sim.setHeldTargets(Eigen::VectorXd::Zero(3)), std::invalid_argument);
  // A NaN at a free dof is ignored.
  targets = sim.restPositions();
  targets[3 * (sim.numNodes() - 1)] = std::nan("");
  EXPECT_NO_THROW(sim.setHeldTargets(targets));
  sim.setHeld({});
  EXPECT_EQ(sim.numHeldDofs(), 0);
}

}  // namespace
}  // namespace rc
