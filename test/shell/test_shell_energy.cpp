// Thin-shell energy (thesis 7.2): gradients, invariance, zero modes and analytic energies.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "relaxed_connectivity/shell/shell_energy.h"
#include "shell_test_support.h"

namespace rc {
namespace {

using shell_test::bendOntoCylinder;
using shell_test::sheetNodes;
using shell_test::sphereNodes;
using shell_test::wobble;

ShellMaterial unitMaterial() {
  ShellMaterial m;
  m.stretch_stiffness = 1.0;
  m.bending_stiffness = 1.0;
  return m;
}

double totalArea(const ShellNodes& nodes) {
  double a = 0.0;
  for (double v : nodes.rest_areas) a += v;
  return a;
}

TEST(ShellEnergy, SphereNodeAreasSumToTheSurfaceArea) {
  const ShellNodes nodes = sphereNodes(0.2);
  std::printf("sphere h=0.2: %zu nodes, area %.4f (4 pi = %.4f)\n", nodes.size(), totalArea(nodes), 4 * M_PI);
  // Measured 0.03 % (each node sums its surfels' tangent Voronoi areas; 1.4 % with the nodes' own cells).
  EXPECT_NEAR(totalArea(nodes), 4.0 * M_PI, 0.003 * 4.0 * M_PI);
}

TEST(ShellEnergy, RestStateHasNoEnergyAndNoForce) {
  const ShellNodes nodes = sphereNodes(0.25);
  const ShellFibers fibers = buildShellFibers(nodes);
  ShellEnergy energy(nodes, fibers, unitMaterial());
  std::vector<Vec3> g;
  const ShellEnergyValue e = energy.evaluate(nodes.rest_positions, &g);
  EXPECT_LT(std::abs(e.total()), 1e-24);
  for (const Vec3& v : g) EXPECT_LT(v.norm(), 1e-12);
}

// Central differences of the energy against the analytic gradient: the error falls as eps^2.
void checkGradient(const ShellNodes& nodes, const std::vector<Vec3>& x, const char* what) {
  const ShellFibers fibers = buildShellFibers(nodes);
  ShellEnergy energy(nodes, fibers, unitMaterial());
  std::vector<Vec3> g;
  energy.evaluate(x, &g);
  double gmax = 0.0;
  for (const Vec3& v : g) gmax = std::max(gmax, v.cwiseAbs().maxCoeff());
  ASSERT_GT(gmax, 0.0);
  const double eps[2] = {2e-4, 5e-5};
  double err[2] = {0.0, 0.0};
  for (int e = 0; e < 2; ++e) {
    std::vector<Vec3> xp = x;
    for (size_t i = 0; i < x.size(); i += 11) {  // every 11th node, all coordinates
      for (int c = 0; c < 3; ++c) {
        xp[i][c] = x[i][c] + eps[e];
        const double ep = energy.evaluate(xp).total();
        xp[i][c] = x[i][c] - eps[e];
        const double em = energy.evaluate(xp).total();
        xp[i][c] = x[i][c];
        err[e] = std::max(err[e], std::abs((ep - em) / (2 * eps[e]) - g[i][c]));
      }
    }
  }
  const double rate = std::log(err[0] / err[1]) / std::log(eps[0] / eps[1]);
  std::printf("%s: |grad|max %.3e, FD error %.3e (eps 2e-4) %.3e (eps 5e-5), order %.2f\n", what, gmax,
              err[0], err[1], rate);
  EXPECT_LT(err[1], 1e-4 * gmax);
  EXPECT_GT(rate, 1.8);
}

TEST(ShellEnergy, GradientMatchesCentralDifferencesOnSphere) {
  const ShellNodes nodes = sphereNodes(0.25);
  checkGradient(nodes, wobble(nodes.rest_positions, 0.05), "sphere");
}

TEST(ShellEnergy, GradientMatchesCentralDifferencesOnSheet) {
  const ShellNodes nodes = sheetNodes(1.0, 0.1);
  checkGradient(nodes, wobble(bendOntoCylinder(nodes.rest_positions, 0.8), 0.02), "bent sheet");
}

TEST(ShellEnergy, RigidMotionStoresNoEnergyAndExertsNoNetForce) {
  const ShellNodes nodes = sphereNodes(0.25);
  const ShellFibers fibers = buildShellFibers(nodes);
  ShellEnergy energy(nodes, fibers, unitMaterial());
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 shift(0.3, -1.2, 2.0);
  std::vector<Vec3> moved, deformed = wobble(nodes.rest_positions, 0.05), deformed_moved;
  for (const Vec3& p : nodes.rest_positions) moved.push_back(rot * p + shift);
  for (const Vec3& p : deformed) deformed_moved.push_back(rot * p + shift);
  std::vector<Vec3> g;
  EXPECT_LT(energy.evaluate(moved, &g).total(), 1e-24);
  for (const Vec3& v : g) EXPECT_LT(v.norm(), 1e-12);
  const double e0 = energy.evaluate(deformed).total();
  const double e1 = energy.evaluate(deformed_moved, &g).total();
  EXPECT_GT(e0, 1e-4);
  EXPECT_NEAR(e1, e0, 1e-12 * e0);
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  double scale = 0.0;
  for (size_t i = 0; i < g.size(); ++i) {
    force += g[i];
    torque += deformed_moved[i].cross(g[i]);
    scale += g[i].norm();
  }
  std::printf("deformed + rigid: net force %.2e, net torque %.2e, sum |f| %.2e\n", force.norm(),
              torque.norm(), scale);
  EXPECT_LT(force.norm(), 1e-12 * scale);
  EXPECT_LT(torque.norm(), 1e-11 * scale);
}

TEST(ShellEnergy, RestHessianOfClosedSphereHasExactlySixZeroModes) {
  const ShellNodes nodes = sphereNodes(0.3, 6000);
  const ShellFibers fibers = buildShellFibers(nodes);
  ShellEnergy energy(nodes, fibers, unitMaterial());
  const size_t n = nodes.size(), dof = 3 * n;
  Eigen::MatrixXd h(dof, dof);
  const double eps = 1e-6;
  std::vector<Vec3> x = nodes.rest_positions, gp, gm;
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      x[i][c] += eps;
      energy.evaluate(x, &gp);
      x[i][c] -= 2 * eps;
      energy.evaluate(x, &gm);
      x[i][c] += eps;
      for (size_t j = 0; j < n; ++j) h.block<3, 1>(3 * j, 3 * i + c) = (gp[j] - gm[j]) / (2 * eps);
    }
  }
  const double asym = (h - h.transpose()).cwiseAbs().maxCoeff();
  h = 0.5 * (h + h.transpose());
  // Mass-weighted: eigenvalues of M^-1/2 H M^-1/2 (squared frequencies).
  for (size_t i = 0; i < dof; ++i) {
    for (size_t j = 0; j < dof; ++j) h(i, j) /= std::sqrt(energy.masses()[i / 3] * energy.masses()[j / 3]);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(h, Eigen::EigenvaluesOnly);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double top = lambda(dof - 1);
  int zero = 0;
  for (Eigen::Index k = 0; k < lambda.size(); ++k) zero += std::abs(lambda(k)) < 1e-6 * top;
  std::printf("sphere %zu nodes, %zu fibers: asymmetry %.1e, lambda min %.3e, 6th %.3e, 7th %.3e, max %.3e\n",
              n, fibers.size(), asym, lambda(0), lambda(5), lambda(6), top);
  EXPECT_EQ(zero, 6);
  EXPECT_GT(lambda(0), -1e-6 * top);
  EXPECT_GT(lambda(6), 1e-4 * top);
}

TEST(ShellEnergy, UniformStretchStoresAnalyticMembraneEnergy) {
  const ShellNodes nodes = sheetNodes(1.0, 0.08);
  const ShellFibers fibers = buildShellFibers(nodes);
  ShellMaterial material = unitMaterial();
  material.stretch_stiffness = 3.0;
  ShellEnergy energy(nodes, fibers, material);
  for (double s : {0.9, 1.05, 1.3}) {
    std::vector<Vec3> x;
    for (const Vec3& p : nodes.rest_positions) x.push_back(s * p);
    const ShellEnergyValue e = energy.evaluate(x);
    const double analytic = material.stretch_stiffness * (s * s - 1) * (s * s - 1) * totalArea(nodes);
    EXPECT_NEAR(e.membrane, analytic, 1e-10 * analytic) << "stretch " << s;
    EXPECT_LT(std::abs(e.bending), 1e-20);
  }
  // Stretch along x only by s: directional stretch (1 + (s^2 - 1) cos^2) averaged as for isotropic fibers.
  const double s = 1.1, e2 = s * s - 1;
  std::vector<Vec3> x;
  for (const Vec3& p : nodes.rest_positions) x.emplace_back(s * p.x(), p.y(), p.z());
  std::vector<double> mem;
  energy.nodeEnergies(x, &mem, nullptr);
  // Per unit area: K_s/2 [(e2/2)^2 + e2^2 <cos^4>] = K_s/2 e2^2 (1/4 + 3/8). Interior nodes only.
  double sum = 0.0, area = 0.0;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Vec3& p = nodes.rest_positions[i];
    if (std::max(std::abs(p.x()), std::abs(p.y())) > 0.5 - 2.5 * nodes.spacing) continue;
    sum += mem[i];
    area += nodes.rest_areas[i];
  }
  const double analytic = 0.5 * material.stretch_stiffness * e2 * e2 * (0.25 + 0.375) * area;
  std::printf("uniaxial stretch 1.1: interior membrane %.5e, analytic %.5e (ratio %.4f)\n", sum, analytic,
              sum / analytic);
  EXPECT_NEAR(sum / analytic, 1.0, 0.05);
}

