// Warm-started element rotations (thesis 9.1.4): Newton iterations from the previous rotation give Horn's
// registration to round-off, fall back to Horn's eigen-solve for flat, mirrored and far-rotated point sets,
// and the warped dynamics' rotations equal Horn's on every element after each step. Above the parallel
// threshold K_w and f_int equal the element sums and do not depend on the thread count.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <Eigen/SparseCore>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "relaxed_connectivity/fem/horn_registration.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"
#include "warped_test_support.h"

namespace rc {
namespace {

Eigen::Matrix3d smallRotation(std::mt19937& rng, double angle) {
  std::normal_distribution<double> normal;
  const Vec3 axis = Vec3(normal(rng), normal(rng), normal(rng)).normalized();
  return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
}

struct PointSet {
  Eigen::VectorXd rest, current, weights;
};

// n points; flat: rest in the plane z = 0; current = q (I + strain) rest + t.
PointSet randomPointSet(std::mt19937& rng, int n, bool flat, const Eigen::Matrix3d& q, double strain) {
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) f(i, j) += strain * uniform(rng);
  const Vec3 t(uniform(rng), uniform(rng), uniform(rng));
  PointSet set{Eigen::VectorXd(3 * n), Eigen::VectorXd(3 * n), Eigen::VectorXd(n)};
  for (int a = 0; a < n; ++a) {
    const Vec3 x(uniform(rng), uniform(rng), flat ? 0.0 : uniform(rng));
    set.rest.segment<3>(3 * a) = x;
    set.current.segment<3>(3 * a) = q * f * x + t;
    set.weights[a] = 1.0 + 0.5 * uniform(rng);
  }
  return set;
}

TEST(WarmStartedRegistration, MatchesHornFromANearbyRotation) {
  std::mt19937 rng(17);
  int newton = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix3d q = randomRotation(rng);
    const PointSet set = randomPointSet(rng, trial % 2 ? 4 : 7, false, q, 0.2);
    const HornRegistration horn = hornRegistration(set.rest, set.current, set.weights);
    bool eigen_solve = true;
    const HornRegistration warm = warmStartedRegistration(
        set.rest, set.current, set.weights, smallRotation(rng, 0.2) * horn.rotation, &eigen_solve);
    newton += !eigen_solve;
    EXPECT_LT((warm.rotation - horn.rotation).cwiseAbs().maxCoeff(), 1e-12) << "trial " << trial;
    EXPECT_NEAR(warm.eigenvalue_gap, horn.eigenvalue_gap, 1e-9) << "trial " << trial;
    EXPECT_LT((warm.rest_centroid - horn.rest_centroid).norm(), 1e-15);
    EXPECT_LT((warm.current_centroid - horn.current_centroid).norm(), 1e-15);
    EXPECT_NEAR(warm.rotation.determinant(), 1.0, 1e-13);
  }
  // Well-shaped, moderately strained point sets near the guess take the Newton path (a few near-flat
  // random tetrahedra may not).
  EXPECT_GE(newton, 190);
}

TEST(WarmStartedRegistration, RigidRotationIsRecoveredExactly) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix3d q = randomRotation(rng);
    const PointSet set = randomPointSet(rng, 4, false, q, 0.0);
    bool eigen_solve = true;
    const HornRegistration warm = warmStartedRegistration(set.rest, set.current, set.weights,
                                                          smallRotation(rng, 0.3) * q, &eigen_solve);
    EXPECT_FALSE(eigen_solve) << "trial " << trial;
    EXPECT_LT((warm.rotation - q).cwiseAbs().maxCoeff(), 1e-13) << "trial " << trial;
  }
}

