// Penalty collision handling between objects (thesis 8.2.6, (8.37)).
#include "relaxed_connectivity/sph/sph_object_penalty.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_lattice.h"

namespace rc {
namespace {

SphParticles twoParticles(double distance, uint8_t phase_a, uint8_t phase_b) {
  SphParticles p;
  p.add(Vec3(0.1, 0.2, 0.0), Vec3::Zero(), 2.0, SphParticleKind::kFluid);
  p.add(Vec3(0.1, 0.2, 0.0) + distance * Vec3(0.6, 0.8, 0.0), Vec3::Zero(), 3.0, SphParticleKind::kFluid);
  p.phases = {phase_a, phase_b};
  return p;
}

TEST(SphObjectPenalty, ConfigIsValidated) {
  const SphKernels kernels(2, 0.1);
  SphObjectPenaltyConfig c;
  c.contact_distance = 0.05;
  EXPECT_NO_THROW(SphObjectPenalty(c, kernels));
  SphObjectPenaltyConfig bad = c;
  bad.stiffness = 0.0;
  EXPECT_THROW(SphObjectPenalty(bad, kernels), std::invalid_argument);
  bad = c;
  bad.damping = -1.0;
  EXPECT_THROW(SphObjectPenalty(bad, kernels), std::invalid_argument);
  bad = c;
  bad.contact_distance = 0.11;  // beyond h
  EXPECT_THROW(SphObjectPenalty(bad, kernels), std::invalid_argument);
  bad.contact_distance = std::nan("");
  EXPECT_THROW(SphObjectPenalty(bad, kernels), std::invalid_argument);
}

TEST(SphObjectPenalty, PairForceIsCentralRepulsiveAntisymmetricAndConservative) {
  const double h = 0.1, d = 0.05, r = 0.035;
  const SphKernels kernels(2, h);
  SphObjectPenaltyConfig c;
  c.stiffness = 1.0e4;
  c.contact_distance = d;
  SphObjectPenalty penalty(c, kernels);
  EXPECT_NEAR(penalty.particleVolume(), std::sqrt(0.75) * d * d, 1e-18);
  SphParticles p = twoParticles(r, 1, 2);
  std::vector<Vec3> f;
  penalty.computeForces(p, f);
  const Vec3 n(0.6, 0.8, 0.0);
  const double mean_mass = 2.5;
  const double expected = mean_mass * penalty.particleVolume() * kernels.poly6(r * r) * c.stiffness * (d - r);
  EXPECT_NEAR(f[1].dot(n), expected, 1e-12 * expected);  // pushes j away from i
  EXPECT_NEAR((f[1] - f[1].dot(n) * n).norm(), 0.0, 1e-12 * expected);
  EXPECT_EQ(f[0] + f[1], Vec3::Zero());  // exactly antisymmetric
  EXPECT_EQ(penalty.stats().objects, 2u);
  EXPECT_EQ(penalty.stats().contact_pairs, 1u);
  EXPECT_EQ(penalty.stats().repulsive_pairs, 1u);
  EXPECT_NEAR(penalty.stats().min_distance, r, 1e-15);
  // The force is the negative gradient of the reported energy.
  auto energyAt = [&](double dist) {
    SphParticles q = twoParticles(dist, 1, 2);
    std::vector<Vec3> g;
    penalty.computeForces(q, g);
    return penalty.potentialEnergy();
  };
  const double eps = 1e-6;
  EXPECT_NEAR(-(energyAt(r + eps) - energyAt(r - eps)) / (2 * eps), expected, 1e-6 * expected);
  EXPECT_EQ(energyAt(d + 1e-9), 0.0);
  EXPECT_GT(energyAt(0.5 * d), energyAt(r));
  // Same object, fluid, or boundary: no penalty.
  for (auto phases : {std::pair<int, int>{1, 1}, {0, 2}, {0, 0}}) {
    SphParticles q = twoParticles(r, uint8_t(phases.first), uint8_t(phases.second));
    penalty.computeForces(q, f);
    EXPECT_EQ(f[0], Vec3::Zero());
    EXPECT_EQ(f[1], Vec3::Zero());
    EXPECT_TRUE(std::isinf(penalty.stableTimeStep(q, 0.4)));
  }
  SphParticles wall = twoParticles(r, 1, 2);
  wall.kinds[0] = SphParticleKind::kStaticBoundary;
  penalty.computeForces(wall, f);
  EXPECT_EQ(f[1], Vec3::Zero());
  EXPECT_EQ(penalty.stats().objects, 1u);
}

TEST(SphObjectPenalty, DampingIsProjectedAndNeverPulls) {
  const double h = 0.1, d = 0.05, r = 0.04;
  const SphKernels kernels(3, h);
  SphObjectPenaltyConfig c;
  c.stiffness = 1.0e4;
  c.contact_distance = d;
  c.damping = 50.0;
  SphObjectPenalty penalty(c, kernels);
  const Vec3 n(0.6, 0.8, 0.0);
  const double scale = 2.5 * penalty.particleVolume() * kernels.poly6(r * r);
  const double spring = scale * c.stiffness * (d - r);
  std::vector<Vec3> f;
  // Approaching (and sliding: the tangential part is projected away by (8.37)).
  SphParticles p = twoParticles(r, 1, 2);
  const Vec3 tangent(0.8, -0.6, 0.0);
  p.velocities[1] = -0.1 * n + 3.0 * tangent;
  penalty.computeForces(p, f);
  EXPECT_NEAR(f[1].dot(n), spring + scale * c.damping * 0.1, 1e-12 * spring);
  EXPECT_NEAR(f[1].dot(tangent), 0.0, 1e-12 * spring);
  EXPECT_EQ(f[0] + f[1], Vec3::Zero());
  // Separating faster than the spring pushes: the damped force would pull, (8.37) drops it.
  p.velocities[1] = 10.0 * n;
  penalty.computeForces(p, f);
  EXPECT_EQ(f[1], Vec3::Zero());
  EXPECT_EQ(penalty.stats().contact_pairs, 1u);
  EXPECT_EQ(penalty.stats().repulsive_pairs, 0u);
  // The step limit tightens with damping and stiffness.
  const double dt = penalty.stableTimeStep(p, 0.4);
  EXPECT_TRUE(std::isfinite(dt));
  c.damping = 0.0;
  EXPECT_GT(SphObjectPenalty(c, kernels).stableTimeStep(p, 0.4), dt);
}

/// Two 2D goal-position blocks (objects 1 and 2) flying at each other, the second rotated.
struct Collision {
  std::unique_ptr<SphFluidSolver> solver;
  std::shared_ptr<SphObjectPenalty> penalty;
  size_t first_b = 0;
};

Collision makeCollision(double d, double gap, double speed, bool with_penalty) {
  SphFluidConfig config;
  config.dimension = 2;
  config.smoothing_length = 2.0 * d;
  config.rest_density = 1000.0;
  config.stiffness = 100.0;  // weak fluid pressure (it also acts between the objects)
  config.gravity = Vec3::Zero();
  config.viscosity = 0.0;
  config.xsph = 0.0;
  config.num_threads = 1;
  const SphKernels kernels(2, config.smoothing_length);
  SphElasticConfig e;
  e.model = SphElasticModel::kGoalPosition;
  e.lattice_spacing = d;
  e.goal_stiffness = 1.0e4;
  const double size = 7.0 * d;
  SphParticles particles;
  const SphLattice lattice(2, d);
  const double mass = lattice.particleMass(kernels, config.rest_density);
  auto a = std::make_shared<SphElasticSolid>(e, kernels, 1);
  a->addParticles(particles, sampleLatticeBox(lattice, Vec3(-size, 0, 0), Vec3(0, size, 0)), mass,
                  Vec3(speed, 0, 0));
  SphLatticeFrame frame;
  frame.orientation = Eigen::AngleAxisd(0.2, Vec3::UnitZ()).toRotationMatrix();
  frame.origin = Vec3(gap, 0.3 * d, 0);
  // An axis-aligned box filled with the rotated lattice: a ragged contact face.
  const std::vector<Vec3> points_b =
      sampleLatticeBox(lattice, frame.origin, frame.origin + Vec3(size, size, 0), frame);
  auto b = std::make_shared<SphElasticSolid>(e, kernels, 2, frame.orientation);
  Collision col;
  col.first_b = b->addParticles(particles, points_b, mass, Vec3(-speed, 0, 0));
  col.solver = std::make_unique<SphFluidSolver>(config, std::move(particles));
  col.solver->addForceTerm(a);
  col.solver->addForceTerm(b);
  if (with_penalty) {
    SphObjectPenaltyConfig pc;
    pc.stiffness = 2.0 * e.goal_stiffness;
    pc.contact_distance = d;
    col.penalty = std::make_shared<SphObjectPenalty>(pc, col.solver->kernels());
    col.solver->addForceTerm(col.penalty);
  }
  return col;
}

double minObjectDistance(const SphParticles& p, size_t first_b) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < first_b; ++i)
    for (size_t j = first_b; j < p.size(); ++j)
      best = std::min(best, (p.positions[j] - p.positions[i]).norm());
  return best;
}