// Bending energy K_b/2 |S - S0|_F^2 integrated over the (interior) rest area.
TEST(ShellEnergy, CylinderBendingMatchesAnalyticAtTwoDensities) {
  const double radius = 0.6;
  for (double h : {0.08, 0.05}) {
    const ShellNodes nodes = sheetNodes(1.4, h, 180);
    const ShellFibers fibers = buildShellFibers(nodes);
    ShellEnergy energy(nodes, fibers, unitMaterial());
    const std::vector<Vec3> x = bendOntoCylinder(nodes.rest_positions, radius);
    std::vector<double> mem, bend;
    energy.nodeEnergies(x, &mem, &bend);
    const std::vector<double> mean_h = energy.nodeMeanCurvature(x);
    double sum = 0.0, area = 0.0, hsum = 0.0, msum = 0.0;
    size_t count = 0;
    for (size_t i = 0; i < nodes.size(); ++i) {
      const Vec3& p = nodes.rest_positions[i];
      if (std::max(std::abs(p.x()), std::abs(p.y())) > 0.7 - 2.5 * nodes.spacing) continue;
      sum += bend[i];
      msum += mem[i];
      area += nodes.rest_areas[i];
      hsum += std::abs(mean_h[i]);
      ++count;
    }
    const double analytic = 0.5 / (radius * radius) * area;
    std::printf(
        "cylinder r=%.2f h=%.3f: %zu interior nodes, bending %.5e analytic %.5e ratio %.4f, |H| %.4f "
        "(1/2r = %.4f), membrane/bending %.2e\n",
        radius, nodes.spacing, count, sum, analytic, sum / analytic, hsum / count, 0.5 / radius, msum / sum);
    EXPECT_NEAR(sum / analytic, 1.0, 0.05);
    EXPECT_NEAR(hsum / count, 0.5 / radius, 0.05 * 0.5 / radius);
  }
}