TEST(WarmStartedRegistration, FlatMirroredAndFarRotatedSetsUseTheEigenSolve) {
  std::mt19937 rng(29);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix3d q = randomRotation(rng);
    // Flat: det S = 0, Horn's eigen-solve recovers the rotation (Newton would have a singular problem).
    const PointSet flat = randomPointSet(rng, 6, true, q, 0.0);
    bool eigen_solve = false;
    const HornRegistration warm =
        warmStartedRegistration(flat.rest, flat.current, flat.weights, q, &eigen_solve);
    EXPECT_TRUE(eigen_solve);
    EXPECT_LT((warm.rotation - q).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_GT(warm.eigenvalue_gap, 1e-3);
    // Mirrored: the proper rotation of Horn's registration.
    PointSet mirrored = randomPointSet(rng, 5, false, Eigen::Matrix3d::Identity(), 0.0);
    for (int a = 0; a < 5; ++a) mirrored.current[3 * a] = -mirrored.current[3 * a];
    const HornRegistration horn = hornRegistration(mirrored.rest, mirrored.current, mirrored.weights);
    const HornRegistration mirrored_warm = warmStartedRegistration(
        mirrored.rest, mirrored.current, mirrored.weights, Eigen::Matrix3d::Identity(), &eigen_solve);
    EXPECT_TRUE(eigen_solve);
    EXPECT_LT((mirrored_warm.rotation - horn.rotation).cwiseAbs().maxCoeff(), 1e-15);
    // Guess half a turn away: the Newton matrix is indefinite, the eigen-solve answers.
    const PointSet far = randomPointSet(rng, 4, false, q, 0.1);
    const HornRegistration far_horn = hornRegistration(far.rest, far.current, far.weights);
    const Eigen::Matrix3d turned = Eigen::AngleAxisd(M_PI * 0.95, Vec3::UnitX()).toRotationMatrix() * q;
    const HornRegistration far_warm =
        warmStartedRegistration(far.rest, far.current, far.weights, turned, &eigen_solve);
    EXPECT_LT((far_warm.rotation - far_horn.rotation).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(WarpedDynamics, WarmStartedRotationsEqualHornsAfterEachStep) {
  const LinearElasticModel model(PolyhedralMesh::randomPlaneCut(Vec3(0, 0, 0), Vec3(1, 1, 1), 3, 3, 3, 8, 5),
                                 3e3, 0.3);
  WarpedDynamicsOptions options;
  options.time_step = 0.02;
  options.gravity = Vec3(0, 0, -9.81);
  options.ground.enabled = true;
  options.ground.offset = -0.2;
  options.solver = WarpedDynamicsOptions::Solver::kSimplicialLDLT;
  WarpedDynamics sim(model, options);
  Eigen::VectorXd v(sim.numDofs());
  for (int i = 0; i < sim.numNodes(); ++i)  // spin about z and tumble about x
    v.segment<3>(3 * i) = Vec3(0, 0, 4.0).cross(sim.restPositions().segment<3>(3 * i) - Vec3(0.5, 0.5, 0.5)) +
                          Vec3(3.0, 0, 0).cross(sim.restPositions().segment<3>(3 * i) - Vec3(0.5, 0.5, 0.5));
  sim.setVelocities(v);
  double worst = 0.0;
  for (int step = 0; step < 30; ++step) {
    sim.step();
    sim.updateWarping();
    for (int e = 0; e < model.mesh().numElements(); ++e) {
      const auto& ids = model.mesh().element(e).globalNodeIds();
      const int n = static_cast<int>(ids.size());
      Eigen::VectorXd rest(3 * n), current(3 * n), weights(n);
      for (int a = 0; a < n; ++a) {
        rest.segment<3>(3 * a) = sim.restPositions().segment<3>(3 * ids[a]);
        current.segment<3>(3 * a) = sim.positions().segment<3>(3 * ids[a]);
        weights[a] = model.lumpedMasses()[ids[a]];
      }
      const HornRegistration horn = hornRegistration(rest, current, weights);
      if (!(horn.eigenvalue_gap > options.min_eigenvalue_gap)) continue;
      worst = std::max(worst, (horn.rotation - sim.rotations()[e]).cwiseAbs().maxCoeff());
    }
  }
  std::printf("max |R_warm - R_horn| over 30 steps: %.3e\n", worst);
  EXPECT_LT(worst, 1e-11);
}

TEST(WarpedDynamics, ParallelWarpingEqualsElementSums) {
  // Above the parallel threshold (512 elements) the rotations and element blocks are computed in parallel;
  // K_w and f_int equal the sums of R_e K_e R_e^T and -R_e K_e u_e and do not depend on the thread count
  // (bit for bit).
  const LinearElasticModel model(PolyhedralMesh::randomPlaneCut(Vec3(0, 0, 0), Vec3(1, 1, 1), 7, 7, 7, 6, 3),
                                 1e3, 0.3);
  ASSERT_GE(model.mesh().numElements(), 512);
  WarpedDynamics sim(model);
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);
  const Eigen::Matrix3d q = randomRotation(rng);
  Eigen::VectorXd x(sim.numDofs());
  for (int i = 0; i < sim.numNodes(); ++i)
    x.segment<3>(3 * i) = q * sim.restPositions().segment<3>(3 * i) + Vec3(jitter(rng), jitter(rng), 0.1);
  sim.setPositions(x);
  sim.updateWarping();
  const WarpedElementSums sums = warpedElementSums(model, sim, x);
  const Eigen::VectorXd& f = sums.forces;
  Eigen::SparseMatrix<double> k(sim.numDofs(), sim.numDofs());
  k.setFromTriplets(sums.stiffness.begin(), sums.stiffness.end());
  const Eigen::SparseMatrix<double> difference = k - sim.warpedStiffness();
  EXPECT_LT(difference.norm(), 1e-13 * k.norm());
  EXPECT_LT((f - sim.elasticForces()).norm(), 1e-12 * f.norm());
#ifdef _OPENMP
  // The same state on one thread (a fresh body: the same warm start, the same rotations).
  WarpedDynamics serial(model);
  serial.setPositions(x);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  serial.updateWarping();
  omp_set_num_threads(threads);
  std::printf("threads %d vs 1\n", threads);
  EXPECT_EQ(Eigen::SparseMatrix<double>(serial.warpedStiffness() - sim.warpedStiffness()).cwiseAbs().sum(),
            0.0);
  EXPECT_EQ((serial.elasticForces() - sim.elasticForces()).cwiseAbs().maxCoeff(), 0.0);
#endif
}

}  // namespace
}  // namespace rc
