// Sample shells for the thin-shell tests: surfel clouds of a sphere and of a flat sheet, and deformations.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/shell/shell_energy.h"
#include "relaxed_connectivity/shell/shell_nodes.h"

namespace rc::shell_test {

/// Material with stiffnesses K_s, K_b and damping D (density 1).
inline ShellMaterial material(double ks, double kb, double damping) {
  ShellMaterial m;
  m.stretch_stiffness = ks;
  m.bending_stiffness = kb;
  m.damping = damping;
  return m;
}

/// Fibonacci sampling of a sphere of radius r about the origin, outward normals.
inline SurfelCloud sphereCloud(double r, size_t count) {
  SurfelCloud cloud;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count;
    const double s = std::sqrt(1.0 - z * z);
    const Vec3 n(s * std::cos(golden * i), s * std::sin(golden * i), z);
    cloud.positions.push_back(r * n);
    cloud.normals.push_back(n);
  }
  return cloud;
}

/// Jittered grid on the square [-size/2, size/2]^2 in the plane z = 0, normal +z.
inline SurfelCloud sheetCloud(double size, size_t per_side, unsigned seed = 7) {
  SurfelCloud cloud;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const double step = size / per_side;
  for (size_t a = 0; a < per_side; ++a) {
    for (size_t b = 0; b < per_side; ++b) {
      cloud.positions.emplace_back(-0.5 * size + (a + 0.5 + jitter(rng)) * step,
                                   -0.5 * size + (b + 0.5 + jitter(rng)) * step, 0.0);
      cloud.normals.push_back(Vec3::UnitZ());
    }
  }
  return cloud;
}

/// Shell nodes of a unit sphere at node spacing h.
inline ShellNodes sphereNodes(double h, size_t surfels = 12000) {
  ShellNodeOptions options;
  options.spacing = h;
  return selectShellNodes(sphereCloud(1.0, surfels), options);
}

/// Shell nodes of a flat square sheet of side `size` at node spacing h.
inline ShellNodes sheetNodes(double size, double h, size_t per_side = 150) {
  ShellNodeOptions options;
  options.spacing = h;
  return selectShellNodes(sheetCloud(size, per_side), options);
}

/// Isometric bend of the plane z = 0 onto a cylinder of radius r whose axis is parallel to y at z = r.
inline std::vector<Vec3> bendOntoCylinder(const std::vector<Vec3>& x, double r) {
  std::vector<Vec3> out;
  for (const Vec3& p : x) out.emplace_back(r * std::sin(p.x() / r), p.y(), r * (1.0 - std::cos(p.x() / r)));
  return out;
}

/// Deterministic smooth non-rigid deformation with amplitude `a` (for gradient checks).
inline std::vector<Vec3> wobble(const std::vector<Vec3>& x, double a) {
  std::vector<Vec3> out;
  for (const Vec3& p : x) {
    out.push_back(p + a * Vec3(std::sin(2.1 * p.y() + 0.3), std::cos(1.7 * p.z() + 1.1 * p.x()),
                               std::sin(1.3 * p.x() - 0.8 * p.y())));
  }
  return out;
}

}  // namespace rc::shell_test