TEST(ShellEnergy, SphereInflationBendingMatchesAnalyticAtTwoDensities) {
  const double scale = 1.25;
  for (double h : {0.2, 0.13}) {
    const ShellNodes nodes = sphereNodes(h, 20000);
    const ShellFibers fibers = buildShellFibers(nodes);
    ShellEnergy energy(nodes, fibers, unitMaterial());
    std::vector<Vec3> x;
    for (const Vec3& p : nodes.rest_positions) x.push_back(scale * p);
    const ShellEnergyValue e = energy.evaluate(x);
    const double dk = 1.0 / scale - 1.0;
    const double analytic = 0.5 * 2.0 * dk * dk * 4.0 * M_PI;  // K_b/2 (dk1^2 + dk2^2) A0
    const std::vector<double> mean_h = energy.nodeMeanCurvature(nodes.rest_positions);
    double hmean = 0.0;
    for (double v : mean_h) hmean += v / mean_h.size();
    std::printf("sphere h=%.3f: %zu nodes, rest H %.4f (1), bending %.5e analytic %.5e ratio %.4f\n",
                nodes.spacing, nodes.size(), hmean, e.bending, analytic, e.bending / analytic);
    EXPECT_NEAR(e.bending / analytic, 1.0, 0.05);
    EXPECT_NEAR(hmean, 1.0, 0.03);
  }
}

}  // namespace
}  // namespace rc
