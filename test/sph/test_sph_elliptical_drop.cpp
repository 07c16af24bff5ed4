// Validation of the SPH fluid on a free-surface flow with an analytic solution: Monaghan's elliptical drop
// (J. J. Monaghan, "Simulating free surface flows with SPH", J. Comput. Phys. 110 (1994) 399-406, section 5).
// A disc of inviscid fluid of radius R starts with v = (-A0 x, A0 y); it stays an ellipse of semi-axes a (x)
// and b (y), a b = R^2, with da/dt = -A a, db/dt = A b, dA/dt = A^2 (a^2 - b^2) / (a^2 + b^2) (the pressure
// p_c (1 - x^2/a^2 - y^2/b^2) vanishes on the boundary). The scene uses the disc shape and the linear
// velocity field of the scene file; the semi-axes are measured from the second moments (a filled ellipse has
// <x^2> = a^2 / 4).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_setup.h"

namespace rc {
namespace {

constexpr double kA0 = 100.0;  // 1/s, Monaghan's
constexpr double kR = 1.0;

struct Ellipse {
  double a = kR, b = kR, rate = kA0;
};

/// Monaghan's ODE, RK4 with 10^4 steps per millisecond.
Ellipse analyticEllipse(double t) {
  auto derivative = [](const Ellipse& e) {
    Ellipse d;
    d.a = -e.rate * e.a;
    d.b = e.rate * e.b;
    d.rate = e.rate * e.rate * (e.a * e.a - e.b * e.b) / (e.a * e.a + e.b * e.b);
    return d;
  };
  auto add = [](const Ellipse& e, const Ellipse& d, double h) {
    return Ellipse{e.a + h * d.a, e.b + h * d.b, e.rate + h * d.rate};
  };
  Ellipse e;
  const int steps = std::max(1, int(std::ceil(t * 1e7)));
  const double h = t / steps;
  for (int s = 0; s < steps; ++s) {
    const Ellipse k1 = derivative(e), k2 = derivative(add(e, k1, h / 2)), k3 = derivative(add(e, k2, h / 2)),
                  k4 = derivative(add(e, k3, h));
    e.a += h / 6 * (k1.a + 2 * k2.a + 2 * k3.a + k4.a);
    e.b += h / 6 * (k1.b + 2 * k2.b + 2 * k3.b + k4.b);
    e.rate += h / 6 * (k1.rate + 2 * k2.rate + 2 * k3.rate + k4.rate);
  }
  return e;
}

/// Semi-axes from the second moments of the fluid particles.
std::pair<double, double> measuredAxes(const SphParticles& p) {
  double xx = 0, yy = 0, n = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.kinds[i] != SphParticleKind::kFluid) continue;
    xx += p.positions[i].x() * p.positions[i].x();
    yy += p.positions[i].y() * p.positions[i].y();
    ++n;
  }
  return {2 * std::sqrt(xx / n), 2 * std::sqrt(yy / n)};
}

std::string dropScene(double dx, const std::string& density = "summation") {
  return "dimension: 2\nspacing: " + std::to_string(dx) +
         "\nsolver: {smoothing_ratio: 3, rest_density: 1000, speed_of_sound: 1400, gamma: 7, gravity: [0, 0],"
         " viscosity: 0, density: " +
         density +
         "}\n"
         "fluid:\n  - shape: sphere\n    center: [0, 0]\n    radius: 1\n"
         "    velocity: {gradient: [[-100, 0], [0, 100]]}\n"
         "frames: {count: 8, time: 0.001}\n";
}

struct DropRun {
  size_t particles = 0;
  double worst_b_error = 0;  ///< max over the frames of |b / b_0 - b_exact / R|
  double b_end = 0, b_exact_end = 0;
  double worst_area_error = 0;     ///< max over the frames of |a b / (a_0 b_0) - 1|
  double worst_density_error = 0;  ///< max over the frames of max |rho - rho_0| / rho_0
};

DropRun runDrop(double dx, const std::string& density = "summation") {
  const SphScene scene = parseSphScene(dropScene(dx, density), "elliptical_drop.yaml");
  SphFluidSolver solver = makeSphSolver(scene);
  DropRun run;
  run.particles = scene.particles.size();
  const auto [a0, b0] = measuredAxes(solver.particles());
  for (int frame = 1; frame <= 8; ++frame) {
    const double t = 1e-3 * frame;
    while (solver.time() < t - 1e-12) solver.step();
    const auto [a, b] = measuredAxes(solver.particles());
    const Ellipse exact = analyticEllipse(solver.time());
    const double error = std::abs(b / b0 - exact.b / kR);
    run.worst_b_error = std::max(run.worst_b_error, error);
    run.b_end = b / b0, run.b_exact_end = exact.b / kR;
    run.worst_area_error = std::max(run.worst_area_error, std::abs(a * b / (a0 * b0) - 1));
    run.worst_density_error = std::max(run.worst_density_error, solver.lastStats().max_density_error);
    std::printf("%s dx %.4f t %.4f s: a %.4f (exact %.4f), b %.4f (exact %.4f), a b %.4f\n", density.c_str(),
                dx, solver.time(), a / a0, exact.a, b / b0, exact.b, a * b / (a0 * b0));
  }
  return run;
}