Vec3 meanVelocity(const SphParticles& p, size_t begin, size_t end) {
  Vec3 v = Vec3::Zero();
  for (size_t i = begin; i < end; ++i) v += p.velocities[i];
  return v / double(end - begin);
}

TEST(SphObjectPenalty, FarApartObjectsFeelNoForce) {
  const double d = 0.05;
  for (double gap : {1.2 * d, 3.0 * d}) {
    Collision col = makeCollision(d, gap, 0.0, true);
    std::vector<Vec3> f;
    col.penalty->computeForces(col.solver->particles(), f);
    ASSERT_GT(minObjectDistance(col.solver->particles(), col.first_b), d);
    for (const Vec3& x : f) EXPECT_EQ(x, Vec3::Zero());
    EXPECT_EQ(col.penalty->stats().objects, 2u);
    EXPECT_EQ(col.penalty->stats().contact_pairs, 0u);
    EXPECT_EQ(col.penalty->potentialEnergy(), 0.0);
  }
  Collision touching = makeCollision(d, 0.7 * d, 0.0, true);
  std::vector<Vec3> f;
  touching.penalty->computeForces(touching.solver->particles(), f);
  EXPECT_GT(touching.penalty->stats().repulsive_pairs, 0u);
  Vec3 on_b = Vec3::Zero();
  for (size_t i = touching.first_b; i < f.size(); ++i) on_b += f[i];
  EXPECT_GT(on_b.x(), 0.0);  // pushes B (on the right) away
}

