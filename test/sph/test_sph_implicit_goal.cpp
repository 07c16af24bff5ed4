// Locally implicit goal springs (SphElasticConfig::implicit_goal) and contact springs
// (SphObjectPenaltyConfig::implicit): stable at the thesis' step of the stiff dice (appendix F.2,
// dt = 4e-4 s with K_e = 2.4e7), where the explicit forces (8.31) and (8.37) blow up.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "momentum_test_support.h"
#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_implicit_goal_solver.h"
#include "relaxed_connectivity/sph/sph_lattice.h"
#include "relaxed_connectivity/sph/sph_object_penalty.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"
#include "scene_file_test_support.h"

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

/// The globally implicit goal springs (SphElasticConfig::global_implicit_goal).
SphElasticConfig globalMaterial(double stiffness = kStiffness) {
  SphElasticConfig e = diceMaterial(true);
  e.global_implicit_goal = true;
  e.goal_stiffness = stiffness;
  return e;
}

/// The Verlet limit of the explicit goal forces, 2 / sqrt(2 K_e) (stableTimeStep at cfl 1).
double explicitLimit(double stiffness) {
  return std::sqrt(2.0 / stiffness);
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

// One stiff cube spinning (3, -2, 4) rad/s and drifting (0.5, -0.2, 0.3) m/s, forces computed.
Cube spinningDriftingCube(const SphFluidConfig& config, const SphElasticConfig& material) {
  Cube c = makeCubes(config, material, {Vec3(0.1, 0.4, -0.2)}, {Vec3(0.5, -0.2, 0.3)},
                     Eigen::AngleAxisd(0.7, Vec3(1, -2, 1).normalized()).toRotationMatrix(), 1.0,
                     Vec3(3.0, -2.0, 4.0), 0.0);
  c.solver->computeForces();
  return c;
}

// Over `steps` steps: momentum exact per step (8.32)-(8.33), the spin kept, the rigid motion not damped and
// no strain from it.
void expectRigidMotionKept(Cube c, int steps, const char* label) {
  SphFluidSolver& solver = *c.solver;
  const double kinetic0 = solver.lastStats().kinetic_energy;
  const MomentumDrift m = trackMomentum(solver.particles(), steps, [&] { solver.step(); });
  const double kinetic = solver.lastStats().kinetic_energy;
  std::printf("%s, spinning cube: dP %.2e dL %.2e per step, kinetic %.6g -> %.6g, max strain %.3g\n", label,
              m.worst_linear, m.worst_angular, kinetic0, kinetic, c.solids[0]->stats().max_strain);
  EXPECT_LT(m.worst_linear, 1e-9);
  EXPECT_LT(m.worst_angular, 1e-9);
  EXPECT_LT((m.angular_end - m.angular_start).norm(), 1e-8 * m.angular_start.norm());
  EXPECT_GT(kinetic, 0.99 * kinetic0);  // the rigid motion is not damped
  EXPECT_LT(c.solids[0]->stats().max_strain, 0.01);
}

// Runs `duration` seconds of steps dt and returns the particles' mean height averaged over the last
// `average` seconds.
double meanHeightOverLastSteps(SphFluidSolver& solver, double duration, double average, double dt) {
  const SphParticles& p = solver.particles();
  const int steps = int(std::lround(duration / dt)), averaged = int(std::lround(average / dt));
  double sum = 0.0;
  for (int step = 0; step < steps; ++step) {
    solver.step();
    if (step >= steps - averaged) {
      double mean = 0.0;
      for (const Vec3& x : p.positions) mean += x.y();
      sum += mean / double(p.size());
    }
  }
  return sum / double(averaged);
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
  expectRigidMotionKept(spinningDriftingCube(diceConfig(), diceMaterial(true)), 100, "local");
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

// The global implicit goal springs at 30x the explicit Verlet limit (dt = 8.7e-3 s, 75x the adaptive step of
// the dice): a stretched (5%) and shaken stiff cube never gains energy, settles and keeps its shape, and CG
// converges within its tolerance.
TEST(SphImplicitGoal, GlobalSpringsAreStableAt30TimesTheExplicitLimit) {
  SphFluidConfig config = diceConfig();
  config.fixed_dt = 30.0 * explicitLimit(kStiffness);
  Cube c = makeCubes(config, globalMaterial(), {Vec3(0, 0.5, 0)}, {Vec3::Zero()},
                     Eigen::AngleAxisd(0.3, Vec3(1, 1, 0).normalized()).toRotationMatrix(), 1.05,
                     Vec3::Zero(), 0.2);
  SphFluidSolver& solver = *c.solver;
  const SphParticles& p = solver.particles();
  EXPECT_TRUE(std::isinf(c.solids[0]->stableTimeStep(p, 1.0)));
  solver.computeForces();
  const double e0 = energyOf(solver);
  double max_energy = e0, last = e0;
  int max_iterations = 0;
  for (int step = 0; step < 40; ++step) {  // 0.35 s
    solver.step();
    last = energyOf(solver);
    max_energy = std::max(max_energy, last);
    const SphElasticStats& st = c.solids[0]->stats();
    max_iterations = std::max(max_iterations, st.implicit_iterations);
    EXPECT_LE(st.implicit_residual, globalMaterial().implicit_tolerance);
  }
  std::printf("global, dt %.3g: energy %.4g -> %.4g (max %.4g), max strain %.3g, CG <= %d iterations\n",
              config.fixed_dt, e0, last, max_energy, c.solids[0]->stats().max_strain, max_iterations);
  EXPECT_LE(max_energy, e0 * (1.0 + 1e-9));
  EXPECT_LT(last, 0.01 * e0);
  for (size_t i = 1; i < c.rest.size(); ++i) {
    const double r0 = (c.rest[i] - c.rest[0]).norm(), r1 = (p.positions[i] - p.positions[0]).norm();
    EXPECT_NEAR(r1, r0, 0.01 * r0);
  }
  // What remains is the static offset of about dt^2 / 2 times the pressure's acceleration (explicit).
  EXPECT_LT(c.solids[0]->stats().max_strain, 0.01);
  EXPECT_GT(max_iterations, 0);
  EXPECT_LT(max_iterations, globalMaterial().implicit_max_iterations);
}

// Momentum (8.32)-(8.33) stays exact with the global springs, whatever the CG residual (the force is
// M dv / dt with its net force and torque removed), and the rigid motion of the solid is not damped: a
// spinning, drifting stiff cube at 30x the explicit limit.
TEST(SphImplicitGoal, GlobalSpringsKeepMomentumAndDoNotDampRigidMotion) {
  SphFluidConfig config = diceConfig();
  config.fixed_dt = 30.0 * explicitLimit(kStiffness);
  expectRigidMotionKept(spinningDriftingCube(config, globalMaterial()), 60, "global");  // 0.52 s, 2.8 rad
}

/// Mean height of the particles of a cube (K_e = `stiffness`) resting on the floor y = 0 under gravity,
/// released at its rest shape: averaged over the steps of the last `average` seconds of `duration`.
double restingHeight(const SphElasticConfig& material, double dt, double duration, double average) {
  SphFluidConfig config = diceConfig();
  config.stiffness = 1.0;  // a soft pressure (sound speed 1 m/s): its step limit stays above 30x the elastic
  config.gravity = Vec3(0, -9.81, 0);
  config.fixed_dt = dt;
  Cube c = makeCubes(config, material, {Vec3(0, 0.0, 0)}, {Vec3::Zero()}, Mat3::Identity(), 1.0, Vec3::Zero(),
                     0.0);
  SphFluidSolver& solver = *c.solver;
  SphParticles& p = solver.particles();
  double low = std::numeric_limits<double>::infinity();
  for (const Vec3& x : p.positions) low = std::min(low, x.y());
  for (Vec3& x : p.positions) x.y() -= low;  // the bottom layer on the floor
  solver.particlesChanged();
  solver.addPlane(SphPlane{});
  c.solids[0]->setEnvironment(solver.planes(), config.gravity);  // used by the global springs only
  return meanHeightOverLastSteps(solver, duration, average, dt);
}

// Stiffness at a large step: a dice cube (K_e = 2.4e7) resting on the floor sags under gravity by the same
// amount with the global springs at 10x and 30x the explicit limit (plane constraints in the solve) as with
// the explicit forces (8.31) at 0.8x (time average of its undamped oscillation), within 3%; the local
// springs at 30x sag 700x more (softened as K_e / (1 + dt^2 k)).
TEST(SphImplicitGoal, GlobalSpringsKeepTheStaticSagAtLargeSteps) {
  const double stiffness = kStiffness, limit = explicitLimit(stiffness);
  SphElasticConfig explicit_material = diceMaterial(false), local = diceMaterial(true);
  explicit_material.goal_stiffness = local.goal_stiffness = stiffness;
  // The rest height: no gravity, nothing moves.
  SphFluidConfig probe = diceConfig();
  const double rest = [&] {
    Cube c = makeCubes(probe, explicit_material, {Vec3::Zero()}, {Vec3::Zero()}, Mat3::Identity(), 1.0,
                       Vec3::Zero(), 0.0);
    double low = std::numeric_limits<double>::infinity(), mean = 0.0;
    for (const Vec3& x : c.solver->particles().positions) {
      low = std::min(low, x.y());
      mean += x.y();
    }
    return mean / double(c.solver->particles().size()) - low;
  }();
  const double sag_explicit = rest - restingHeight(explicit_material, 0.8 * limit, 0.3, 0.25);
  const double sag_global = rest - restingHeight(globalMaterial(stiffness), 30.0 * limit, 0.3, 0.1);
  const double sag_global10 = rest - restingHeight(globalMaterial(stiffness), 10.0 * limit, 0.3, 0.1);
  const double sag_local = rest - restingHeight(local, 30.0 * limit, 0.3, 0.1);
  std::printf("sag under gravity: explicit %.4g m, global 10x %.4g m, global 30x %.4g m, local 30x %.4g m\n",
              sag_explicit, sag_global10, sag_global, sag_local);
  EXPECT_GT(sag_explicit, 0.0);
  EXPECT_NEAR(sag_global10, sag_explicit, 0.03 * sag_explicit);
  EXPECT_NEAR(sag_global, sag_explicit, 0.03 * sag_explicit);
  EXPECT_GT(sag_local, 100.0 * sag_explicit);
}

// Scene files select the global springs with `implicit_goal: global` (true: the local ones); other words
// are errors.
TEST(SphImplicitGoal, SceneFileKeySelectsTheGlobalSprings) {
  const std::string head =
      "dimension: 2\nspacing: 0.02\nenable: [elasticity]\nsolver: {smoothing_ratio: 2}\n"
      "frames: {count: 1, time: 0.01}\nsolids:\n";
  const SphScene scene = parseSphScene(head +
                                           "  - {lo: [0, 0], hi: [0.1, 0.1], implicit_goal: global, "
                                           "implicit_step_factor: 30}\n"
                                           "  - {lo: [0.2, 0], hi: [0.3, 0.1], implicit_goal: true}\n"
                                           "  - {lo: [0.4, 0], hi: [0.5, 0.1]}\n",
                                       "global.yaml");
  ASSERT_EQ(scene.solids.size(), 3u);
  EXPECT_TRUE(scene.solids[0].elastic.implicit_goal);
  EXPECT_TRUE(scene.solids[0].elastic.global_implicit_goal);
  EXPECT_EQ(scene.solids[0].elastic.implicit_step_factor, 30.0);
  EXPECT_TRUE(scene.solids[1].elastic.implicit_goal);
  EXPECT_FALSE(scene.solids[1].elastic.global_implicit_goal);
  EXPECT_FALSE(scene.solids[2].elastic.implicit_goal);
  EXPECT_FALSE(scene.solids[2].elastic.global_implicit_goal);
  EXPECT_ANY_THROW(
      parseSphScene(head + "  - {lo: [0, 0], hi: [0.1, 0.1], implicit_goal: globl}\n", "bad.yaml"));
  SphElasticConfig config;  // the config needs implicit_goal with global_implicit_goal
  config.global_implicit_goal = true;
  EXPECT_THROW(config.validate(), std::invalid_argument);
  config.implicit_goal = true;
  EXPECT_NO_THROW(config.validate());
}

// The linear system of the global springs on random points and springs: K = (I - P)^T L (I - P) is
// symmetric, positive semi-definite, zero on rigid motions and exerts no net force or torque; the solve
// meets its tolerance and its prescribed components.
TEST(SphImplicitGoal, GlobalSystemIsSymmetricRigidFreeAndSolved) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const size_t n = 60;
  std::vector<Vec3> x(n), u(n), w(n), f0(n), v(n);
  std::vector<double> masses(n);
  std::vector<std::vector<SphGoalSpring>> springs(n);
  for (size_t s = 0; s < n; ++s) {
    x[s] = Vec3(uni(rng), uni(rng), uni(rng));
    u[s] = Vec3(uni(rng), uni(rng), uni(rng));
    w[s] = Vec3(uni(rng), uni(rng), uni(rng));
    f0[s] = Vec3(uni(rng), uni(rng), uni(rng));
    v[s] = Vec3(uni(rng), uni(rng), uni(rng));
    masses[s] = 1.0 + 0.5 * uni(rng);
  }
  for (size_t s = 0; s < n; ++s)
    for (size_t j = 0; j < n; ++j)
      if (j != s && (x[j] - x[s]).norm() < 0.8) springs[s].push_back({uint32_t(j), 1e3 * (1.5 + uni(rng))});
  SphImplicitGoalSolver solver;
  solver.setSystem(x, masses, springs);
  std::vector<Vec3> ku, kw, rigid(n);
  solver.applyStiffness(u, ku);
  solver.applyStiffness(w, kw);
  double wku = 0.0, ukw = 0.0, uku = 0.0, scale = 0.0;
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  for (size_t s = 0; s < n; ++s) {
    wku += w[s].dot(ku[s]);
    ukw += u[s].dot(kw[s]);
    uku += u[s].dot(ku[s]);
    scale += ku[s].norm();
    force += ku[s];
    torque += x[s].cross(ku[s]);
  }
  EXPECT_NEAR(wku, ukw, 1e-12 * std::abs(wku) + 1e-9);
  EXPECT_GT(uku, 0.0);
  EXPECT_LT(force.norm(), 1e-12 * scale);
  EXPECT_LT(torque.norm(), 1e-12 * scale);
  const Vec3 t(0.3, -0.2, 0.5), omega(1.0, 2.0, -0.7);
  for (size_t s = 0; s < n; ++s) rigid[s] = t + omega.cross(x[s]);
  std::vector<Vec3> k_rigid;
  solver.applyStiffness(rigid, k_rigid);
  for (size_t s = 0; s < n; ++s) EXPECT_LT(k_rigid[s].norm(), 1e-10 * scale / double(n));
  // Solve with two constrained particles: one fixed, one with a prescribed normal component.
  SphVelocityConstraint fixed, plane;
  fixed.particle = 3;
  fixed.count = 3;
  for (int k = 0; k < 3; ++k) fixed.normals[k] = Vec3::Unit(k);
  plane.particle = 11;
  plane.count = 1;
  plane.normals[0] = Vec3(0, 1, 0);
  plane.values[0] = 0.25;
  solver.setConstraints({fixed, plane});
  const double dt = 0.05;
  std::vector<Vec3> dv;
  const SphImplicitGoalResult result = solver.solve(f0, v, dt, 1e-10, 500, dv);
  EXPECT_TRUE(result.converged);
  EXPECT_LE(result.relative_residual, 1e-10);
  EXPECT_EQ(dv[3], Vec3::Zero());
  EXPECT_NEAR(dv[11].y(), 0.25, 1e-14);
  // The unconstrained rows hold: m dv + dt^2 K dv = dt (f0 - dt K v).
  std::vector<Vec3> kdv, kv;
  solver.applyStiffness(dv, kdv);
  solver.applyStiffness(v, kv);
  double worst = 0.0, rhs = 0.0;
  for (size_t s = 0; s < n; ++s) {
    if (s == 3 || s == 11) continue;
    const Vec3 b = dt * (f0[s] - dt * kv[s]);
    worst = std::max(worst, (masses[s] * dv[s] + dt * dt * kdv[s] - b).norm());
    rhs = std::max(rhs, b.norm());
  }
  EXPECT_LT(worst, 1e-8 * rhs);
}

/// A stiff dice cube (K_e = 2.4e7) with its lowest particle 0.02 m above the floor y = 0, falling
/// at `speed` under gravity, adaptive step (the dice scene's pressure, K = 20).
Cube fallingCube(const SphElasticConfig& material, double stretch, double speed) {
  SphFluidConfig config = diceConfig();
  config.fixed_dt = 0.0;
  config.gravity = Vec3(0, -9.81, 0);
  Cube c = makeCubes(config, material, {Vec3(0, 0.5, 0)}, {Vec3(0, -speed, 0)},
                     Eigen::AngleAxisd(0.3, Vec3(1, 0, 1).normalized()).toRotationMatrix(), stretch,
                     Vec3::Zero(), 0.0);
  SphParticles& p = c.solver->particles();
  double low = std::numeric_limits<double>::infinity();
  for (const Vec3& x : p.positions) low = std::min(low, x.y());
  for (Vec3& x : p.positions) x.y() += 0.02 - low;
  c.solver->particlesChanged();
  c.solver->addPlane(SphPlane{});
  for (auto& s : c.solids) s->setEnvironment(c.solver->planes(), config.gravity);
  return c;
}

// The explicit goal forces (8.31) keep the force limit cfl sqrt(h / max |a|) on their accelerations: the
// falling stiff cube, stretched by 30%, hits the floor with the same force limits and steps, bit for bit, as
// before the implicit terms left that limit (reference values of that code).
TEST(SphImplicitGoal, ExplicitSpringsKeepTheForceLimitBitwise) {
  Cube c = fallingCube(diceMaterial(false), 1.3, 3.0);
  SphFluidSolver& solver = *c.solver;
  double dt_force = std::numeric_limits<double>::infinity();
  for (int step = 0; step < 150; ++step) dt_force = std::min(dt_force, solver.step().dt_force);
  double sum = 0.0;
  for (size_t i = 0; i < solver.particles().size(); ++i) {
    const Vec3& x = solver.particles().positions[i];
    const Vec3& v = solver.particles().velocities[i];
    sum += x.x() + 2.0 * x.y() + 3.0 * x.z() + 5.0 * v.x() + 7.0 * v.y() + 11.0 * v.z();
  }
  std::printf("explicit falling cube: time %a, checksum %a, smallest force limit %a\n", solver.time(), sum,
              dt_force);
  EXPECT_EQ(solver.time(), 0x1.1bc779ef0d4e8p-6);
  EXPECT_EQ(sum, 0x1.71d3d39fec595p+11);
  EXPECT_EQ(dt_force, 0x1.ccbd842e40c1dp-12);
}

/// Mean particle height of the scene file's cube (K_e = 2.4e7, `implicit_goal` as given, soft pressure
/// K = 1) resting on the floor plane of its box under gravity at the fixed step `dt`, run through
/// makeSphSolver: averaged over the steps of the last `average` seconds of `duration`, minus the mean height
/// at rest (no gravity). `no_environment`: the solids' planes and gravity taken away again.
double sceneFileSag(const std::string& implicit_goal, double dt, double duration, double average,
                    bool no_environment = false) {
  char text[1024];
  std::snprintf(
      text, sizeof text,
      "dimension: 3\nspacing: 0.07\nenable: [elasticity]\n"
      "solver: {smoothing_ratio: 2, rest_density: 1, stiffness: 1, gamma: 1, "
      "negative_pressure_scale: 0.01, xsph: 0, gravity: [0, -9.81, 0], fixed_dt: %.17g, threads: 1}\n"
      "solids:\n  - {lo: [-0.175, 0, -0.175], hi: [0.175, 0.35, 0.175], model: goal_position, "
      "goal_stiffness: 2.4e7, implicit_goal: %s}\n"
      "boundary:\n  box_planes:\n    - {lo: [-1, 0, -1], hi: [1, 2, 1]}\n"
      "frames: {count: 1, time: 0.01}\n",
      dt, implicit_goal.c_str());
  const SphScene scene = parseSphScene(text, "resting_cube.yaml");
  SphFluidSolver solver = makeSphSolver(scene);
  SphParticles& p = solver.particles();
  double low = std::numeric_limits<double>::infinity(), rest = 0.0;
  for (const Vec3& x : p.positions) low = std::min(low, x.y());
  for (Vec3& x : p.positions) {
    x.y() -= low;  // the bottom layer on the floor
    rest += x.y() / double(p.size());
  }
  solver.particlesChanged();
  if (no_environment)
    for (const auto& term : solver.forceTerms())
      if (auto* solid = dynamic_cast<SphElasticSolid*>(term.get())) solid->setEnvironment({}, Vec3::Zero());
  return rest - meanHeightOverLastSteps(solver, duration, average, dt);
}

// The scene runner gives the global springs the scene's planes and gravity (makeSphSolver): a scene-file
// cube with `implicit_goal: global` at 30x the explicit limit rests on the floor with the sag of the
// explicit forces (8.31) at 0.8x (within 3%, as GlobalSpringsKeepTheStaticSagAtLargeSteps); without its
// environment it sinks in by dt^2 times the floor's reaction acceleration.
TEST(SphImplicitGoal, SceneFileGlobalSpringsGetTheFloorAndKeepTheSag) {
  const double limit = explicitLimit(kStiffness);
  const double sag_explicit = sceneFileSag("false", 0.8 * limit, 0.3, 0.25);
  const double sag_global = sceneFileSag("global", 30.0 * limit, 0.3, 0.1);
  const double sag_bare = sceneFileSag("global", 30.0 * limit, 0.3, 0.1, true);
  std::printf("scene file cube, sag under gravity: explicit %.4g m, global 30x %.4g m (no planes: %.4g m)\n",
              sag_explicit, sag_global, sag_bare);
  EXPECT_GT(sag_explicit, 0.0);
  EXPECT_NEAR(sag_global, sag_explicit, 0.03 * sag_explicit);
  EXPECT_GT(sag_bare, 1.5 * sag_explicit);
}

// Two stiff cubes (global springs at 30x the explicit limit) colliding head-on at 6 m/s with the implicit
// penalty (K_c = 1e7). Without the bodies' stiffness in the contact springs a contact moves a surface
// particle by the whole overlap in one step, straining the stiff cube by it: the kinetic energy grows
// 17-fold. With setObjectStiffness(K_e) it does not grow, the cubes keep their shape and every step is the
// capped one.
TEST(SphImplicitGoal, ContactSpringsSeeTheBodyStiffness) {
  auto collide = [](bool body_stiffness, double& max_kinetic, double& max_strain, int& steps) {
    SphFluidConfig config = diceConfig();
    config.fixed_dt = 0.0;
    SphElasticConfig material = globalMaterial();
    material.implicit_step_factor = 30.0;
    Cube pair = makeCubes(config, material, {Vec3(-0.25, 0.5, 0), Vec3(0.25, 0.5, 0)},
                          {Vec3(3.0, 0, 0), Vec3(-3.0, 0, 0)}, Mat3::Identity(), 1.0, Vec3::Zero(), 0.0);
    SphObjectPenaltyConfig contact;
    contact.stiffness = 1e7;
    contact.contact_distance = kSpacing;
    contact.implicit = true;
    auto penalty = std::make_shared<SphObjectPenalty>(contact, SphKernels(3, config.smoothing_length));
    EXPECT_THROW(penalty->setObjectStiffness(1, -1.0), std::invalid_argument);
    if (body_stiffness)
      for (uint8_t phase : {1, 2}) penalty->setObjectStiffness(phase, kStiffness);
    SphFluidSolver& solver = *pair.solver;
    solver.addForceTerm(penalty);
    solver.computeForces();
    const double kinetic0 = solver.lastStats().kinetic_energy;
    max_kinetic = kinetic0;
    max_strain = 0.0;
    steps = 0;
    while (solver.time() < 0.05) {
      max_kinetic = std::max(max_kinetic, solver.step().kinetic_energy);
      for (const auto& solid : pair.solids) max_strain = std::max(max_strain, solid->stats().max_strain);
      ++steps;
    }
    std::printf("cubes collide, body stiffness %s: %d steps, kinetic %.4g -> max %.4g, max strain %.3g\n",
                body_stiffness ? "on" : "off", steps, kinetic0, max_kinetic, max_strain);
    return kinetic0;
  };
  double max_kinetic = 0.0, max_strain = 0.0;
  int steps = 0;
  const double kinetic0 = collide(false, max_kinetic, max_strain, steps);
  EXPECT_GT(max_kinetic, 5.0 * kinetic0);
  collide(true, max_kinetic, max_strain, steps);
  EXPECT_EQ(steps, int(std::ceil(0.05 / (30.0 * 0.4 * explicitLimit(kStiffness)))));  // all at the cap
  EXPECT_LE(max_kinetic, kinetic0 * (1.0 + 1e-3));
  EXPECT_LT(max_strain, 0.1);
}

/// Two stiff cubes (global springs at 30x the explicit limit, K_e = 2.4e7) at (-0.25 - gap / 2) and
/// (0.25 + gap / 2) moving at +-`speed` along x, with the implicit penalty (K_c = 1e7, d) added after them
/// and, if `coupled`, their contacts in the coupled solve (SphObjectPenalty::coupleGlobalImplicit).
struct CubePair {
  Cube cubes;
  std::shared_ptr<SphObjectPenalty> penalty;
};

CubePair cubePair(double speed, double gap, bool coupled, double fixed_dt = 0.0) {
  SphFluidConfig config = diceConfig();
  config.fixed_dt = fixed_dt;
  SphElasticConfig material = globalMaterial();
  material.implicit_step_factor = 30.0;
  CubePair pair;
  pair.cubes = makeCubes(config, material, {Vec3(-0.25 - 0.5 * gap, 0.5, 0), Vec3(0.25 + 0.5 * gap, 0.5, 0)},
                         {Vec3(speed, 0, 0), Vec3(-speed, 0, 0)}, Mat3::Identity(), 1.0, Vec3::Zero(), 0.0);
  SphObjectPenaltyConfig contact;
  contact.stiffness = 1e7;
  contact.contact_distance = kSpacing;
  contact.implicit = true;
  pair.penalty = std::make_shared<SphObjectPenalty>(contact, SphKernels(3, config.smoothing_length));
  for (uint8_t phase : {1, 2}) pair.penalty->setObjectStiffness(phase, kStiffness);
  if (coupled)
    for (auto& solid : pair.cubes.solids) pair.penalty->coupleGlobalImplicit(*solid);
  pair.cubes.solver->addForceTerm(pair.penalty);
  return pair;
}

// The coupled solve (contacts in the solids' backward Euler system): the head-on collision at 6 m/s never
// gains kinetic energy, keeps linear and angular momentum per step to 1e-12 while the contacts push, the
// cubes bounce apart without passing into each other, and every step is the capped one.
TEST(SphImplicitGoal, CoupledContactsCollideWithoutEnergyGainAndKeepMomentum) {
  CubePair pair = cubePair(3.0, 0.0, true);
  SphFluidSolver& solver = *pair.cubes.solver;
  solver.computeForces();
  const double kinetic0 = solver.lastStats().kinetic_energy;
  double max_kinetic = kinetic0, max_strain = 0.0, min_distance = kSpacing;
  int steps = 0, contact_steps = 0;
  size_t max_pushing = 0;
  double worst_linear = 0.0, worst_angular = 0.0;
  while (solver.time() < 0.05) {
    const MomentumDrift m = trackMomentum(solver.particles(), 1, [&] { solver.step(); });
    max_kinetic = std::max(max_kinetic, solver.lastStats().kinetic_energy);
    for (const auto& solid : pair.cubes.solids) max_strain = std::max(max_strain, solid->stats().max_strain);
    min_distance = std::min(min_distance, pair.penalty->stats().min_distance);
    const size_t pushing = pair.penalty->couplingStats().active_contacts;
    max_pushing = std::max(max_pushing, pushing);
    if (pushing > 0) {
      ++contact_steps;
      worst_linear = std::max(worst_linear, m.worst_linear);
      worst_angular = std::max(worst_angular, m.worst_angular);
    }
    ++steps;
  }
  double v_left = 0.0;
  size_t n_left = 0;
  const SphParticles& p = solver.particles();
  for (size_t i = 0; i < p.size(); ++i)
    if (p.phases[i] == 1) {
      v_left += p.velocities[i].x();
      ++n_left;
    }
  v_left /= double(n_left);
  std::printf(
      "coupled contacts, cubes at 6 m/s: %d steps (%d with contacts, <= %zu pushing), kinetic %.4g -> max "
      "%.4g, max strain %.3g, min distance %.4g, left cube after %.3g m/s, dP %.2e dL %.2e per step\n",
      steps, contact_steps, max_pushing, kinetic0, max_kinetic, max_strain, min_distance, v_left,
      worst_linear, worst_angular);
  EXPECT_EQ(steps, int(std::ceil(0.05 / (30.0 * 0.4 * explicitLimit(kStiffness)))));  // all at the cap
  EXPECT_GT(contact_steps, 2);
  EXPECT_LE(max_kinetic, kinetic0 * (1.0 + 1e-3));
  EXPECT_LT(max_strain, 0.1);
  EXPECT_GT(min_distance, 0.4 * kSpacing);
  EXPECT_LT(v_left, 0.0);  // bounced back
  EXPECT_LT(worst_linear, 1e-12);
  EXPECT_LT(worst_angular, 1e-12);
}

enum class ContactMode { kExplicit, kLocal, kCoupled };

struct Pressed {
  double overlap = 0.0;    ///< d - r_min
  double approach = 0.0;   ///< of the cubes' centres along x from touching
  size_t max_pushing = 0;  ///< the most contact springs that pushed in a coupled solve
};

/// Overlap d - r_min and approach of the centres of two stiff cubes (side 0.21, K_e = 2.4e7) pressed together
/// from touching at rest: gravity 2000 m/s^2 along -x, cube 1 resting on the wall plane x = const, cube 2 on
/// cube 1, both in a channel of planes along x; penalty K_c = 1e7 with damping 3000 / s. Explicit goal forces
/// and penalty at 0.4x their limits, averaged over the last 0.02 s of 0.08 s; or global springs at 30x the
/// explicit limit (the wall and gravity in their solve) with the local (kLocal) or the coupled (kCoupled)
/// contact springs, averaged over the last 0.03 s of 0.12 s.
Pressed pressedCubes(ContactMode mode) {
  SphFluidConfig config = diceConfig();
  const SphKernels kernels(3, config.smoothing_length);
  const SphLattice lattice(3, kSpacing);
  const double mass = lattice.particleMass(kernels, config.rest_density);
  SphElasticConfig material = mode == ContactMode::kExplicit ? diceMaterial(false) : globalMaterial();
  SphObjectPenaltyConfig contact;
  contact.stiffness = 1e7;
  contact.contact_distance = kSpacing;
  contact.damping = 3000.0;
  contact.implicit = mode != ContactMode::kExplicit;
  // One lattice box split at x = 0: the cubes touch with their lattice continued across the interface
  // (the closest pairs at the contact distance d, no force).
  const std::vector<Vec3> points =
      sampleLatticeBox(lattice, Vec3(-0.21, 0.395, -0.105), Vec3(0.21, 0.605, 0.105));
  std::vector<Vec3> halves[2];
  for (const Vec3& x : points) halves[x.x() < -1e-9 ? 0 : 1].push_back(x);
  SphParticles particles;
  std::vector<std::shared_ptr<SphElasticSolid>> solids;
  for (int k = 0; k < 2; ++k) {
    auto solid = std::make_shared<SphElasticSolid>(material, kernels, uint8_t(k + 1));
    solid->addParticles(particles, halves[k], mass);
    solids.push_back(solid);
  }
  auto penalty = std::make_shared<SphObjectPenalty>(contact, kernels);
  const double explicit_dt =
      0.4 * std::min(std::sqrt(2.0 / kStiffness), penalty->stableTimeStep(particles, 1.0));
  config.fixed_dt = mode == ContactMode::kExplicit ? explicit_dt : 30.0 * 0.4 * explicitLimit(kStiffness);
  config.gravity = Vec3(-2000.0, 0.0, 0.0);
  if (mode == ContactMode::kExplicit) config.viscosity = 0.2;  // damps its bouncing (stable at its step)
  SphPlane wall;
  wall.normal = Vec3::UnitX();
  wall.offset = std::numeric_limits<double>::infinity();
  for (const Vec3& x : particles.positions) wall.offset = std::min(wall.offset, x.x());
  // A channel of planes along x around both cubes keeps them from sliding off each other.
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec3& x : particles.positions) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  SphFluidSolver solver(config, std::move(particles));
  solver.addPlane(wall);
  for (int axis : {1, 2}) {
    SphPlane side;
    side.normal = Vec3::Unit(axis);
    side.offset = lo[axis] - 1e-3;
    solver.addPlane(side);
    side.normal = -Vec3::Unit(axis);
    side.offset = -hi[axis] - 1e-3;
    solver.addPlane(side);
  }
  for (auto& solid : solids) {
    solid->setEnvironment(solver.planes(), config.gravity);
    solver.addForceTerm(solid);
    if (mode == ContactMode::kCoupled) penalty->coupleGlobalImplicit(*solid);
    penalty->setObjectStiffness(solid->phase(), kStiffness);
  }
  solver.addForceTerm(penalty);
  const double duration = mode == ContactMode::kExplicit ? 0.25 : 0.12;
  const double average = mode == ContactMode::kExplicit ? 0.088 : 0.03;  // explicit: 4 of its bounces
  // Approach of the cubes' centres along x from touching.
  const auto centreDistance = [&] {
    const SphParticles& p = solver.particles();
    double c[2] = {0.0, 0.0}, n[2] = {0.0, 0.0};
    for (size_t i = 0; i < p.size(); ++i) {
      c[p.phases[i] - 1] += p.positions[i].x();
      n[p.phases[i] - 1] += 1.0;
    }
    return c[1] / n[1] - c[0] / n[0];
  };
  const double touching = centreDistance();
  Pressed out;
  int samples = 0;
  while (solver.time() < duration - 0.5 * config.fixed_dt) {
    solver.step();
    out.max_pushing = std::max(out.max_pushing, penalty->couplingStats().active_contacts);
    if (solver.time() > duration - average) {
      out.overlap += kSpacing - penalty->stats().min_distance;
      out.approach += touching - centreDistance();
      ++samples;
    }
  }
  out.overlap /= double(samples);
  out.approach /= double(samples);
  return out;
}