TEST(SphEllipticalDrop, TheSceneHoldsADiscWithTheStrainingVelocityField) {
  const SphScene scene = parseSphScene(dropScene(0.05), "elliptical_drop.yaml");
  size_t outside = 0;
  double worst = 0;
  for (size_t i = 0; i < scene.particles.size(); ++i) {
    const Vec3& x = scene.particles.positions[i];
    outside += x.norm() > kR;
    worst = std::max(worst, (scene.particles.velocities[i] - Vec3(-kA0 * x.x(), kA0 * x.y(), 0)).norm());
  }
  EXPECT_EQ(outside, 0u);
  EXPECT_EQ(worst, 0.0);
  // The lattice disc: pi R^2 / dx^2 = 1256.6 cells; the cell centres within R.
  EXPECT_NEAR(double(scene.particles.size()), M_PI / (0.05 * 0.05), 20.0);
}

TEST(SphEllipticalDrop, TheSemiAxisFollowsMonaghansSolution) {
  // The ODE itself: a b = R^2 holds.
  const Ellipse e = analyticEllipse(0.008);
  EXPECT_NEAR(e.a * e.b, kR * kR, 1e-9);
  const DropRun coarse = runDrop(0.05), fine = runDrop(0.025);
  std::printf(
      "b(8 ms) / R: exact %.4f; dx 0.05 (%zu particles) %.4f, worst error %.4f; dx 0.025 (%zu) %.4f, "
      "worst error %.4f\n",
      coarse.b_exact_end, coarse.particles, coarse.b_end, coarse.worst_b_error, fine.particles, fine.b_end,
      fine.worst_b_error);
  EXPECT_GT(coarse.b_exact_end, 1.5);  // the drop has stretched (to 2.0 R)
  // Measured: the worst |b / b_0 - b / R| over the 8 frames 0.0085 at dx = R / 20 and 0.0050 at R / 40 (h = 3
  // dx, c = 1400 m/s as Monaghan's, XSPH 0.1, poly6 gradient, summation density); a b = R^2 within 1.4 %.
  EXPECT_LT(coarse.worst_b_error, 0.012);
  EXPECT_LT(fine.worst_b_error, 0.008);
  EXPECT_LT(fine.worst_b_error, coarse.worst_b_error);  // converges
}

TEST(SphEllipticalDrop, ContinuityDensityKeepsTheRimAtRestDensity) {
  // Monaghan (1994) integrated the density by the continuity equation. Summation densities read up to 40 %
  // low on the drop's rim (its particles miss neighbours); continuity densities start at rho_0 everywhere and
  // drift where the strained lattice makes the rate's sums anisotropic (13 % at R/20, 9 % at R/40 by 8 ms),
  // which a Shepard re-initialisation every 20 steps holds to 4 % (every 5: 0.8 %). Measured (worst over 8
  // frames of |b - b_exact| / R, |a b / R^2 - 1|, |rho - rho_0| / rho_0): summation R/20 0.0085, 0.013, 0.40;
  // continuity R/20 0.0052, 0.025, 0.13, R/40 0.0050, 0.026, 0.089; re-initialised every 20 steps R/20
  // 0.0061, 0.029, 0.037, R/40 0.0053, 0.028, 0.024. The area from second moments assumes evenly spread
  // particles: summation pulls the rim in (its low densities under the clamped tension), continuity leaves
  // its spacing as the flow makes it.
  const DropRun summation = runDrop(0.05), coarse = runDrop(0.05, "continuity"),
                fine = runDrop(0.025, "continuity"),
                coarse_reinit = runDrop(0.05, "continuity, density_reinit_interval: 20"),
                fine_reinit = runDrop(0.025, "continuity, density_reinit_interval: 20");
  for (const auto& [name, run] : {std::pair<const char*, const DropRun*>{"summation R/20", &summation},
                                  {"continuity R/20", &coarse},
                                  {"continuity R/40", &fine},
                                  {"continuity, reinit 20, R/20", &coarse_reinit},
                                  {"continuity, reinit 20, R/40", &fine_reinit}}) {
    std::printf("%-28s worst b error %.4f, area error %.4f, density error %.3f\n", name, run->worst_b_error,
                run->worst_area_error, run->worst_density_error);
    EXPECT_LT(run->worst_area_error, 0.035) << name;
  }
  EXPECT_GT(summation.worst_density_error, 0.3);
  EXPECT_LT(coarse.worst_density_error, 0.5 * summation.worst_density_error);
  EXPECT_LT(fine.worst_density_error, coarse.worst_density_error);
  EXPECT_LT(coarse_reinit.worst_density_error, 0.05);
  EXPECT_LT(fine_reinit.worst_density_error, 0.05);
  EXPECT_LT(coarse.worst_b_error, summation.worst_b_error);
  EXPECT_LT(fine.worst_b_error, 0.006);
  EXPECT_LT(coarse_reinit.worst_b_error, 0.007);
  EXPECT_LT(fine_reinit.worst_b_error, 0.006);
}

}  // namespace
}  // namespace rc