TEST(SphObjectPenalty, ElasticBlocksCollideWithoutInterpenetratingAndBounce) {
  const double d = 0.05, speed = 0.5, duration = 0.6;
  double min_without = 0.0;
  for (bool with_penalty : {true, false}) {
    Collision col = makeCollision(d, 1.5 * d, speed, with_penalty);
    SphFluidSolver& solver = *col.solver;
    const SphParticles& p = solver.particles();
    const size_t n = p.size();
    double momentum_scale = 0.0;
    Vec3 initial_momentum = Vec3::Zero();
    for (size_t i = 0; i < n; ++i) {
      momentum_scale += p.masses[i] * p.velocities[i].norm();
      initial_momentum += p.masses[i] * p.velocities[i];
    }
    double min_distance = minObjectDistance(p, col.first_b), max_drift = 0.0;
    size_t max_repulsive = 0;
    while (solver.time() < duration) {
      solver.step();
      min_distance = std::min(min_distance, minObjectDistance(p, col.first_b));
      Vec3 momentum = -initial_momentum;
      for (size_t i = 0; i < n; ++i) momentum += p.masses[i] * p.velocities[i];
      max_drift = std::max(max_drift, momentum.norm() / momentum_scale);
      if (with_penalty) max_repulsive = std::max(max_repulsive, col.penalty->stats().repulsive_pairs);
    }
    const Vec3 va = meanVelocity(p, 0, col.first_b), vb = meanVelocity(p, col.first_b, n);
    std::printf(
        "collision %s penalty: %zu particles, %llu steps (dt %.3g), min distance %.4f d, momentum drift "
        "%.2g, "
        "max repulsive pairs %zu, final mean vx %.3f | %.3f (initial +-%.2f), final distance %.3f d\n",
        with_penalty ? "with" : "without", n, (unsigned long long)solver.stepCount(), solver.lastStats().dt,
        min_distance / d, max_drift, max_repulsive, va.x(), vb.x(), speed,
        minObjectDistance(p, col.first_b) / d);
    EXPECT_LT(max_drift, 1e-12);  // all forces are pairwise antisymmetric
    if (!with_penalty) {
      min_without = min_distance;
      continue;
    }
    EXPECT_GT(min_distance, 0.6 * d);  // no interpenetration
    EXPECT_GT(max_repulsive, 5u);
    // Bounced: both blocks reversed and separate at more than 40% of the approach speed (the rest went
    // into vibration and rotation of the elastic blocks).
    EXPECT_LT(va.x(), 0.0);
    EXPECT_GT(vb.x(), 0.0);
    EXPECT_GT(vb.x() - va.x(), 0.4 * 2.0 * speed);
    EXPECT_GT(minObjectDistance(p, col.first_b), d);  // separated at the end
  }
  // Control: without the penalty only the weak fluid pressure acts and the blocks pass through each other.
  EXPECT_LT(min_without, 0.3 * d);
}

}  // namespace
}  // namespace rc