// Two stiff cubes pressed together at rest reach the overlap of the explicit penalty (8.37) (measured: 0.53 %
// deeper, the centres' approach 1.1 % larger) with the contact springs in the coupled solve at 30x the
// explicit limit; the local contact springs, softened by 1 + dt^2 K_e, let them sink 6.5x deeper.
TEST(SphImplicitGoal, CoupledContactsReachTheExplicitEquilibriumOverlap) {
  const Pressed reference = pressedCubes(ContactMode::kExplicit);
  const Pressed coupled = pressedCubes(ContactMode::kCoupled);
  const Pressed local = pressedCubes(ContactMode::kLocal);
  std::printf(
      "pressed cubes, overlap d - r_min / approach of the centres: explicit %.5g / %.5g m, coupled 30x %.5g "
      "/ %.5g m (%+.2f %% / %+.2f %%, %zu springs push), local 30x %.4g / %.4g m\n",
      reference.overlap, reference.approach, coupled.overlap, coupled.approach,
      100.0 * (coupled.overlap / reference.overlap - 1.0),
      100.0 * (coupled.approach / reference.approach - 1.0), coupled.max_pushing, local.overlap,
      local.approach);
  EXPECT_GT(reference.overlap, 0.002);
  EXPECT_GT(coupled.max_pushing, 10u);
  EXPECT_NEAR(coupled.overlap, reference.overlap, 0.01 * reference.overlap);     // measured 0.53 %
  EXPECT_NEAR(coupled.approach, reference.approach, 0.02 * reference.approach);  // measured 1.1 %
  EXPECT_GT(local.overlap, 5.0 * reference.overlap);                             // measured 6.5x
}

