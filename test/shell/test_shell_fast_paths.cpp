// Fast paths of the thin-shell simulation (thesis 7.2-7.3) against straightforward references: the fused
// per-fiber measure and the force pass against fiberArcLength / fiberNormalAngle evaluated term by term,
// the fiber measures the solver keeps against measureFibers, incremental re-neighbouring after cracks
// against a full recomputation, and pinned nodes pulled inside the solver's drift.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>

#include "relaxed_connectivity/shell/shell_crack.h"
#include "relaxed_connectivity/shell/shell_energy.h"
#include "relaxed_connectivity/shell/shell_material.h"
#include "relaxed_connectivity/shell/shell_solver.h"
#include "shell_test_support.h"

namespace rc {
namespace {

using shell_test::sheetNodes;
using shell_test::sphereNodes;
using shell_test::wobble;

// Straightforward evaluation of the energy and its gradient (7.7, 7.3 with 7.9-7.11; 7.14-7.17): every
// fiber through fiberArcLength and fiberNormalAngle, the normal through fanNormal, the bending form of each
// node (shell_bending_form.h, tested in test_shell_energy) applied as a dense matrix, gradients added
// directly into the node array in serial order.
ShellEnergyValue referenceEnergy(const ShellNodes& nodes, const ShellFibers& fibers, const ShellMaterial& mat,
                                 const ShellBendingForms& forms, const std::vector<Vec3>& x,
                                 std::vector<Vec3>* grad) {
  constexpr double beta = ShellEnergy::kSplineAngleScale;
  ShellEnergyValue value;
  grad->assign(x.size(), Vec3::Zero());
  for (size_t i = 0; i < nodes.size(); ++i) {
    const size_t f0 = fibers.node_offsets[i], f1 = fibers.node_offsets[i + 1];
    if (f0 == f1) continue;
    const double area = nodes.rest_areas[i], ks = mat.stretch_stiffness, kb = mat.bending_stiffness;
    double normal_length = 0.0;
    const Vec3 normal = fanNormal(nodes, i, x, &normal_length);
    std::vector<double> len, ang, dk;
    std::vector<std::array<Vec3, 3>> gl(f1 - f0), ga(f1 - f0);
    std::vector<Vec3> gn(f1 - f0);
    double s = 0, s0 = 0, fiber_stretch = 0, mean_scale = 0;
    for (size_t q = f0; q < f1; ++q) {
      const Fiber& f = fibers.fibers[q];
      len.push_back(fiberArcLength(x[f.end1], x[i], x[f.end2], &gl[q - f0]));
      ang.push_back(fiberNormalAngle(x[f.end1], x[i], x[f.end2], normal, &ga[q - f0], &gn[q - f0]));
      dk.push_back(std::sqrt(f.bend_scale) *
                   (ang.back() / (beta * len.back()) - f.rest_angle / (beta * f.rest_length)));
      const double l0sq = f.rest_length * f.rest_length, e = len.back() * len.back() / l0sq - 1.0;
      s += f.weight * len.back() * len.back();
      s0 += f.weight * l0sq;
      fiber_stretch += f.weight * f.stretch_scale * e * e;
      mean_scale += f.weight * f.stretch_scale;
    }
    const int m = int(f1 - f0);
    const Eigen::Map<const Eigen::MatrixXd> form(forms.values.data() + forms.offsets[i], m, m);
    const Eigen::VectorXd d = Eigen::Map<const Eigen::VectorXd>(dk.data(), m), form_d = form * d;
    const double r = s / s0 - 1.0;
    value.membrane += 0.5 * area * ks * (mean_scale * r * r + fiber_stretch);
    value.bending += 0.5 * area * kb * d.dot(form_d);
    Vec3 dn = Vec3::Zero();
    for (size_t q = f0; q < f1; ++q) {
      const Fiber& f = fibers.fibers[q];
      const size_t a = q - f0;
      const double l0sq = f.rest_length * f.rest_length;
      const double de_dtheta = area * kb * form_d(int(a)) * std::sqrt(f.bend_scale) / (beta * len[a]);
      const double de_dl =
          area * ks * f.weight * len[a] * 2.0 *
              (mean_scale * r / s0 + f.stretch_scale * (len[a] * len[a] / l0sq - 1.0) / l0sq) -
          de_dtheta * ang[a] / len[a];
      const uint32_t ends[3] = {f.end1, static_cast<uint32_t>(i), f.end2};
      for (int p = 0; p < 3; ++p) (*grad)[ends[p]] += de_dl * gl[a][p] + de_dtheta * ga[a][p];
      dn += de_dtheta * gn[a];
    }
    if (normal_length > 0.0) {
      const Vec3 g = (dn - normal * normal.dot(dn)) / normal_length;
      const uint32_t* nb = nodes.neighborsOf(i);
      for (size_t p = nodes.fan_offsets[i]; p < nodes.fan_offsets[i + 1]; ++p) {
        const auto& pr = nodes.fan_pairs[p];
        const Vec3 ea = x[nb[pr.first]] - x[i], eb = x[nb[pr.second]] - x[i];
        (*grad)[nb[pr.first]] += eb.cross(g);
        (*grad)[nb[pr.second]] += g.cross(ea);
        (*grad)[i] -= eb.cross(g) + g.cross(ea);
      }
    }
  }
  return value;
}

// Rest state away from the deformed one (plastic-like), per-fiber stiffness factors away from 1.
void perturbRestState(ShellFibers& fibers, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (Fiber& f : fibers.fibers) {
    f.rest_length *= 1.0 + 0.05 * (u(rng) - 0.5);
    f.rest_angle += 0.1 * (u(rng) - 0.5);
    f.stretch_scale = 0.5 + u(rng);
    f.bend_scale = u(rng) < 0.5 ? 1.0 : 0.3 + 2.0 * u(rng);
  }
}

void checkAgainstReference(const ShellNodes& nodes, const std::vector<Vec3>& x, const char* what) {
  ShellFibers fibers = buildShellFibers(nodes);
  perturbRestState(fibers, 11);
  ShellMaterial mat;
  mat.stretch_stiffness = 1000.0;
  mat.bending_stiffness = 10.0;
  const ShellEnergy energy(nodes, fibers, mat);
  std::vector<Vec3> g, g_ref;
  std::vector<double> length, angle, length_ref, angle_ref;
  const ShellEnergyValue e = energy.evaluate(x, &g, &length, &angle);
  const ShellEnergyValue e_ref = referenceEnergy(nodes, fibers, mat, energy.bendingForms(), x, &g_ref);
  measureFibers(nodes, fibers, x, &length_ref, &angle_ref);
  double gmax = 0.0, gerr = 0.0, lerr = 0.0, aerr = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    gmax = std::max(gmax, g_ref[i].norm());
    gerr = std::max(gerr, (g[i] - g_ref[i]).norm());
  }
  for (size_t q = 0; q < fibers.size(); ++q) {
    lerr = std::max(lerr, std::abs(length[q] - length_ref[q]) / length_ref[q]);
    aerr = std::max(aerr, std::abs(angle[q] - angle_ref[q]));
  }
  const double emem = std::abs(e.membrane - e_ref.membrane) / e_ref.membrane;
  const double ebend = std::abs(e.bending - e_ref.bending) / e_ref.bending;
  std::printf(
      "%s: %zu nodes, %zu fibers: |grad - ref|max / |ref|max %.2e, energy rel. error membrane %.2e bending "
      "%.2e, fiber length %.2e, angle %.2e\n",
      what, nodes.size(), fibers.size(), gerr / gmax, emem, ebend, lerr, aerr);
  ASSERT_GT(gmax, 0.0);
  EXPECT_LT(gerr, 1e-12 * gmax);
  EXPECT_LT(emem, 1e-12);
  EXPECT_LT(ebend, 1e-12);
  EXPECT_LT(lerr, 1e-13);
  EXPECT_LT(aerr, 1e-12);
  // The energy-only pass gives the same energies.
  const ShellEnergyValue e_only = energy.evaluate(x);
  EXPECT_EQ(e_only.membrane, e.membrane);
  EXPECT_EQ(e_only.bending, e.bending);
}

TEST(ShellFastPaths, ForcesEqualStraightforwardReferenceOnSheet) {
  const ShellNodes nodes = sheetNodes(1.0, 0.03, 200);
  ASSERT_GE(nodes.size(), 1000u);
  checkAgainstReference(nodes, wobble(nodes.rest_positions, 0.01), "sheet");
}

TEST(ShellFastPaths, ForcesEqualStraightforwardReferenceOnSphere) {
  const ShellNodes nodes = sphereNodes(0.15);
  checkAgainstReference(nodes, wobble(nodes.rest_positions, 0.03), "sphere");
}

TEST(ShellFastPaths, FusedFiberMeasureEqualsSeparateFunctions) {
  std::mt19937 rng(5);
  std::normal_distribution<double> d(0.0, 1.0);
  double err = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 x(d(rng), d(rng), d(rng));
    const Vec3 x1 = x + Vec3(-1.0 + 0.2 * d(rng), 0.2 * d(rng), 0.2 * d(rng));
    const Vec3 x2 = x + Vec3(1.0 + 0.2 * d(rng), 0.2 * d(rng), 0.2 * d(rng));
    const Vec3 normal = Vec3(0.1 * d(rng), 0.1 * d(rng), 1.0).normalized();
    std::array<Vec3, 3> gl, ga;
    Vec3 gn;
    const double l = fiberArcLength(x1, x, x2, &gl);
    const double a = fiberNormalAngle(x1, x, x2, normal, &ga, &gn);
    FiberMeasure m;
    measureFiber(x1 - x, x2 - x, normal, true, &m);
    err = std::max({err, std::abs(m.length - l) / l, std::abs(m.angle - a)});
    err = std::max({err, (m.grad_length[0] - gl[0]).norm(), (m.grad_length[1] - gl[2]).norm(),
                    (m.grad_length[0] + m.grad_length[1] + gl[1]).norm()});
    err = std::max({err, (m.grad_angle[0] - ga[0]).norm(), (m.grad_angle[1] - ga[2]).norm(),
                    (m.grad_angle[0] + m.grad_angle[1] + ga[1]).norm(), (m.grad_normal - gn).norm()});
  }
  std::printf("fused fiber measure: max deviation %.2e over 200 random fibers\n", err);
  EXPECT_LT(err, 1e-12);
}

