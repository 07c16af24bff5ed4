// State carried across cuts (FemSimulation::setCarryStateAcrossCuts): bodies made by a cut start from the
// cut body's rotations (warm start of the registrations) and dv (CG warm start); the physics equals a fresh
// start up to the registration and CG tolerances. And the
// OpenBLAS thread control around CHOLMOD factorisations leaves the solutions as they are.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <memory>
#include <tuple>

#include "relaxed_connectivity/fem/cholmod_solver.h"
#include "relaxed_connectivity/fem/fem_simulation.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace rc {
namespace {

constexpr double kDt = 0.01;

// A 2 x 1 x 1 tetrahedral bar spinning about a tilted axis through its centre (rotations far from I).
FemScene spinningBarScene(WarpedDynamicsOptions::Solver solver) {
  FemScene scene;
  scene.name = "spinning_bar";
  scene.mesh =
      std::make_shared<PolyhedralMesh>(PolyhedralMesh::tetrahedralGrid(Vec3::Zero(), Vec3(2, 1, 1), 6, 3, 3));
  const Vec3 omega(3.0, 8.0, 2.0), centre(1.0, 0.5, 0.5);
  for (const Vec3& x : scene.mesh->nodes()) scene.initial_velocities.push_back(omega.cross(x - centre));
  scene.youngs_modulus = 2e4;
  scene.poisson_ratio = 0.3;
  scene.density = 1.0;
  scene.dynamics.time_step = kDt;
  scene.dynamics.solver = solver;
  scene.dynamics.cg_tolerance = 1e-10;
  scene.frame_count = 1;
  scene.steps_per_frame = 1;
  return scene;
}

// Cuts the bar across at x = 1.1 (between node planes: crossed elements are split) in two bodies.
FemSceneCut crossCut(double time) {
  FemSceneCut cut;
  cut.time = time;
  cut.polygons = {{Vec3(1.1, -0.5, -0.5), Vec3(1.1, 1.5, -0.5), Vec3(1.1, 1.5, 1.5), Vec3(1.1, -0.5, 1.5)}};
  cut.duration = 0.0;
  return cut;
}

std::tuple<double, double, double> centroidKey(const ConvexPolyhedron& element) {
  const Vec3 c = element.centroid();
  return {c.x(), c.y(), c.z()};
}

TEST(FemStateCarry, CutBodiesStartFromTheCutBodysRotations) {
  FemScene scene = spinningBarScene(WarpedDynamicsOptions::Solver::kConjugateGradient);
  FemSimulation sim(scene);
  for (int s = 0; s < 5; ++s) sim.step();
  // Rotations of the cut body by element rest centroid (elements the cut leaves whole keep their geometry).
  std::map<std::tuple<double, double, double>, Eigen::Matrix3d> before;
  const WarpedDynamics& body = sim.body(0);
  double angle = 0.0;
  for (int e = 0; e < body.model().mesh().numElements(); ++e) {
    before[centroidKey(body.model().mesh().element(e))] = body.rotations()[e];
    angle = std::max(angle, Eigen::AngleAxisd(body.rotations()[e]).angle());
  }
  EXPECT_GT(angle, 0.3);  // ~0.45 rad after 5 steps: a fresh start (I) is far off
  const int elements_before =
      body.model().mesh().numElements();  // (the cut replaces `body`: ASan found a read)

  const FemCutReport report = sim.applyCut(crossCut(0.0));
  ASSERT_EQ(sim.numBodies(), 2);
  EXPECT_EQ(report.bodies_separated, 1);
  EXPECT_GT(report.split_elements, 0);
  int whole = 0, split = 0;
  for (int b = 0; b < sim.numBodies(); ++b) {
    const WarpedDynamics& part = sim.body(b);
    for (int e = 0; e < part.model().mesh().numElements(); ++e) {
      const auto it = before.find(centroidKey(part.model().mesh().element(e)));
      if (it != before.end()) {
        ++whole;
        EXPECT_EQ((part.rotations()[e] - it->second).norm(), 0.0) << "element " << e << " of body " << b;
      } else {
        ++split;  // a piece of a split element: a neighbour's rotation, within ~0.1 rad of the cut body's
        EXPECT_GT(Eigen::AngleAxisd(part.rotations()[e]).angle(), 0.3);
      }
    }
  }
  EXPECT_EQ(whole + split, sim.numElements());
  EXPECT_GE(whole, elements_before - 2 * report.split_elements);
  EXPECT_GE(split, report.split_elements);
  // dv carried: the bodies' CG warm starts are the cut body's velocity increments (centripetal, non-zero).
  for (int b = 0; b < sim.numBodies(); ++b) EXPECT_GT(sim.body(b).previousVelocityIncrement().norm(), 1e-3);
}

// Positions of all bodies, and their rotations, after `steps` steps with the cross cut at t = 0.05.
struct CutRun {
  Eigen::VectorXd positions;
  std::vector<Eigen::Matrix3d> rotations;
  FemSimulation::SolverCounts counts;
};

CutRun runCut(WarpedDynamicsOptions::Solver solver, bool carry, int steps,
              std::vector<Eigen::Matrix3d>* first_rotations = nullptr) {
  FemScene scene = spinningBarScene(solver);
  scene.cuts = {crossCut(0.05)};
  FemSimulation sim(scene);
  sim.setCarryStateAcrossCuts(carry);
  CutRun run;
  for (int s = 0; s < steps; ++s) {
    sim.step();
    if (s == 5 && first_rotations)  // the first step after the cut (it starts at t = 0.05)
      for (int b = 0; b < sim.numBodies(); ++b)
        first_rotations->insert(first_rotations->end(), sim.body(b).rotations().begin(),
                                sim.body(b).rotations().end());
  }
  EXPECT_EQ(sim.numBodies(), 2);
  for (int b = 0; b < sim.numBodies(); ++b) {
    const Eigen::VectorXd& x = sim.body(b).positions();
    run.positions.conservativeResize(run.positions.size() + x.size());
    run.positions.tail(x.size()) = x;
    run.rotations.insert(run.rotations.end(), sim.body(b).rotations().begin(), sim.body(b).rotations().end());
  }
  run.counts = sim.solverCounts();
  return run;
}

void expectSameMotion(WarpedDynamicsOptions::Solver solver) {
  std::vector<Eigen::Matrix3d> carried_first, fresh_first;
  const CutRun carried = runCut(solver, true, 12, &carried_first);
  const CutRun fresh = runCut(solver, false, 12, &fresh_first);
  // The registrations of the first step after the cut converge to the same R_e from the carried rotations
  // and from I (same positions).
  ASSERT_EQ(carried_first.size(), fresh_first.size());
  double first_difference = 0.0;
  for (size_t e = 0; e < carried_first.size(); ++e)
    first_difference = std::max(first_difference, (carried_first[e] - fresh_first[e]).norm());
  EXPECT_LT(first_difference, 1e-10);
  // Then only the CG warm start differs (relative residual 1e-10 per solve).
  ASSERT_EQ(carried.positions.size(), fresh.positions.size());
  EXPECT_LT((carried.positions - fresh.positions).cwiseAbs().maxCoeff(), 1e-8);
  double rotation_difference = 0.0;
  for (size_t e = 0; e < carried.rotations.size(); ++e)
    rotation_difference = std::max(rotation_difference, (carried.rotations[e] - fresh.rotations[e]).norm());
  EXPECT_LT(rotation_difference, 1e-8);
}

TEST(FemStateCarry, CarriedStateMovesLikeAFreshStartCg) {
  expectSameMotion(WarpedDynamicsOptions::Solver::kConjugateGradient);
}

TEST(FemStateCarry, CarriedStateMovesLikeAFreshStartCholmodPcg) {
  if (!cholmodAvailable()) GTEST_SKIP() << "build without CHOLMOD";
  expectSameMotion(WarpedDynamicsOptions::Solver::kCholmodPcg);
  // Counts: one body, then two made by the cut (a new pattern each: analysed anew).
  const CutRun carried = runCut(WarpedDynamicsOptions::Solver::kCholmodPcg, true, 12);
  EXPECT_EQ(carried.counts.bodies_built, 3);
  EXPECT_EQ(carried.counts.analyses, 3);
  EXPECT_GE(carried.counts.factorizations, 3);
}

TEST(FemStateCarry, CarriedStateIsValidated) {
  const FemScene scene = spinningBarScene(WarpedDynamicsOptions::Solver::kConjugateGradient);
  WarpedDynamics body(LinearElasticModel(*scene.mesh, 2e4, 0.3), scene.dynamics);
  EXPECT_THROW(body.setRotations(std::vector<Eigen::Matrix3d>(3, Eigen::Matrix3d::Identity())),
               std::invalid_argument);
  std::vector<Eigen::Matrix3d> rotations(body.model().mesh().numElements(), Eigen::Matrix3d::Identity());
  rotations[2](1, 1) = NAN;
  EXPECT_THROW(body.setRotations(rotations), std::invalid_argument);
  EXPECT_THROW(body.setPreviousVelocityIncrement(Eigen::VectorXd::Zero(5)), std::invalid_argument);
  EXPECT_EQ(body.cholmodSolver(), nullptr);  // CG: no CHOLMOD solver
}

TEST(FemStateCarry, BlasThreadControlLeavesCholmodSolutionsUnchanged) {
  if (!cholmodAvailable()) GTEST_SKIP() << "build without CHOLMOD";
  const FemScene scene = spinningBarScene(WarpedDynamicsOptions::Solver::kCholmod);
  const LinearElasticModel model(*scene.mesh, 2e4, 0.3);
  Eigen::SparseMatrix<double> a = model.stiffness();
  for (int d = 0; d < a.rows(); ++d) a.coeffRef(d, d) += 1.0;  // K + I: positive definite
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 2.0);
  Eigen::VectorXd x_on, x_off;
  const bool previous = cholmodBlasThreadControl();
  setCholmodBlasThreadControl(true);
  CholmodSolver on;
  on.factorize(a);
  on.solve(b, x_on);
  setCholmodBlasThreadControl(false);
  CholmodSolver off;
  off.factorize(a);
  off.solve(b, x_off);
  setCholmodBlasThreadControl(previous);
  EXPECT_LT((a * x_on - b).norm(), 1e-10 * b.norm());
  EXPECT_LT((x_on - x_off).norm(), 1e-10 * x_off.norm());
  EXPECT_GT(on.factorizationSeconds(), 0.0);
  EXPECT_GT(on.analysisSeconds(), 0.0);
}

}  // namespace
}  // namespace rc