// Coupling needs implicit contact springs and solids with global implicit goal springs, and the penalty
// evaluated after the solids it couples; makeSphSolver couples the dice of the shipped scene.
TEST(SphImplicitGoal, CouplingChecksItsTermsAndTheirOrder) {
  const SphKernels kernels(3, 2.0 * kSpacing);
  SphObjectPenaltyConfig contact;
  contact.contact_distance = kSpacing;
  SphObjectPenalty explicit_penalty(contact, kernels);
  SphElasticSolid global_solid(globalMaterial(), kernels, 1), local_solid(diceMaterial(true), kernels, 2);
  EXPECT_THROW(explicit_penalty.coupleGlobalImplicit(global_solid), std::invalid_argument);
  contact.implicit = true;
  SphObjectPenalty penalty(contact, kernels);
  EXPECT_THROW(penalty.coupleGlobalImplicit(local_solid), std::invalid_argument);
  penalty.coupleGlobalImplicit(global_solid);
  penalty.coupleGlobalImplicit(global_solid);  // once only
  EXPECT_EQ(penalty.coupledSolids(), 1u);
  EXPECT_EQ(global_solid.implicitCoupling() != nullptr, true);

  // The penalty added before the solids: their systems are not there when it solves.
  CubePair pair = cubePair(3.0, 0.0, false, 30.0 * 0.4 * explicitLimit(kStiffness));
  SphFluidConfig config = diceConfig();
  auto early = std::make_shared<SphObjectPenalty>(pair.penalty->config(), kernels);
  SphFluidSolver solver(config, pair.cubes.solver->particles());
  solver.addForceTerm(early);
  for (auto& solid : pair.cubes.solids) {
    early->coupleGlobalImplicit(*solid);
    solver.addForceTerm(solid);
  }
  EXPECT_THROW(solver.step(), std::logic_error);

  const SphScene dice = loadSphScene(sphSceneDir() + "dice_3d.yaml");
  SphFluidSolver scene_solver = makeSphSolver(dice);
  size_t coupled = 0;
  for (const auto& term : scene_solver.forceTerms())
    if (const auto* p = dynamic_cast<const SphObjectPenalty*>(term.get())) coupled = p->coupledSolids();
  EXPECT_EQ(coupled, 9u);
}