TEST(ShellFastPaths, FiberPairMeasureEqualsSingleMeasures) {
  std::mt19937 rng(6);
  std::normal_distribution<double> d(0.0, 1.0);
  double err = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    Vec3 e1[2], e2[2];
    for (int k = 0; k < 2; ++k) {
      e1[k] = Vec3(-1.0 + 0.3 * d(rng), 0.3 * d(rng), 0.3 * d(rng));
      e2[k] = Vec3(1.0 + 0.3 * d(rng), 0.3 * d(rng), 0.3 * d(rng));
    }
    if (trial == 0) e1[1] = e2[1] = Vec3::Zero();  // degenerate fiber: zero norms give zero terms, no NaN
    const Vec3 normal = Vec3(0.1 * d(rng), 0.1 * d(rng), 1.0).normalized();
    for (bool gradients : {false, true}) {
      FiberMeasure pair[2], single;
      measureFiberPair(e1, e2, normal, gradients, pair);
      for (int k = 0; k < 2; ++k) {
        measureFiber(e1[k], e2[k], normal, gradients, &single);
        ASSERT_TRUE(std::isfinite(pair[k].length) && std::isfinite(pair[k].angle));
        err =
            std::max({err, std::abs(pair[k].length - single.length), std::abs(pair[k].angle - single.angle)});
        if (!gradients) continue;
        for (int e = 0; e < 2; ++e) {
          err = std::max({err, (pair[k].grad_length[e] - single.grad_length[e]).norm(),
                          (pair[k].grad_angle[e] - single.grad_angle[e]).norm()});
        }
        err = std::max(err, (pair[k].grad_normal - single.grad_normal).norm());
        ASSERT_TRUE(pair[k].grad_normal.allFinite() && pair[k].grad_angle[0].allFinite());
      }
    }
  }
  std::printf("fiber pair measure: max deviation from single measures %.2e\n", err);
  EXPECT_LT(err, 1e-14);
}

