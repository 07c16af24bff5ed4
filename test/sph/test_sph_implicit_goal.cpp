// Locally implicit goal springs (SphElasticConfig::implicit_goal) and contact springs
// (SphObjectPenaltyConfig::implicit): stable at the thesis' step of the stiff dice (appendix F.2,
// dt = 4e-4 s with K_e = 2.4e7), where the explicit forces (8.31) and (8.37) blow up.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "momentum_test_support.h"
#include "sph/sph_elastic_solid.h"
#include "sph/sph_fluid_solver.h"
#include "sph/sph_lattice.h"
#include "sph/sph_object_penalty.h"

namespace rc {
namespace {

using Mat3 = Eigen::Matrix3d;

constexpr double kSpacing = 0.07;     // the dice of Fig. 8.8
constexpr double kStiffness = 2.4e7;  // K_e, appendix F.2
constexpr double kThesisStep = 4e-4;  // appendix F.2

SphFluidConfig diceConfig() {
  SphFluidConfig c;  // appendix F.2: rho = 1, Gamma = 1, K = 20, zeta = 0.01
  c.dimension = 3;
  c.smoothing_length = 2.0 * kSpacing;
  c.rest_density = 1.0;
  c.stiffness = 20.0;
  c.gamma = 1.0;
  c.negative_pressure_scale = 0.01;
  c.xsph = 0.0;
  c.viscosity = 0.0;
  c.gravity = Vec3::Zero();
  c.fixed_dt = kThesisStep;
  c.num_threads = 1;
  return c;
}

SphElasticConfig diceMaterial(bool implicit) {
  SphElasticConfig e;
  e.model = SphElasticModel::kGoalPosition;
  e.lattice_spacing = kSpacing;
  e.goal_stiffness = kStiffness;
  e.implicit_goal = implicit;
  return e;
}

struct Cube {
  std::unique_ptr<SphFluidSolver> solver;
  std::vector<std::shared_ptr<SphElasticSolid>> solids;
  std::vector<Vec3> rest;
};

/// `count` cubes of side 0.35 (phases 1, 2, ...) at `centers`, sampled with orientation q, each stretched by
/// `stretch` along x about its centre and moving with `velocities` plus `spin` about its centre, plus a
/// small random velocity.
Cube makeCubes(const SphFluidConfig& config, const SphElasticConfig& material,
               const std::vector<Vec3>& centers, const std::vector<Vec3>& velocities, const Mat3& q,
               double stretch, const Vec3& spin, double jitter_speed) {
  Cube c;
  const SphKernels kernels(3, config.smoothing_length);
  const SphLattice lattice(3, kSpacing);
  const double mass = lattice.particleMass(kernels, config.rest_density);
  SphParticles particles;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (size_t k = 0; k < centers.size(); ++k) {
    SphLatticeFrame frame;
    frame.orientation = q;
    frame.origin = centers[k];
    const std::vector<Vec3> points = sampleLatticeBox(lattice, centers[k] - Vec3::Constant(0.175),
                                                      centers[k] + Vec3::Constant(0.175), frame);
    Vec3 mean = Vec3::Zero();
    for (const Vec3& p : points) mean += p;
    mean /= double(points.size());
    auto solid = std::make_shared<SphElasticSolid>(material, kernels, uint8_t(k + 1), q);
    std::vector<Vec3> x;
    for (const Vec3& p : points)
      x.push_back(mean + Vec3(stretch * (p - mean).x(), (p - mean).y(), (p - mean).z()));
    const size_t first = solid->addParticles(particles, x, mass, velocities[k]);
    for (size_t i = first; i < particles.size(); ++i)
      particles.velocities[i] +=
          spin.cross(particles.positions[i] - mean) + jitter_speed * Vec3(uni(rng), uni(rng), uni(rng));
    c.solids.push_back(solid);
    c.rest.insert(c.rest.end(), points.begin(), points.end());
  }
  c.solver = std::make_unique<SphFluidSolver>(config, std::move(particles));
  for (auto& s : c.solids) c.solver->addForceTerm(s);
  return c;
}

double energyOf(const SphFluidSolver& solver) {
  const SphStepStats& st = solver.lastStats();
  return st.kinetic_energy + st.term_energy + st.compression_energy;
}

// A stiff goal-position cube (K_e = 2.4e7), stretched by 5% and shaken (0.2 m/s random velocities), at the
// thesis' dt = 4e-4: with the implicit springs the energy never exceeds its start and decays, the cube
// returns to its shape and the step is no longer limited by the elasticity; with the explicit force (8.31)
// the step exceeds the reported limit and the energy grows (19-fold in 0.06 s).
TEST(SphImplicitGoal, StiffCubeIsStableAtTheThesisStep) {
  for (bool implicit : {true, false}) {
    Cube c = makeCubes(diceConfig(), diceMaterial(implicit), {Vec3(0, 0.5, 0)}, {Vec3::Zero()},
                       Eigen::AngleAxisd(0.3, Vec3(1, 1, 0).normalized()).toRotationMatrix(), 1.05,
                       Vec3::Zero(), 0.2);
    SphFluidSolver& solver = *c.solver;
    const SphParticles& p = solver.particles();
    const double reported = c.solids[0]->stableTimeStep(p, 1.0);
    solver.computeForces();
    const double e0 = energyOf(solver);
    double max_energy = e0, last = e0;
    bool blew_up = false;
    try {
      for (int step = 0; step < 150; ++step) {  // 0.06 s
        const SphStepStats& st = solver.step();
        last = energyOf(solver);
        max_energy = std::max(max_energy, last);
        for (const Vec3& x : p.positions) ASSERT_TRUE(x.allFinite());
        EXPECT_EQ(st.limit, SphStepLimit::kFixed);
      }
    } catch (const SphInstabilityError& e) {
      blew_up = true;
      std::printf("explicit: %s\n", e.what());
    }
    std::printf("%s: reported elastic limit %.3g s (dt %.3g), energy %.4g -> %.4g (max %.4g)%s\n",
                implicit ? "implicit" : "explicit", reported, kThesisStep, e0, last, max_energy,
                blew_up ? ", blew up" : "");
    if (implicit) {
      EXPECT_FALSE(blew_up);
      EXPECT_TRUE(std::isinf(reported));
      EXPECT_LE(max_energy, e0 * (1.0 + 1e-9));  // never gains energy
      EXPECT_LT(last, 0.05 * e0);                // the stiff oscillation is dissipated
      // The cube keeps its shape: every particle's distance to the first one within 2% of the rest.
      for (size_t i = 1; i < c.rest.size(); ++i) {
        const double r0 = (c.rest[i] - c.rest[0]).norm(), r1 = (p.positions[i] - p.positions[0]).norm();
        EXPECT_NEAR(r1, r0, 0.02 * r0);
      }
      EXPECT_LT(c.solids[0]->stats().max_strain, 0.01);
    } else {
      EXPECT_LT(reported, kThesisStep);  // the explicit scheme reports that dt = 4e-4 is beyond its limit
      EXPECT_TRUE(blew_up || max_energy > 5.0 * e0);  // and gains energy
    }
  }
}

// The implicit springs keep linear and angular momentum exact (the damping and the scaling act per
// neighbourhood before the correction (8.32)-(8.33)) and do not damp a rigid motion: a spinning, drifting
// cube keeps its kinetic energy and spin at dt = 4e-4.
TEST(SphImplicitGoal, KeepsMomentumAndDoesNotDampRigidMotion) {
  const Vec3 spin(3.0, -2.0, 4.0), drift(0.5, -0.2, 0.3);
  Cube c = makeCubes(diceConfig(), diceMaterial(true), {Vec3(0.1, 0.4, -0.2)}, {drift},
                     Eigen::AngleAxisd(0.7, Vec3(1, -2, 1).normalized()).toRotationMatrix(), 1.0, spin, 0.0);
  SphFluidSolver& solver = *c.solver;
  solver.computeForces();
  const double kinetic0 = solver.lastStats().kinetic_energy;
  Vec3 p0, l0;
  double sp, sl, worst_p = 0.0, worst_l = 0.0;
  momenta(solver.particles(), p0, l0, sp, sl);
  const Vec3 l_start = l0;
  for (int step = 0; step < 100; ++step) {
    solver.step();
    Vec3 p1, l1;
    momenta(solver.particles(), p1, l1, sp, sl);
    worst_p = std::max(worst_p, (p1 - p0).norm() / sp);
    worst_l = std::max(worst_l, (l1 - l0).norm() / sl);
    p0 = p1;
    l0 = l1;
  }
  const double kinetic = solver.lastStats().kinetic_energy;
  std::printf("spinning cube: dP %.2e dL %.2e per step, kinetic %.5g -> %.5g, max strain %.3g\n", worst_p,
              worst_l, kinetic0, kinetic, c.solids[0]->stats().max_strain);
  EXPECT_LT(worst_p, 1e-9);
  EXPECT_LT(worst_l, 1e-9);
  EXPECT_LT((l0 - l_start).norm(), 1e-8 * l_start.norm());
  EXPECT_GT(kinetic, 0.99 * kinetic0);  // the rigid motion is not damped
  EXPECT_LT(c.solids[0]->stats().max_strain, 0.01);
}

// Two stiff cubes collide head-on at 2 m/s each with the collision penalty of the dice (K_c = 1e7, contact
// distance d) at dt = 4e-4: with the implicit contact springs the collision is stable, the cubes do not
// pass into each other and bounce back, and momentum is exact; the explicit penalty reports a limit below
// the step.
TEST(SphImplicitGoal, ImplicitPenaltyResolvesAStiffCollision) {
  SphFluidConfig config = diceConfig();
  Cube c = makeCubes(config, diceMaterial(true), {Vec3(-0.25, 0.5, 0), Vec3(0.25, 0.5, 0)},
                     {Vec3(2, 0, 0), Vec3(-2, 0, 0)}, Mat3::Identity(), 1.0, Vec3::Zero(), 0.0);
  SphObjectPenaltyConfig pc;
  pc.stiffness = 1.0e7;
  pc.contact_distance = kSpacing;
  pc.implicit = true;
  const SphKernels kernels(3, config.smoothing_length);
  SphObjectPenaltyConfig explicit_pc = pc;
  explicit_pc.implicit = false;
  const double explicit_limit =
      SphObjectPenalty(explicit_pc, kernels).stableTimeStep(c.solver->particles(), 1.0);
  auto penalty = std::make_shared<SphObjectPenalty>(pc, kernels);
  c.solver->addForceTerm(penalty);
  const double implicit_limit = penalty->stableTimeStep(c.solver->particles(), 1.0);
  SphFluidSolver& solver = *c.solver;
  Vec3 p0, l0;
  double sp, sl;
  momenta(solver.particles(), p0, l0, sp, sl);
  const double scale = sp;
  double min_distance = kSpacing;
  for (int step = 0; step < 300; ++step) {  // 0.12 s: they meet after about 0.02 s
    solver.step();
    min_distance = std::min(min_distance, penalty->stats().min_distance);
  }
  Vec3 p1, l1;
  momenta(solver.particles(), p1, l1, sp, sl);
  // Mean x velocity of each cube after the collision.
  double v_left = 0.0, v_right = 0.0;
  const SphParticles& p = solver.particles();
  size_t n_left = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.phases[i] == 1) {
      v_left += p.velocities[i].x();
      ++n_left;
    } else {
      v_right += p.velocities[i].x();
    }
  }
  v_left /= double(n_left);
  v_right /= double(p.size() - n_left);
  std::printf(
      "collision: explicit limit %.3g s, implicit limit %.3g s, dt %.3g; min distance %.3g (d %.3g), "
      "velocities after %.3g %.3g, dP %.2e\n",
      explicit_limit, implicit_limit, kThesisStep, min_distance, kSpacing, v_left, v_right,
      (p1 - p0).norm() / scale);
  EXPECT_LT(explicit_limit, kThesisStep);
  EXPECT_GT(implicit_limit, kThesisStep);
  EXPECT_GT(min_distance, 0.4 * kSpacing);  // no interpenetration
  EXPECT_LT(v_left, 0.0);                   // bounced back
  EXPECT_GT(v_right, 0.0);
  EXPECT_LT((p1 - p0).norm(), 1e-9 * scale);
  for (const Vec3& x : p.positions) EXPECT_TRUE(x.allFinite());
}

}  // namespace
}  // namespace rc
