// Thin-shell materials (thesis 7.3): plastic rest state, fracture from a weak point with visibility-based
// re-neighbouring, weakening (7.25), anisotropic / inhomogeneous stiffness and balloon pressure.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>

#include "relaxed_connectivity/shell/shell_material.h"
#include "relaxed_connectivity/shell/shell_skinning.h"
#include "relaxed_connectivity/shell/shell_solver.h"
#include "shell_test_support.h"

namespace rc {
namespace {

using shell_test::bendOntoCylinder;
using shell_test::material;
using shell_test::sheetNodes;
using shell_test::sphereNodes;

// Nodes at least `margin` inside the square [-size/2, size/2]^2.
std::vector<size_t> interiorNodes(const ShellNodes& nodes, double size, double margin) {
  std::vector<size_t> out;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Vec3& p = nodes.rest_positions[i];
    if (std::abs(p.x()) < 0.5 * size - margin && std::abs(p.y()) < 0.5 * size - margin) out.push_back(i);
  }
  return out;
}

double meanOver(const std::vector<double>& v, const std::vector<size_t>& idx) {
  double s = 0.0;
  for (size_t i : idx) s += v[i];
  return s / idx.size();
}

// Holds a strip bent onto a cylinder for `hold_steps` steps of the plasticity update, releases it and lets
// it come to rest. Returns mean curvature after release / mean curvature while held.
double releasedCurvatureRatio(double bend_yield, int hold_steps, double* predicted) {
  const double size = 1.0, h = 0.1, radius = 1.0, dt = 0.01, creep = 2.0;
  ShellSolverOptions so;
  ShellSolver solver(sheetNodes(size, h), material(100.0, 1.0, 20.0), so);
  ShellMaterialOptions mo;
  mo.plasticity.bend_yield = bend_yield;
  mo.plasticity.bend_creep = creep;
  ShellMaterialModel model(solver.nodes(), solver.fibers(), mo);
  const std::vector<Vec3> bent = bendOntoCylinder(solver.nodes().rest_positions, radius);
  for (int s = 0; s < hold_steps; ++s)
    model.updatePlasticity(solver.nodes(), solver.mutableFibers(), bent, dt);
  *predicted = 1.0 - std::pow(1.0 - creep * dt, hold_steps);  // (7.23) at a fixed angle
  solver.setPositions(bent);
  const std::vector<size_t> inner = interiorNodes(solver.nodes(), size, 1.5 * h);
  const double held = meanOver(solver.energy().nodeMeanCurvature(bent), inner);
  ShellStepReport r;
  while (solver.time() < 3.0) r = solver.step();
  const double released = meanOver(solver.energy().nodeMeanCurvature(solver.positions()), inner);
  std::printf(
      "bend yield %.3f, %d hold steps: H held %.4f, released %.4f (ratio %.4f, creep law %.4f), "
      "kinetic %.2e, %zu steps\n",
      bend_yield, hold_steps, held, released, released / held, *predicted, r.kinetic, r.step);
  EXPECT_LT(r.kinetic, 1e-8);
  return released / held;
}

TEST(ShellMaterial, PlasticBendStaysBentByTheCreptAmount) {
  double predicted = 0.0;
  const double ratio = releasedCurvatureRatio(0.01, 35, &predicted);
  EXPECT_NEAR(ratio, predicted, 0.05 * predicted);
  EXPECT_GT(ratio, 0.3);
}

TEST(ShellMaterial, BendBelowYieldSpringsBackFlat) {
  double predicted = 0.0;
  const double ratio = releasedCurvatureRatio(0.5, 35, &predicted);  // angles ~0.15 rad < 0.5
  EXPECT_LT(std::abs(ratio), 0.01);
}

// Independent check of the visibility rule: does segment a-b pass through the disc?
bool segmentHitsDisc(const ShellCrack& c, const Vec3& a, const Vec3& b) {
  const double da = (a - c.center).dot(c.normal), db = (b - c.center).dot(c.normal);
  if (da * db > 0.0 || da == db) return false;
  if (da == 0.0 && db != 0.0)
    return db < 0.0 && (a - c.center).norm() <= c.radius;  // node on the plane: + side
  if (db == 0.0) return da < 0.0 && (b - c.center).norm() <= c.radius;
  const Vec3 hit = a + (b - a) * (da / (da - db));
  return (hit - c.center).norm() <= c.radius;
}

// Connected components of the fiber graph (edges centre-end1, centre-end2); sizes sorted descending.
size_t fiberGraphComponents(const ShellNodes& nodes, const ShellFibers& fibers, std::vector<size_t>* sizes) {
  std::vector<size_t> parent(nodes.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](size_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (const Fiber& f : fibers.fibers) {
    parent[find(f.end1)] = find(f.center);
    parent[find(f.end2)] = find(f.center);
  }
  std::vector<size_t> count(nodes.size(), 0);
  for (size_t i = 0; i < nodes.size(); ++i) ++count[find(i)];
  sizes->clear();
  for (size_t c : count)
    if (c > 0) sizes->push_back(c);
  std::sort(sizes->rbegin(), sizes->rend());
  return sizes->size();
}

TEST(ShellMaterial, TearStartsAtTheWeakPointAndSeparatesTheSheet) {
  // Pulled slowly (the sides part at 2 x 0.02 per second; the membrane's wave crosses the sheet in about
  // 0.03 s): at 0.05 per side, waves reflected from the grips broke fibers all over the sheet.
  const double size = 1.0, h = 0.07, pull = 0.02;
  ShellSolverOptions so;
  ShellSolver solver(sheetNodes(size, h), material(1000.0, 10.0, 5.0), so);
  const ShellFibers original = solver.fibers();
  ShellMaterialOptions mo;
  mo.fracture.stretch_threshold = 0.02;  // F.1, figure 7.8
  ShellMaterialModel model(solver.nodes(), solver.fibers(), mo);
  const Vec3 edge_middle(0.0, 0.5 * size, 0.0);
  size_t weak_node = 0;  // the node nearest the middle of the top edge
  for (size_t i = 0; i < solver.nodes().size(); ++i) {
    if ((solver.nodes().rest_positions[i] - edge_middle).norm() <
        (solver.nodes().rest_positions[weak_node] - edge_middle).norm())
      weak_node = i;
  }
  size_t weak = 0;
  for (size_t q = 0; q < solver.fibers().size(); ++q) {
    if (solver.fibers().fibers[q].center == weak_node) {
      model.states()[q].stretch_threshold = 0.005;
      ++weak;
    }
  }
  ASSERT_GT(weak, 0u);
  std::vector<int> side(solver.nodes().size(), 0);
  for (size_t i = 0; i < side.size(); ++i) {
    const double x = solver.nodes().rest_positions[i].x();
    if (std::abs(x) > 0.5 * size - 0.8 * h) side[i] = x > 0 ? 1 : -1, solver.pin(i);
  }
  // Grips reinforce the material, as the scenes do (shell_simulation): the clamp corners would otherwise
  // tear first, a singularity of the displacement boundary condition.
  for (size_t q = 0; q < solver.fibers().size(); ++q) {
    const Fiber& f = solver.fibers().fibers[q];
    if (side[f.center] != 0 || side[f.end1] != 0 || side[f.end2] != 0)
      model.states()[q].stretch_threshold = model.states()[q].bend_threshold = INFINITY;
  }
  std::vector<size_t> sizes;
  // Pieces: components of at least 3 nodes (the tear also chips off crumbs of 1-2 nodes along its path).
  auto pieces = [&] {
    fiberGraphComponents(solver.nodes(), solver.fibers(), &sizes);
    return size_t(std::count_if(sizes.begin(), sizes.end(), [](size_t c) { return c >= 3; }));
  };
  // Pulled until the two largest pieces each hold a quarter of the nodes (a chip of a few nodes along the
  // tear's path does not end it).
  const size_t n = solver.nodes().size();
  auto separated = [&] { return pieces() >= 2 && sizes[1] > n / 4; };
  size_t steps = 0;
  bool apart = false;
  double min_dt = INFINITY, first_dt = 0.0;
  while (!apart && steps < 10000) {
    const ShellStepReport r = solver.step();
    if (steps == 0) first_dt = r.dt;
    min_dt = std::min(min_dt, r.dt);
    ++steps;
    std::vector<Vec3> x = solver.positions();
    for (size_t i = 0; i < x.size(); ++i) x[i].x() += side[i] * pull * r.dt;
    solver.setPositions(x);
    if (model.update(solver, r.dt).new_cracks > 0) apart = separated();
  }
  for (int extra = 0; extra < 50; ++extra) model.update(solver, solver.step().dt);  // let it settle
  const size_t components = pieces();
  size_t chipped = 0;  // nodes outside the two largest pieces
  for (size_t c = 2; c < sizes.size(); ++c) chipped += sizes[c];
  const std::vector<ShellCrack>& cracks = model.cracks();
  ASSERT_FALSE(cracks.empty());
  ASSERT_GE(sizes.size(), 2u);
  std::printf(
      "tear: %zu weak fibers, first crack at node %u (%.3f, %.3f), %zu cracks in %zu steps, "
      "pieces of 3 or more nodes %zu (sizes %zu, %zu), %zu of %zu nodes in neither half, dt %.3e -> min "
      "%.3e\n",
      weak, cracks[0].node, cracks[0].center.x(), cracks[0].center.y(), cracks.size(), steps, components,
      sizes[0], sizes[1], chipped, n, first_dt, min_dt);
  // The tear runs across the sheet from the weak point, perpendicular to the pull.
  size_t in_band = 0;
  for (const ShellCrack& c : cracks) in_band += std::abs(c.center.x() - cracks[0].center.x()) < 0.25 * size;
  std::printf("cracks within a quarter of the width of the first: %zu of %zu\n", in_band, cracks.size());
  EXPECT_GE(in_band, cracks.size() * 9 / 10);
  EXPECT_EQ(cracks[0].node, weak_node);
  EXPECT_TRUE(cracks[0].stretch);
  EXPECT_TRUE(apart);
  EXPECT_GT(sizes[1], n / 3);  // two halves
  // Branching tears chip off a few nodes: 0-29 of 213 in variants of the model measured (bending_fit 0.02 to
  // 2); 2 with the defaults.
  EXPECT_LE(chipped, n / 7);
  const SurfelCloud discs = crackDiscontinuitySurfels(cracks);  // for the renderer (4.3)
  ASSERT_EQ(discs.size(), 2 * cracks.size());
  for (size_t c = 0; c < cracks.size(); ++c)
    EXPECT_NEAR(discs.normals[2 * c].dot(discs.normals[2 * c + 1]), -1.0, 1e-15);
  EXPECT_GT(min_dt, 0.3 * first_dt);  // re-neighbouring keeps the stable step

  // No fiber crosses a crack disc (rest configuration); some original fibers did.
  const std::vector<Vec3>& xr = solver.nodes().rest_positions;
  auto crossings = [&](const ShellFibers& fibers) {
    size_t n = 0;
    for (const Fiber& f : fibers.fibers) {
      for (const ShellCrack& c : cracks) {
        if (segmentHitsDisc(c, xr[f.center], xr[f.end1]) || segmentHitsDisc(c, xr[f.center], xr[f.end2])) {
          ++n;
          break;
        }
      }
    }
    return n;
  };
  const size_t before = crossings(original), after = crossings(solver.fibers());
  std::printf("fibers crossing a crack: %zu of %zu before, %zu of %zu after\n", before, original.size(),
              after, solver.fibers().size());
  EXPECT_GT(before, 10u);
  EXPECT_EQ(after, 0u);
}

TEST(ShellMaterial, RepeatedPlasticBendingWeakensByTheLaw) {
  const double h = 0.1, chi = 3.0, dt = 0.01, gamma_b = 0.2;
  const ShellNodes nodes = sheetNodes(1.0, h);
  ShellFibers fibers = buildShellFibers(nodes);
  ShellMaterialOptions mo;
  mo.plasticity.bend_yield = 0.01;
  mo.plasticity.bend_creep = 2.0;
  mo.plasticity.weakening = chi;
  mo.fracture.bend_threshold = gamma_b;
  ShellMaterialModel model(nodes, fibers, mo);
  const std::vector<Vec3> flat = nodes.rest_positions, bent = bendOntoCylinder(flat, 1.6);
  auto cracksAt = [&](const std::vector<Vec3>& x) {  // fracture test on copies
    ShellMaterialModel probe = model;
    ShellNodes n = nodes;
    ShellFibers f = fibers;
    return probe.updateFracture(n, f, x).new_cracks;
  };
  std::vector<double> lengths, angles;
  measureFibers(nodes, fibers, bent, &lengths, &angles);
  double peak = 0.0;
  for (size_t q = 0; q < fibers.size(); ++q)
    peak = std::max(peak, std::abs(angles[q] - fibers.fibers[q].rest_angle));
  ASSERT_LT(peak, gamma_b);
  EXPECT_EQ(cracksAt(bent), 0u);  // the fresh material survives the bend
  const int cycles = 6;
  std::vector<double> weakest(cycles + 1, gamma_b);
  for (int c = 0; c < cycles; ++c) {
    for (int s = 0; s < 25; ++s) model.updatePlasticity(nodes, fibers, bent, dt);
    for (int s = 0; s < 25; ++s) model.updatePlasticity(nodes, fibers, flat, dt);
    for (const FiberMaterialState& st : model.states())
      weakest[c + 1] = std::min(weakest[c + 1], st.bend_threshold);
  }
  // (7.25) integrates to gamma_b = gamma_b0 prod (1 - chi |d theta_p|) ~ gamma_b0 exp(-chi sum |d theta_p|).
  double worst = 0.0;
  size_t untouched = 0, yielded = 0;
  for (const FiberMaterialState& st : model.states()) {
    const double law = gamma_b * std::exp(-chi * st.plastic_bend_total);
    worst = std::max(worst, std::abs(st.bend_threshold - law) / law);
    if (st.plastic_bend_total == 0.0) {
      ++untouched;
      EXPECT_EQ(st.bend_threshold, gamma_b);
    } else {
      ++yielded;
    }
  }
  std::printf("weakening chi %.1f: weakest gamma_b per cycle:", chi);
  for (double w : weakest) std::printf(" %.4f", w);
  std::printf("; peak bend %.4f; %zu fibers yielded, %zu never; max deviation from exp law %.2e\n", peak,
              yielded, untouched, worst);
  for (int c = 0; c < cycles; ++c) EXPECT_LT(weakest[c + 1], weakest[c]);
  EXPECT_LT(worst, 0.01);
  EXPECT_GT(yielded, 0u);
  EXPECT_LT(weakest[cycles], peak);  // weakened below the bend it survived
  // The flat hold left little plastic angle, so the same bend now exceeds the weakened threshold.
  EXPECT_GT(cracksAt(bent), 0u);
}

// Energy per rest area of interior nodes under a uniaxial stretch by s along `dir`.
double interiorStretchDensity(const ShellNodes& nodes, const ShellFibers& fibers, const Vec3& dir, double s,
                              const std::vector<size_t>& inner) {
  ShellEnergy energy(nodes, fibers, material(1.0, 0.0, 0.0));
  std::vector<Vec3> x = nodes.rest_positions;
  for (Vec3& p : x) p += (s - 1.0) * dir * p.dot(dir);
  std::vector<double> mem;
  energy.nodeEnergies(x, &mem, nullptr);
  double e = 0.0, a = 0.0;
  for (size_t i : inner) e += mem[i], a += nodes.rest_areas[i];
  return e / a;
}

TEST(ShellMaterial, AnisotropicStiffnessGivesDirectionDependentStretchEnergy) {
  const double size = 1.0, h = 0.05, s = 1.001, a = 0.5;
  const ShellNodes nodes = sheetNodes(size, h, 200);
  ShellFibers fibers = buildShellFibers(nodes);
  const std::vector<size_t> inner = interiorNodes(nodes, size, 2.5 * h);
  const double iso_x = interiorStretchDensity(nodes, fibers, Vec3::UnitX(), s, inner);
  setFiberStiffness(nodes, fibers, [a](const Vec3&, const Vec3& d) {
    const double c = d.x() * d.x() - d.y() * d.y();  // cos(2 phi)
    return std::make_pair(1.0 + a * c, 1.0);
  });
  const double ex = interiorStretchDensity(nodes, fibers, Vec3::UnitX(), s, inner);
  const double ey = interiorStretchDensity(nodes, fibers, Vec3::UnitY(), s, inner);
  // Isotropic weights: area term (s^2 - 1)^2 / 4, fiber term (s^2 - 1)^2 (3/8 +- a/4) (moments of cos^4).
  const double e2 = (s * s - 1.0) * (s * s - 1.0);
  const double px = 0.5 * e2 * (0.25 + 0.375 + 0.25 * a), py = 0.5 * e2 * (0.25 + 0.375 - 0.25 * a);
  const double piso = 0.5 * e2 * 0.625;
  std::printf(
      "anisotropic a=%.1f: density x %.4e (pred %.4e), y %.4e (pred %.4e), ratio %.4f (pred %.4f); "
      "isotropic %.4e (pred %.4e)\n",
      a, ex, px, ey, py, ex / ey, px / py, iso_x, piso);
  EXPECT_NEAR(iso_x, piso, 0.05 * piso);
  EXPECT_NEAR(ex, px, 0.05 * px);
  EXPECT_NEAR(ey, py, 0.05 * py);
  EXPECT_NEAR(ex / ey, px / py, 0.05 * px / py);

  // Inhomogeneous: twice as stiff for x > 0.
  setFiberStiffness(nodes, fibers,
                    [](const Vec3& c, const Vec3&) { return std::make_pair(c.x() > 0 ? 2.0 : 1.0, 1.0); });
  std::vector<size_t> left, right;
  for (size_t i : inner) {
    const double x = nodes.rest_positions[i].x();
    if (x < -2.0 * h) left.push_back(i);
    if (x > 2.0 * h) right.push_back(i);
  }
  const double el = interiorStretchDensity(nodes, fibers, Vec3::UnitY(), s, left);
  const double er = interiorStretchDensity(nodes, fibers, Vec3::UnitY(), s, right);
  std::printf("inhomogeneous: right / left energy density %.4f (pred 2)\n", er / el);
  EXPECT_NEAR(er / el, 2.0, 0.04);  // sampling differences of the halves: 1.7 %
}

// Pressure p on a sphere of rest radius 1 stretched to radius s: dPi/ds = 0 with the energy per rest area
// K_s (s^2 - 1)^2 + K_b (1/s - 1)^2 gives p = 4 K_s (s^2 - 1) / s - 2 K_b (1/s - 1) / s^4.
double pressureForRadius(double ks, double kb, double s) {
  return 4.0 * ks * (s * s - 1.0) / s - 2.0 * kb * (1.0 / s - 1.0) / std::pow(s, 4);
}

TEST(ShellMaterial, BalloonPressureInflatesToTheAnalyticRadius) {
  const double ks = 100.0, kb = 100.0, pressure = 120.0;  // F.1, figure 7.10 stiffnesses
  double lo = 1.0, hi = 2.0;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (pressureForRadius(ks, kb, mid) < pressure ? lo : hi) = mid;
  }
  const double expected = 0.5 * (lo + hi);
  ShellSolver solver(sphereNodes(0.2, 8000), material(ks, kb, 15.0), ShellSolverOptions());
  solver.setExternalForce(balloonPressure(solver.nodes(), solver.fibers(), pressure));
  ShellStepReport r;
  while (solver.time() < 2.5) r = solver.step();
  double mean = 0.0, spread = 0.0;
  for (const Vec3& p : solver.positions()) mean += p.norm() / solver.positions().size();
  double rms = 0.0;
  for (const Vec3& p : solver.positions()) {
    spread = std::max(spread, std::abs(p.norm() - mean));
    rms += std::pow(p.norm() - mean, 2) / solver.positions().size();
  }
  rms = std::sqrt(rms);
  const double volume = balloonVolume(solver.nodes(), solver.fibers(), solver.positions());
  std::printf(
      "balloon p=%.1f K_s=%.0f K_b=%.0f, %zu nodes: radius %.5f (analytic %.5f, error %.3f %%), "
      "spread max %.2e rms %.2e, volume %.4f (4/3 pi r^3 = %.4f), kinetic %.2e, %zu steps\n",
      pressure, ks, kb, solver.nodes().size(), mean, expected, 100.0 * (mean / expected - 1.0), spread, rms,
      volume, 4.0 / 3.0 * M_PI * std::pow(mean, 3), r.kinetic, r.step);
  EXPECT_NEAR(mean, expected, 0.01 * expected);
  EXPECT_LT(rms, 0.025 * mean);
  EXPECT_LT(spread, 0.05 * mean);
  EXPECT_LT(r.kinetic, 1e-4 * r.elastic.total());
  EXPECT_GT(expected, 1.1);  // a real inflation
}

// The clamp against short fibers (re-neighbouring uses buildNodeFibers with min_fiber_length * spacing):
// Poisson-disc nodes keep fibers >= 2 spacings long, so the case needs hand-placed nodes.
TEST(ShellMaterial, ShortFibersAreDroppedWhenFibersAreRebuilt) {
  std::vector<Vec3> points, normals;
  const double h = 0.1;
  for (int a = -4; a <= 4; ++a) {
    for (int b = -4; b <= 4; ++b) {
      Vec3 p(a * h, b * h, 0.0);
      if (b == 0 && std::abs(a) == 1) p.x() = 0.15 * h * a;  // squeeze the centre's x-neighbours
      points.push_back(p);
      normals.push_back(Vec3::UnitZ());
    }
  }
  const ShellNodes nodes = shellNodesFromPoints(points, normals);
  const size_t centre = 40;  // (0, 0)
  ASSERT_LT(nodes.rest_positions[centre].norm(), 1e-15);
  const std::vector<Fiber> all = buildNodeFibers(nodes, centre, 0.0);
  const std::vector<Fiber> kept = buildNodeFibers(nodes, centre, 0.5 * nodes.spacing);
  double shortest_all = INFINITY, shortest_kept = INFINITY, weights = 0.0;
  for (const Fiber& f : all) shortest_all = std::min(shortest_all, f.rest_length);
  for (const Fiber& f : kept) shortest_kept = std::min(shortest_kept, f.rest_length), weights += f.weight;
  std::printf("short fibers: spacing %.3f, shortest fiber %.3f of %zu -> %.3f of %zu after the clamp\n",
              nodes.spacing, shortest_all, all.size(), shortest_kept, kept.size());
  EXPECT_LT(shortest_all, 0.5 * nodes.spacing);
  EXPECT_GE(shortest_kept, 0.5 * nodes.spacing);
  EXPECT_LT(kept.size(), all.size());
  EXPECT_GE(kept.size(), 3u);
  EXPECT_NEAR(weights, 1.0, 1e-12);
}

// A step in y across the line y = 0 overloads the fibers crossing it everywhere along the line at once. With
// max_crack_speed v no crack is placed within two crack radii of one made less than distance / v earlier;
// the line still ends up cut. Without the limit the cracks along the line come in far fewer calls.
TEST(ShellMaterial, CrackSpeedLimitSpacesNeighbouringCracksInTime) {
  const ShellNodes rest_nodes = sheetNodes(1.0, 0.07);
  std::vector<Vec3> x = rest_nodes.rest_positions;
  for (Vec3& p : x) p.y() += p.y() > 0.0 ? 0.01 : 0.0;
  struct Run {
    std::vector<ShellCrack> cracks;
    int calls_until_done = 0;
  };
  const double dt = 0.005;
  auto run = [&](double speed) {
    ShellNodes nodes = rest_nodes;
    ShellFibers fibers = buildShellFibers(nodes);
    ShellMaterialOptions mo;
    mo.fracture.stretch_threshold = 0.02;
    mo.fracture.max_cracks_per_step = 1000;
    mo.fracture.max_crack_speed = speed;
    ShellMaterialModel model(nodes, fibers, mo);
    Run out;
    int idle = 0;
    for (int call = 0; call < 2000 && idle < 100; ++call) {
      const size_t made = model.updateFracture(nodes, fibers, x, call * dt).new_cracks;
      idle = made > 0 ? 0 : idle + 1;
      if (made > 0) out.calls_until_done = call + 1;
    }
    out.cracks = model.cracks();
    return out;
  };
  const double speed = 0.5;
  const Run limited = run(speed), free = run(std::numeric_limits<double>::infinity());
  auto violations = [speed](const std::vector<ShellCrack>& cracks) {
    size_t n = 0;
    for (size_t b = 0; b < cracks.size(); ++b) {
      for (size_t a = 0; a < b; ++a) {
        const double d = (cracks[a].center - cracks[b].center).norm();
        if (d < 2.0 * std::max(cracks[a].radius, cracks[b].radius) &&
            cracks[b].time - cracks[a].time < d / speed - 1e-12)
          ++n;
      }
    }
    return n;
  };
  std::printf(
      "crack speed %.2f: %zu cracks over %d calls (%zu too close in time); unlimited: %zu cracks in %d "
      "calls (%zu would be too close)\n",
      speed, limited.cracks.size(), limited.calls_until_done, violations(limited.cracks), free.cracks.size(),
      free.calls_until_done, violations(free.cracks));
  EXPECT_EQ(violations(limited.cracks), 0u);
  EXPECT_GT(violations(free.cracks), 0u);
  EXPECT_GT(limited.calls_until_done, 4 * free.calls_until_done);
  // Both cut the whole line: the cracks span it.
  for (const Run* r : {&limited, &free}) {
    double lo = INFINITY, hi = -INFINITY;
    for (const ShellCrack& c : r->cracks) lo = std::min(lo, c.center.x()), hi = std::max(hi, c.center.x());
    EXPECT_GT(hi - lo, 0.8);
  }
  for (size_t c = 1; c < limited.cracks.size(); ++c)
    EXPECT_GE(limited.cracks[c].time, limited.cracks[c - 1].time);  // made in time order
}

TEST(ShellMaterial, RejectsBadOptions) {
  const ShellNodes nodes = sheetNodes(1.0, 0.2);
  ShellFibers fibers = buildShellFibers(nodes);
  ShellMaterialOptions mo;
  mo.plasticity.bend_creep = -1.0;
  EXPECT_THROW(ShellMaterialModel(nodes, fibers, mo), std::invalid_argument);
  mo = ShellMaterialOptions();
  mo.fracture.max_crack_speed = 0.0;
  EXPECT_THROW(ShellMaterialModel(nodes, fibers, mo), std::invalid_argument);
  mo = ShellMaterialOptions();
  mo.plasticity.bend_yield = 0.0;
  mo.plasticity.bend_creep = 10.0;
  ShellMaterialModel model(nodes, fibers, mo);
  EXPECT_THROW(model.updatePlasticity(nodes, fibers, nodes.rest_positions, 0.5), std::invalid_argument);
  EXPECT_THROW(
      setFiberStiffness(nodes, fibers, [](const Vec3&, const Vec3&) { return std::make_pair(-1.0, 1.0); }),
      std::invalid_argument);
}

}  // namespace
}  // namespace rc