TEST(ShellFastPaths, SolverFiberMeasuresFollowThePositions) {
  ShellSolver solver(sheetNodes(1.0, 0.05, 120), ShellMaterial(), ShellSolverOptions());
  solver.setPositions(wobble(solver.nodes().rest_positions, 0.01));
  for (int s = 0; s < 3; ++s) solver.step();
  std::vector<double> length, angle;
  measureFibers(solver.nodes(), solver.fibers(), solver.positions(), &length, &angle);
  ASSERT_EQ(solver.fiberLengths().size(), length.size());
  double err = 0.0;
  for (size_t q = 0; q < length.size(); ++q) {
    err = std::max({err, std::abs(solver.fiberLengths()[q] - length[q]) / length[q],
                    std::abs(solver.fiberAngles()[q] - angle[q])});
  }
  EXPECT_LT(err, 1e-12);
}

// Cutting a sheet crack by crack with incremental re-neighbouring ends in the neighbourhoods of one full
// recomputation against all cracks.
TEST(ShellFastPaths, IncrementalReneighbouringEqualsFullRecomputation) {
  const double h = 0.05;
  const ShellNodes start = sheetNodes(1.0, h, 150);
  std::vector<ShellCrack> cracks;
  for (double y = -0.5; y <= 0.2; y += 0.5 * h) {
    ShellCrack c;
    c.center = Vec3(0.01 + 0.1 * y, y, 0.0);
    c.normal = Vec3(1.0, -0.1, 0.0).normalized();
    c.radius = h;
    cracks.push_back(c);
  }
  ShellNodes full = start, step = start;
  const std::vector<uint32_t> dirty_full = recomputeVisibleNeighborhoods(full, cracks, 8);
  size_t dirty_steps = 0;
  for (size_t c = 0; c < cracks.size(); c += 3) {
    const size_t end = std::min(cracks.size(), c + 3);
    const std::vector<ShellCrack> upto(cracks.begin(), cracks.begin() + end);
    dirty_steps += recomputeVisibleNeighborhoods(step, upto, 8, c).size();
  }
  std::printf("%zu cracks: full recomputation %zu nodes, incremental %zu node recomputations\n",
              cracks.size(), dirty_full.size(), dirty_steps);
  ASSERT_GT(dirty_full.size(), 0u);
  // A list recomputed against the earlier cracks that no new crack cuts is also the first visible nodes
  // under all cracks, so the incremental result matches exactly.
  EXPECT_EQ(step.neighbors, full.neighbors);
  EXPECT_EQ(step.neighbor_offsets, full.neighbor_offsets);
  EXPECT_EQ(step.fan_pairs, full.fan_pairs);
  EXPECT_EQ(step.fan_offsets, full.fan_offsets);
}

