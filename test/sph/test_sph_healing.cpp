// Healing of fractured elastic solids through docking (thesis 8.2.5): the docking rates are per unit time
// (the docking process does not depend on the step), and pieces that are put back together dock again
// and regain the stiffness of the unbroken solid.
#include "relaxed_connectivity/sph/sph_elastic_solid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_lattice.h"

namespace rc {
namespace {

constexpr double kSpacing = 0.02;  // d; h = 2 d as in the Fig. 8.7 scenes
constexpr double kDt = 2.5e-4;

/// h just below 2 d: the lattice points at exactly 2 d (weight 0) are outside the kernel, whatever the
/// rounding of the sampled positions.
SphKernels kernels2d() {
  return SphKernels(2, 2.0 * kSpacing * (1.0 - 1e-9));
}

std::vector<Vec3> hexBox(const Vec3& lo, const Vec3& hi) {
  return sampleLatticeBox(SphLattice(2, kSpacing), lo, hi);
}

/// A static lattice from which a sparse set of particles (no two adjacent) is away and then returns: every
/// lattice point of the others that one of them occupies on its return is free. away_time < 0: away from
/// the first evaluation on (the points never docked, rate 0); else at home at the first evaluation (docked
/// at max_rate), away for away_time (the rates decay), back. Returns the fraction of these points docked
/// after each of `evaluations` evaluations of step dt after the return; *free_points their number.
struct ReturnScenario {
  double growth = 0.0, decay = 0.0, max_rate = 1.0e9, away_time = -1.0, dt = 1e-3;
  int evaluations = 0;
};
std::vector<double> dockedFractionAfterReturn(const ReturnScenario& r, size_t* free_points) {
  SphElasticConfig e;
  e.lattice_spacing = kSpacing;
  e.goal_stiffness = 1.0e4;
  e.docking = true;
  e.docking_rate_increase = r.growth;
  e.docking_rate_decrease = r.decay;
  e.max_docking_rate = r.max_rate;
  e.time_step = r.dt;
  e.seed = 5;
  const SphKernels kernels = kernels2d();
  SphElasticSolid solid(e, kernels, 1);
  solid.beginStep(r.dt);
  const std::vector<Vec3> home = hexBox(Vec3(0, 0, 0), Vec3(0.5, 0.5, 0));
  SphParticles particles;
  solid.addParticles(particles, home, 1.0);
  // Returning particles: lattice indices (a, b) with (a + 3 b) % 7 == 0 (pairwise at least 2 d apart).
  std::vector<uint8_t> returning(home.size(), 0);
  std::vector<Vec3> away = home;
  for (size_t i = 0; i < home.size(); ++i) {
    const Eigen::Vector3i n = solid.lattice().nearestIndex(home[i]);
    returning[i] = ((n.x() + 3 * n.y()) % 7 + 7) % 7 == 0;
    if (returning[i]) away[i] += Vec3(100.0, 0, 0);
  }
  const auto stayingDocked = [&](const SphElasticSolid& s) {
    size_t sum = 0;
    for (size_t i = 0; i < home.size(); ++i)
      if (!returning[i]) sum += s.dockedCounts()[i];
    return sum;
  };
  std::vector<Vec3> forces;
  {
    SphElasticSolid full(e, kernels, 1);  // the whole lattice docked at its first evaluation
    full.computeForces(particles, forces);
    *free_points = stayingDocked(full);
  }
  particles.positions = away;
  if (r.away_time >= 0.0) {
    particles.positions = home;
    solid.computeForces(particles, forces);
    particles.positions = away;
    for (int k = 0; k < int(std::lround(r.away_time / r.dt)); ++k) solid.computeForces(particles, forces);
  } else {
    solid.computeForces(particles, forces);  // first evaluation: the others dock their occupied points
  }
  const size_t before = stayingDocked(solid);
  *free_points -= before;
  particles.positions = home;
  std::vector<double> fraction;
  for (int k = 0; k < r.evaluations; ++k) {
    solid.computeForces(particles, forces);
    fraction.push_back(double(stayingDocked(solid) - before) / double(*free_points));
  }
  return fraction;
}

/// The scenario at r.dt and at r.dt / 2 (twice the evaluations): the docked fractions of both, which must
/// see the same free points.
struct CoarseAndFine {
  std::vector<double> coarse, fine;
  size_t free_points = 0;
};
CoarseAndFine dockedFractionAtStepAndHalfStep(ReturnScenario r) {
  CoarseAndFine result;
  size_t free_fine = 0;
  result.coarse = dockedFractionAfterReturn(r, &result.free_points);
  r.dt *= 0.5;
  r.evaluations *= 2;
  result.fine = dockedFractionAfterReturn(r, &free_fine);
  EXPECT_EQ(result.free_points, free_fine);
  return result;
}

TEST(SphHealing, DockingTimeFollowsTheRateGrowthAtAnyStep) {
  // lambda_d = a t from 0: P(docked by t) = 1 - exp(-a t^2 / 2) (mean sqrt(pi / (2 a))), whatever the step.
  ReturnScenario r;
  r.growth = 1.0e4;
  r.dt = 1.0e-3;
  r.evaluations = 30;
  const CoarseAndFine runs = dockedFractionAtStepAndHalfStep(r);
  const std::vector<double>&coarse = runs.coarse, &fine = runs.fine;
  const size_t free_coarse = runs.free_points;
  EXPECT_GT(free_coarse, 1000u);                                        // 12 per returning particle
  const double tolerance = 4.0 * 0.5 / std::sqrt(double(free_coarse));  // 4 sigma of a binomial, at worst
  double worst_coarse = 0.0, worst_fine = 0.0, mean_time = 0.5e-3;      // trapezoid rule from S(0) = 1
  for (int n = 1; n <= 30; ++n) {
    const double t = n * 1e-3, expected = -std::expm1(-0.5 * r.growth * t * t);
    if (n % 5 == 0)
      std::printf("t %.3f s: docked %.3f (dt 1 ms) %.3f (dt 0.5 ms), analytic %.3f\n", t, coarse[n - 1],
                  fine[2 * n - 1], expected);
    worst_coarse = std::max(worst_coarse, std::abs(coarse[n - 1] - expected));
    worst_fine = std::max(worst_fine, std::abs(fine[2 * n - 1] - expected));
    mean_time += 1e-3 * (1.0 - coarse[n - 1]) * (n < 30 ? 1.0 : 0.5);  // integral of the survival S
  }
  const double analytic_mean = std::sqrt(M_PI / (2.0 * r.growth));
  std::printf(
      "%zu free points; worst |fraction - analytic| %.4f (dt) %.4f (dt/2), tolerance %.4f; mean "
      "docking time %.4f s (analytic %.4f s)\n",
      free_coarse, worst_coarse, worst_fine, tolerance, mean_time, analytic_mean);
  EXPECT_LT(worst_coarse, tolerance);
  EXPECT_LT(worst_fine, tolerance);
  EXPECT_NEAR(mean_time, analytic_mean, 0.06 * analytic_mean);  // about 4 sigma
  EXPECT_GT(coarse.back(), 0.98);                               // 1 - exp(-4.5) = 0.989
}

TEST(SphHealing, RatesDecayPerUnitTimeWhileUnoccupied) {
  // Docked at lambda_max, unoccupied for T, back with no growth: the rate is lambda_max - b T, and the
  // points dock as a Poisson process of that rate: P(docked by t) = 1 - exp(-(lambda_max - b T) t).
  ReturnScenario r;
  r.max_rate = 300.0;
  r.decay = 1.0e4;
  r.away_time = 0.02;  // lambda = 300 - 200 = 100 / s
  r.dt = 1.0e-3;
  r.evaluations = 20;
  const CoarseAndFine runs = dockedFractionAtStepAndHalfStep(r);
  const std::vector<double>&coarse = runs.coarse, &fine = runs.fine;
  const size_t free_coarse = runs.free_points;
  const double tolerance = 4.0 * 0.5 / std::sqrt(double(free_coarse));
  double worst = 0.0;
  for (int n = 1; n <= 20; ++n) {
    const double expected = -std::expm1(-100.0 * n * 1e-3);
    worst = std::max({worst, std::abs(coarse[n - 1] - expected), std::abs(fine[2 * n - 1] - expected)});
  }
  std::printf(
      "after 20 ms: docked %.3f (dt 1 ms) %.3f (dt 0.5 ms), analytic %.3f; worst deviation %.4f "
      "(tolerance %.4f)\n",
      coarse.back(), fine.back(), -std::expm1(-2.0), worst, tolerance);
  EXPECT_LT(worst, tolerance);
  // Away longer than lambda_max / b: the rate is 0 and nothing docks without growth.
  r.away_time = 0.04;
  size_t free_points = 0;
  const std::vector<double> forgotten = dockedFractionAfterReturn(r, &free_points);
  EXPECT_EQ(forgotten.back(), 0.0);
}

/// A bar 0.3 x 0.08 along x whose two left columns are anchored boundary particles of the solid, with
/// docking (fracture strain 5%).
struct AnchoredBar {
  std::shared_ptr<SphElasticSolid> solid;
  std::unique_ptr<SphFluidSolver> solver;
  std::vector<Vec3> rest;
  std::vector<uint8_t> right;  ///< the piece that is broken off (x > kSplit)
};

constexpr double kLength = 0.3, kSplit = 0.15;

SphFluidConfig barFluidConfig(const Vec3& gravity) {
  SphFluidConfig c;
  c.dimension = 2;
  c.smoothing_length = 2.0 * kSpacing;
  c.rest_density = 1.0;
  c.stiffness = 20.0;
  c.gravity = gravity;
  c.xsph = 0.1;
  c.viscosity = 0.02;
  c.fixed_dt = kDt;
  return c;
}

AnchoredBar makeAnchoredBar() {
  SphElasticConfig e;
  e.lattice_spacing = kSpacing;
  e.goal_stiffness = 2.0e6;
  e.time_step = kDt;
  e.anchor_boundary_particles = true;
  e.docking = true;
  e.fracture_strain = 0.05;
  e.docking_rate_increase = 1.0e5;  // a free point docks within about 4 ms
  e.docking_rate_decrease = 1.0e5;
  e.seed = 7;
  AnchoredBar b;
  b.rest = hexBox(Vec3(0, 0, 0), Vec3(kLength, 0.08, 0));
  const SphFluidConfig c = barFluidConfig(Vec3::Zero());
  const SphKernels kernels(2, c.smoothing_length);
  b.solid = std::make_shared<SphElasticSolid>(e, kernels, 1);
  SphParticles particles;
  b.solid->addParticles(particles, b.rest, b.solid->lattice().particleMass(kernels, c.rest_density));
  for (size_t i = 0; i < b.rest.size(); ++i) {
    if (b.rest[i].x() < 1.5 * kSpacing) particles.kinds[i] = SphParticleKind::kStaticBoundary;
    b.right.push_back(b.rest[i].x() > kSplit);
  }
  b.solver = std::make_unique<SphFluidSolver>(c, std::move(particles));
  b.solver->addForceTerm(b.solid);
  return b;
}

/// The same particles (and solid state) under other gravity.
void setGravity(AnchoredBar& b, const Vec3& gravity) {
  b.solver = std::make_unique<SphFluidSolver>(barFluidConfig(gravity), b.solver->particles());
  b.solver->addForceTerm(b.solid);
}

/// Mean x displacement of the right piece from its rest position.
double rightShift(const AnchoredBar& b) {
  double sum = 0.0;
  int n = 0;
  for (size_t i = 0; i < b.rest.size(); ++i)
    if (b.right[i]) {
      sum += b.solver->particles().positions[i].x() - b.rest[i].x();
      ++n;
    }
  return sum / n;
}

/// Brings the bar to rest without gravity (a strong drag).
void settle(AnchoredBar& b) {
  setGravity(b, Vec3::Zero());
  const double start = b.solver->time();
  while (b.solver->time() < start + 0.05) {
    b.solver->step();
    for (Vec3& v : b.solver->particles().velocities) v *= 0.95;
    b.solver->particlesChanged();
  }
}

/// Elongation of the bar under gravity g along +x (pulling it off the anchor): the right piece's mean
/// shift, averaged over the second half of `duration` (the bar oscillates about its equilibrium).
double elongationUnderLoad(AnchoredBar& b, double g, double duration) {
  setGravity(b, Vec3(g, 0, 0));
  const double start = b.solver->time();
  double sum = 0.0;
  int n = 0;
  while (b.solver->time() < start + duration) {
    b.solver->step();
    if (b.solver->time() > start + 0.5 * duration) {
      sum += rightShift(b);
      ++n;
    }
  }
  return sum / n;
}

TEST(SphHealing, BrokenBarPushedBackTogetherRegainsItsStiffness) {
  // Load: gravity g along the bar (+x), a strain of about 0.5% at the anchor (fracture strain 5%).
  const double g = 2.0, load_time = 0.5, return_speed = 0.1, hold = 0.3;
  // Unbroken reference.
  AnchoredBar whole = makeAnchoredBar();
  whole.solver->step();
  settle(whole);
  const double shift0 = rightShift(whole);
  const double elongation_whole = elongationUnderLoad(whole, g, load_time) - shift0;
  const size_t docked_whole = whole.solid->stats().docked_points;
  // Broken: the right piece (x > 0.15) is pulled off at 1 m/s.
  AnchoredBar bar = makeAnchoredBar();
  bar.solver->step();
  SphParticles& p = bar.solver->particles();
  for (size_t i = 0; i < p.size(); ++i)
    if (bar.right[i]) p.velocities[i] = Vec3(1.0, 0, 0);
  bar.solver->particlesChanged();
  while (bar.solver->time() < 0.06) bar.solver->step();
  const size_t docked_broken = bar.solid->stats().docked_points;
  const double gap = rightShift(bar);
  const uint64_t detached_broken = bar.solid->totalDetached();
  // Pushed back and held: it returns at 0.1 m/s and gravity along -x presses it against the anchored piece.
  for (size_t i = 0; i < p.size(); ++i)
    if (bar.right[i]) p.velocities[i] = Vec3(-return_speed, 0, 0);
  setGravity(bar, Vec3(-g, 0, 0));
  const double hold_start = bar.solver->time();
  while (bar.solver->time() < hold_start + hold) {
    bar.solver->step();
    if (bar.solver->time() > hold_start + 0.05) {  // held: a drag of about 40 / s after the contact
      for (Vec3& v : bar.solver->particles().velocities) v *= 0.99;
      bar.solver->particlesChanged();
    }
  }
  settle(bar);
  const size_t docked_held = bar.solid->stats().docked_points;
  const uint64_t detached_before_load = bar.solid->totalDetached();
  const double elongation_healed = elongationUnderLoad(bar, g, load_time) - shift0;
  const size_t docked_healed = bar.solid->stats().docked_points;
  std::printf(
      "broken: %llu detached, %zu docked points, right piece %.4f off; held %.2f s: %zu docked, %llu "
      "redocked\n",
      (unsigned long long)detached_broken, docked_broken, gap, hold, docked_held,
      (unsigned long long)bar.solid->totalRedocked());
  std::printf(
      "under load: elongation healed %.6g, unbroken %.6g (ratio %.4f); docked points healed %zu, "
      "unbroken %zu; detached under load %llu\n",
      elongation_healed, elongation_whole, elongation_healed / elongation_whole, docked_healed, docked_whole,
      (unsigned long long)(bar.solid->totalDetached() - detached_before_load));
  EXPECT_GT(detached_broken, 100u);   // it broke ...
  EXPECT_GT(gap, kSpacing);           // ... the right piece was pulled off by more than a spacing
  EXPECT_GT(elongation_whole, 2e-4);  // the load is measurable
  EXPECT_NEAR(elongation_healed, elongation_whole, 0.01 * elongation_whole);  // measured ratio 0.9999
  EXPECT_EQ(bar.solid->totalDetached(), detached_before_load);                // the healed bar holds the load
  // The crack's points docked again; the unbroken bar also keeps the few points at the kernel rim that were
  // docked at its first evaluation (free ones there never dock).
  EXPECT_GT(docked_held, docked_broken + 150);
  EXPECT_GE(double(docked_healed), 0.93 * double(docked_whole));
  EXPECT_LE(docked_healed, docked_whole);
}

}  // namespace
}  // namespace rc
