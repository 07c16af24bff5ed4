// Fracture and healing through per-lattice-point docking (thesis 8.2.5), plastic flow of the rest lattice,
// and anchoring to boundary particles, on 2D hexagonal-lattice bodies.
#include "relaxed_connectivity/sph/sph_elastic_solid.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_lattice.h"

namespace rc {
namespace {

constexpr double kSpacing = 0.02;  // d; h = 2 d as in the Fig. 8.7 scenes
constexpr double kDt = 2.5e-4;

struct Body {
  std::shared_ptr<SphElasticSolid> solid;
  std::unique_ptr<SphFluidSolver> solver;
};

SphElasticConfig baseConfig() {
  SphElasticConfig e;
  e.lattice_spacing = kSpacing;
  e.goal_stiffness = 2.0e5;
  e.time_step = kDt;
  return e;
}

/// A solid of the points with the given velocities, no gravity, fixed step kDt.
Body makeBody(const SphElasticConfig& e, const std::vector<Vec3>& points, const std::vector<Vec3>& velocities,
              int threads = 0, double viscosity = 0.0) {
  SphFluidConfig c;
  c.dimension = 2;
  c.smoothing_length = 2.0 * kSpacing;
  c.rest_density = 1.0;
  c.stiffness = 20.0;
  c.gravity = Vec3::Zero();
  c.xsph = 0.1;
  c.viscosity = viscosity;
  c.fixed_dt = kDt;
  c.num_threads = threads;
  const SphKernels kernels(2, c.smoothing_length);
  Body b;
  b.solid = std::make_shared<SphElasticSolid>(e, kernels, 1);
  SphParticles particles;
  b.solid->addParticles(particles, points, b.solid->lattice().particleMass(kernels, c.rest_density));
  for (size_t i = 0; i < velocities.size(); ++i) particles.velocities[i] = velocities[i];
  b.solver = std::make_unique<SphFluidSolver>(c, std::move(particles));
  b.solver->addForceTerm(b.solid);
  return b;
}

/// Hexagonal lattice points of the box [lo, hi].
std::vector<Vec3> hexBox(const Vec3& lo, const Vec3& hi) {
  return sampleLatticeBox(SphLattice(2, kSpacing), lo, hi);
}

/// Mean x of the particles whose start point lies left (or right) of `split`.
double meanX(const SphParticles& p, const std::vector<Vec3>& start, bool left, double split) {
  double sum = 0.0;
  int n = 0;
  for (size_t i = 0; i < p.size(); ++i)
    if ((start[i].x() < split) == left) {
      sum += p.positions[i].x();
      ++n;
    }
  return sum / n;
}

/// A bar 0.4 x 0.1 whose halves start with velocities -/+ v along x (pulled apart).
struct PullResult {
  uint64_t detached = 0;
  double gap = 0.0;  ///< smallest distance between a left-half and a right-half particle at the end
  double separation_change = 0.0;
  size_t particles = 0;
  double mass_change = 0.0;
  std::vector<Vec3> positions;
};

PullResult pullBar(double speed, int threads, double duration = 0.08) {
  SphElasticConfig e = baseConfig();
  e.docking = true;
  e.fracture_strain = 0.08;
  e.fracture_rate = 5000.0;
  e.docking_rate_increase = 5.0 / kDt;    // 1/s^2: slow healing, a crack that opens stays open
  e.docking_rate_decrease = 100.0 / kDt;  // forgets a point in 10 steps
  e.seed = 11;
  const std::vector<Vec3> points = hexBox(Vec3(0, 0, 0), Vec3(0.4, 0.1, 0));
  std::vector<Vec3> velocities;
  for (const Vec3& p : points) velocities.push_back(Vec3(p.x() < 0.2 ? -speed : speed, 0, 0));
  Body b = makeBody(e, points, velocities, threads);
  const SphParticles& p = b.solver->particles();
  double mass0 = 0.0;
  for (double m : p.masses) mass0 += m;
  const double sep0 = meanX(p, points, false, 0.2) - meanX(p, points, true, 0.2);
  while (b.solver->time() < duration) b.solver->step();
  PullResult r;
  r.detached = b.solid->totalDetached();
  r.separation_change = meanX(p, points, false, 0.2) - meanX(p, points, true, 0.2) - sep0;
  r.gap = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = 0; j < p.size(); ++j)
      if (points[i].x() < 0.2 && points[j].x() >= 0.2)
        r.gap = std::min(r.gap, (p.positions[i] - p.positions[j]).norm());
  r.particles = p.size();
  double mass = 0.0;
  for (double m : p.masses) mass += m;
  r.mass_change = mass - mass0;
  r.positions = p.positions;
  return r;
}

TEST(SphFracture, ConfigRejectsBadDockingAndPlasticityValues) {
  SphElasticConfig e = baseConfig();
  e.docking = true;
  e.time_step = 0.0;
  EXPECT_THROW(e.validate(), std::invalid_argument);  // docking needs the step
  e = baseConfig();
  e.yield_strain = 0.1;
  e.time_step = 0.0;
  EXPECT_THROW(e.validate(), std::invalid_argument);  // plasticity needs the step
  e = baseConfig();
  e.docking_distance = 1.5;
  EXPECT_THROW(e.validate(), std::invalid_argument);
  e = baseConfig();
  e.fracture_strain = -0.1;
  EXPECT_THROW(e.validate(), std::invalid_argument);
  e = baseConfig();
  e.max_plastic_strain = 0.0;
  EXPECT_THROW(e.validate(), std::invalid_argument);
  e = baseConfig();
  e.time_step = 0.0;  // both off: no step needed
  EXPECT_NO_THROW(e.validate());
}

TEST(SphFracture, BarPulledApartFracturesButNotBelowTheThreshold) {
  const PullResult fast = pullBar(1.0, 0);
  const PullResult slow = pullBar(0.05, 0);
  std::printf("fast pull: %llu detached, gap %.4f, separation change %.4f\n",
              (unsigned long long)fast.detached, fast.gap, fast.separation_change);
  std::printf("slow pull: %llu detached, gap %.4f, separation change %.4f\n",
              (unsigned long long)slow.detached, slow.gap, slow.separation_change);
  EXPECT_GT(fast.detached, 10u);
  EXPECT_GT(fast.gap, 2.0 * kSpacing);                // the pieces are apart (beyond the kernel support)
  EXPECT_GT(fast.separation_change, 0.05);            // and moving away from each other
  EXPECT_EQ(slow.detached, 0u);                       // below the threshold nothing detaches
  EXPECT_LT(slow.gap, 1.2 * kSpacing);                // the bar stays whole
  EXPECT_LT(std::abs(slow.separation_change), 0.01);  // and springs back
  EXPECT_EQ(fast.particles, slow.particles);          // nothing is created or removed
  EXPECT_EQ(fast.mass_change, 0.0);
}

TEST(SphFracture, FractureIsIdenticalForOneAndTwoThreads) {
  const PullResult one = pullBar(1.0, 1, 0.03);
  const PullResult two = pullBar(1.0, 2, 0.03);
  EXPECT_GT(one.detached, 0u);
  EXPECT_EQ(one.detached, two.detached);
  ASSERT_EQ(one.positions.size(), two.positions.size());
  EXPECT_EQ(std::memcmp(one.positions.data(), two.positions.data(), one.positions.size() * sizeof(Vec3)), 0);
}

/// Two blocks of one lattice with a gap of `gap` between them approach each other, then are pulled apart
/// gently. Returns the change of their separation in the second phase; *redocked the healed points.
double approachThenPull(double docking_rate_increase, uint64_t* redocked, size_t* docked_before,
                        size_t* docked_after) {
  SphElasticConfig e = baseConfig();
  e.docking = true;
  e.fracture_strain = 0.3;
  e.docking_rate_increase = docking_rate_increase;
  e.docking_rate_decrease = 100.0 / kDt;
  e.max_docking_rate = 2000.0;
  const double gap = 2.0 * kSpacing, speed = 0.1;  // no neighbours across the gap at the start
  std::vector<Vec3> points;
  for (const Vec3& p : hexBox(Vec3(0, 0, 0), Vec3(0.2, 0.1, 0)))
    points.push_back(p.x() < 0.1 - 1e-9 ? p : p + Vec3(gap, 0, 0));
  std::vector<Vec3> velocities;
  for (const Vec3& p : points) velocities.push_back(Vec3(p.x() < 0.1 ? speed : -speed, 0, 0));
  Body b = makeBody(e, points, velocities, 0, 0.002);
  SphParticles& p = b.solver->particles();
  b.solver->step();
  *docked_before = b.solid->stats().docked_points;
  // Approach: the gap closes after gap / (2 speed) = 0.2 s; then the pieces rest against each other.
  while (b.solver->time() < 0.25) {
    b.solver->step();
  }
  *redocked = b.solid->totalRedocked();
  *docked_after = b.solid->stats().docked_points;
  // Pull apart gently (slower than the elastic waves, far below the fracture strain of a healed bond).
  for (size_t i = 0; i < p.size(); ++i) p.velocities[i] = Vec3(points[i].x() < 0.1 ? -0.1 : 0.1, 0, 0);
  b.solver->particlesChanged();
  const double sep0 = meanX(p, points, false, 0.1) - meanX(p, points, true, 0.1);
  double widest = 0.0;
  while (b.solver->time() < 0.33) {
    b.solver->step();
    widest = std::max(widest, meanX(p, points, false, 0.1) - meanX(p, points, true, 0.1) - sep0);
  }
  return widest;
}

TEST(SphFracture, PiecesPushedTogetherHealAndHoldTogether) {
  uint64_t healed = 0, never = 0;
  size_t before = 0, after = 0, before0 = 0, after0 = 0;
  const double healed_change = approachThenPull(200.0 / kDt, &healed, &before, &after);
  const double apart_change = approachThenPull(0.0, &never, &before0, &after0);
  std::printf("healing: %llu redocked, docked points %zu -> %zu, separation change on pulling %.4f\n",
              (unsigned long long)healed, before, after, healed_change);
  std::printf("no healing: %llu redocked, docked points %zu -> %zu, separation change %.4f\n",
              (unsigned long long)never, before0, after0, apart_change);
  // Lattice points across the contact docked (free points at the kernel rim, 2 d, never dock: they carry no
  // force at rest), and the count is back at that of the start.
  EXPECT_GT(healed, 40u);
  EXPECT_GE(after, before);
  // Delta lambda^+ = 0: only points that lost their particle a moment ago (rate not yet decayed) re-dock.
  EXPECT_LT(20 * never, healed);
  EXPECT_LE(after0, before0);
  EXPECT_GT(apart_change, 0.01);                 // the unhealed pieces drift apart when pulled
  EXPECT_LT(healed_change, 0.3 * apart_change);  // the healed ones hold together
}

double extentX(const std::vector<Vec3>& x) {
  double lo = 1e300, hi = -1e300;
  for (const Vec3& p : x) {
    lo = std::min(lo, p.x());
    hi = std::max(hi, p.x());
  }
  return hi - lo;
}

/// A block held stretched by 25% in x for `hold` evaluations (the load), then released and left to
/// settle. Returns the residual strain extent / rest extent - 1.
double residualStretch(const SphElasticConfig& e, int hold, double* max_plastic_strain) {
  const std::vector<Vec3> rest = hexBox(Vec3(0, 0, 0), Vec3(0.16, 0.16, 0));
  std::vector<Vec3> stretched;
  for (const Vec3& p : rest) stretched.push_back(Vec3(1.25 * p.x(), p.y(), 0));
  Body b = makeBody(e, stretched, {}, 0, 0.01);
  std::vector<Vec3> forces;
  for (int k = 0; k < hold; ++k) b.solid->computeForces(b.solver->particles(), forces);
  b.solver->particlesChanged();
  while (b.solver->time() < 0.3) b.solver->step();
  *max_plastic_strain = b.solid->stats().max_plastic_strain;
  return extentX(b.solver->particles().positions) / extentX(rest) - 1.0;
}

TEST(SphPlasticity, PlasticBlockKeepsItsDeformationTheElasticOneReturns) {
  double elastic_plastic_strain = 0.0, plastic_strain = 0.0;
  const double elastic = residualStretch(baseConfig(), 400, &elastic_plastic_strain);
  SphElasticConfig e = baseConfig();
  e.yield_strain = 0.02;
  e.plastic_flow_rate = 100.0;
  const double plastic = residualStretch(e, 400, &plastic_strain);
  std::printf("residual stretch: elastic %.4f, plastic %.4f (max plastic log-stretch %.3f)\n", elastic,
              plastic, plastic_strain);
  EXPECT_LT(std::abs(elastic), 0.03);  // returns to its rest shape
  EXPECT_GT(plastic, 0.07);            // keeps a good part of the 25% stretch
  EXPECT_LT(plastic, 0.3);
  EXPECT_GT(plastic_strain, 0.07);
  EXPECT_EQ(elastic_plastic_strain, 0.0);  // plasticity off: nothing is stored
}

TEST(SphPlasticity, OffCostsNothingAndChangesNothing) {
  // Docking and plasticity switched on but never triggered give the same forces as the plain solid.
  const std::vector<Vec3> rest = hexBox(Vec3(0, 0, 0), Vec3(0.16, 0.16, 0));
  std::vector<Vec3> x;
  for (const Vec3& p : rest) x.push_back(Vec3(1.03 * p.x(), 0.98 * p.y(), 0));
  SphElasticConfig on = baseConfig();
  on.docking = true;
  on.yield_strain = 1.0;
  Body plain = makeBody(baseConfig(), x, {}), full = makeBody(on, x, {});
  std::vector<Vec3> f_plain, f_full;
  plain.solid->computeForces(plain.solver->particles(), f_plain);
  full.solid->computeForces(full.solver->particles(), f_full);
  ASSERT_EQ(f_plain.size(), f_full.size());
  double worst = 0.0;
  for (size_t i = 0; i < f_plain.size(); ++i) worst = std::max(worst, (f_plain[i] - f_full[i]).norm());
  EXPECT_LT(worst, 1e-12);
  EXPECT_TRUE(plain.solid->dockedCounts().empty());
  EXPECT_TRUE(plain.solid->plasticTransforms().empty());
  EXPECT_EQ(full.solid->stats().docked_points, full.solid->stats().assigned_pairs);
}

TEST(SphAnchor, BoundaryParticlesOfThePhaseHoldTheSolid) {
  // A bar under gravity whose left end is boundary particles of its phase: anchored it hangs on, without
  // anchoring it falls.
  const std::vector<Vec3> points = hexBox(Vec3(0, 0, 0), Vec3(0.2, 0.06, 0));
  double drop[2];
  for (int anchored = 0; anchored < 2; ++anchored) {
    SphElasticConfig e = baseConfig();
    e.anchor_boundary_particles = anchored == 1;
    Body b = makeBody(e, points, {});
    SphParticles& p = b.solver->particles();
    for (size_t i = 0; i < p.size(); ++i)
      if (p.positions[i].x() < 0.03) p.kinds[i] = SphParticleKind::kStaticBoundary;
    b.solver = std::make_unique<SphFluidSolver>(
        [&] {
          SphFluidConfig c = b.solver->config();
          c.gravity = Vec3(0, -9.81, 0);
          return c;
        }(),
        p);
    b.solver->addForceTerm(b.solid);
    while (b.solver->time() < 0.1) b.solver->step();
    // Mean drop of the free particles next to the anchor.
    double sum = 0.0;
    int n = 0;
    for (size_t i = 0; i < points.size(); ++i)
      if (points[i].x() >= 0.03 && points[i].x() < 0.07) {
        sum += points[i].y() - b.solver->particles().positions[i].y();
        ++n;
      }
    drop[anchored] = sum / n;
  }
  std::printf("drop next to the anchor after 0.1 s: free %.4f, anchored %.4f\n", drop[0], drop[1]);
  EXPECT_GT(drop[0], 0.04);  // free fall: g t^2 / 2 = 0.049
  EXPECT_LT(drop[1], 0.02);  // held by the anchor (the soft bar sags a little)
}

}  // namespace
}  // namespace rc