// A pulled pin moves by v dt per step, keeps zero velocity, and its work keeps the energy check quiet.
TEST(ShellFastPaths, PinVelocityMovesPinnedNodesInTheDrift) {
  ShellSolverOptions options;
  options.time_step = 2e-3;
  ShellMaterial mat;
  mat.stretch_stiffness = 100.0;
  mat.bending_stiffness = 0.01;
  mat.damping = 1.0;
  ShellSolver solver(sheetNodes(1.0, 0.1, 60), mat, options);
  const Vec3 pull(0.5, 0.0, 0.0);
  std::vector<size_t> left, right;
  for (size_t i = 0; i < solver.nodes().size(); ++i) {
    const double px = solver.nodes().rest_positions[i].x();
    if (px < -0.4) solver.pin(i), left.push_back(i);
    if (px > 0.4) solver.setPinVelocity(i, pull), right.push_back(i);
  }
  ASSERT_FALSE(left.empty());
  ASSERT_FALSE(right.empty());
  const int steps = 200;
  for (int s = 0; s < steps; ++s) ASSERT_NO_THROW(solver.step());
  double err = 0.0;
  for (size_t i : right) {
    err = std::max(
        err,
        (solver.positions()[i] - solver.nodes().rest_positions[i] - steps * options.time_step * pull).norm());
    EXPECT_EQ(solver.velocities()[i], Vec3::Zero());
  }
  for (size_t i : left) EXPECT_EQ(solver.positions()[i], solver.nodes().rest_positions[i]);
  EXPECT_LT(err, 1e-12);
  // The sheet is stretched: the middle follows the pull partway.
  double mean_x = 0.0;
  size_t middle = 0;
  for (size_t i = 0; i < solver.nodes().size(); ++i) {
    if (std::abs(solver.nodes().rest_positions[i].x() - 0.2) < 0.05)
      mean_x += solver.positions()[i].x() - solver.nodes().rest_positions[i].x(), ++middle;
  }
  ASSERT_GT(middle, 0u);
  mean_x /= middle;
  std::printf("pulled by %.3f: nodes at x = 0.2 moved %.4f along x\n", steps * options.time_step * pull.x(),
              mean_x);
  EXPECT_GT(mean_x, 0.0);
  EXPECT_LT(mean_x, steps * options.time_step * pull.x());
  EXPECT_THROW(solver.setPinVelocity(0, Vec3(NAN, 0, 0)), std::invalid_argument);
}

}  // namespace
}  // namespace rc