// The coupled solve of two random spring systems joined by five contact springs: one group; its forces
// reproduce M dv / dt (the CG tolerance), have no net force or torque, and the contact that separates fast
// lets go ((8.37) never pulls); without contacts each system is solved alone.
TEST(SphImplicitGoal, CoupledSystemKeepsMomentumAndReleasesPullingContacts) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const size_t n = 20;
  SphImplicitGoalSolver solvers[2];
  std::vector<uint32_t> particles[2];
  std::vector<Vec3> x[2], f0[2], v[2], dv[2], force[2], all_x(2 * n);
  for (int b = 0; b < 2; ++b) {
    std::vector<double> masses(n);
    std::vector<std::vector<SphGoalSpring>> springs(n);
    for (size_t s = 0; s < n; ++s) {
      x[b].push_back(Vec3(0.5 * uni(rng) + (b == 0 ? -0.5 : 0.5), 0.5 * uni(rng), 0.5 * uni(rng)));
      f0[b].push_back(Vec3(uni(rng), uni(rng), uni(rng)));
      v[b].push_back(Vec3(uni(rng), uni(rng), uni(rng)));
      masses[s] = 1.0 + 0.5 * uni(rng);
      particles[b].push_back(uint32_t(b * n + s));
      all_x[b * n + s] = x[b][s];
    }
    for (size_t s = 0; s < n; ++s)
      for (size_t j = 0; j < n; ++j)
        if (j != s && (x[b][j] - x[b][s]).norm() < 0.5)
          springs[s].push_back({uint32_t(j), 1e3 * (1.5 + uni(rng))});
    solvers[b].setSystem(x[b], masses, springs);
    solvers[b].removeNetForceAndTorque(f0[b]);  // goal forces have none (8.32)-(8.33)
  }
  std::vector<SphContactSpring> contacts;
  for (size_t k = 0; k < 5; ++k) {
    SphContactSpring c;
    c.first = uint32_t(k);
    c.second = uint32_t(n + k);
    c.normal = (all_x[c.second] - all_x[c.first]).normalized();
    c.force = 2.0;
    c.stiffness = 1e3;
    c.damping = 0.5;
    contacts.push_back(c);
  }
  v[1][0] += 50.0 * contacts[0].normal;  // contact 0 separates fast: it would pull
  for (size_t k = 1; k < 5; ++k) v[1][k] -= 5.0 * contacts[k].normal;  // the others close
  const double dt = 0.05;
  auto solve = [&](const std::vector<SphContactSpring>& springs, std::vector<Vec3>& forces) {
    SphImplicitGoalCoupling coupling;
    forces.assign(2 * n, Vec3::Zero());
    for (int b = 0; b < 2; ++b) {
      dv[b].assign(n, Vec3::Zero());
      SphImplicitGoalBlock block;
      block.solver = &solvers[b];
      block.particles = &particles[b];
      block.f0 = &f0[b];
      block.velocity = &v[b];
      block.dv = &dv[b];
      block.force = &force[b];
      block.dt = dt;
      block.tolerance = 1e-12;
      block.max_iterations = 1000;
      coupling.submit(block);
    }
    EXPECT_THROW(coupling.submit(SphImplicitGoalBlock{}), std::invalid_argument);
    return coupling.solve(springs, forces);
  };
  std::vector<Vec3> forces;
  const SphImplicitCouplingStats st = solve(contacts, forces);
  Vec3 net = Vec3::Zero(), torque = Vec3::Zero();
  double scale = 0.0, mismatch = 0.0;
  for (int b = 0; b < 2; ++b)
    for (size_t s = 0; s < n; ++s) {
      const Vec3& f = forces[b * n + s];
      net += f;
      torque += all_x[b * n + s].cross(f);
      scale += f.norm();
      mismatch = std::max(mismatch, (f - solvers[b].masses()[s] / dt * dv[b][s]).norm());
    }
  std::printf(
      "coupled system: %zu group(s), %zu pushing, %zu released, %d CG iterations, |net force| %.2e, "
      "|torque| %.2e, max |F - M dv / dt| %.2e (scale %.3g)\n",
      st.groups, st.active_contacts, st.released_contacts, st.iterations, net.norm(), torque.norm(), mismatch,
      scale);
  EXPECT_EQ(st.groups, 1u);
  EXPECT_EQ(st.coupled_solids, 2u);
  EXPECT_GE(st.released_contacts, 1u);
  EXPECT_GE(st.active_contacts, 1u);
  EXPECT_LE(st.active_contacts + st.released_contacts, 5u);
  EXPECT_GT(st.iterations, 0);
  EXPECT_LT(net.norm(), 1e-12 * scale);
  EXPECT_LT(torque.norm(), 1e-12 * scale);
  EXPECT_LT(mismatch, 1e-8 * scale / double(2 * n));
  // Without contacts: two groups, each solved alone, again without net force.
  const SphImplicitCouplingStats alone = solve({}, forces);
  net.setZero();
  for (const Vec3& f : forces) net += f;
  EXPECT_EQ(alone.groups, 2u);
  EXPECT_EQ(alone.coupled_solids, 0u);
  EXPECT_LT(net.norm(), 1e-12 * scale);
  // A contact with an end outside the blocks is an error.
  SphContactSpring stray = contacts[1];
  stray.second = uint32_t(5 * n);
  EXPECT_THROW(solve({stray}, forces), std::invalid_argument);
}

}  // namespace
}  // namespace rc
