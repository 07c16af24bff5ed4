#include "relaxed_connectivity/sph/sph_skinning.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_lattice.h"

namespace rc {
namespace {

using Mat3 = Eigen::Matrix3d;

Mat3 rotation(double angle, const Vec3& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

Mat3 cofactor(const Mat3& j) {
  return j.determinant() * j.inverse().transpose();
}

/// Surfels on the boundary of the box [lo, hi], `per_unit` samples per unit length on each face, with
/// outward normals and radius 0.5 / per_unit.
SurfelCloud boxSurface(const Vec3& lo, const Vec3& hi, double per_unit) {
  SurfelCloud cloud;
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    const int na = std::max(1, static_cast<int>(std::lround((hi[a] - lo[a]) * per_unit)));
    const int nb = std::max(1, static_cast<int>(std::lround((hi[b] - lo[b]) * per_unit)));
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i <= na; ++i)
        for (int j = 0; j <= nb; ++j) {
          Vec3 p, n = Vec3::Zero();
          p[axis] = side ? hi[axis] : lo[axis];
          p[a] = lo[a] + (hi[a] - lo[a]) * i / na;
          p[b] = lo[b] + (hi[b] - lo[b]) * j / nb;
          n[axis] = side ? 1.0 : -1.0;
          cloud.positions.push_back(p);
          cloud.normals.push_back(n);
          cloud.radii.push_back(0.5 / per_unit);
        }
  }
  return cloud;
}

struct Solid {
  SphSkinRest rest;
  SurfelCloud surface;
};

/// An fcc box [lo, hi] of spacing d (sampled with orientation q) and its boundary surface.
Solid boxSolid(double d, const Vec3& lo, const Vec3& hi, const Mat3& q = Mat3::Identity()) {
  Solid s;
  const SphLattice lattice(3, d);
  SphLatticeFrame frame;
  frame.orientation = q;
  frame.origin = lo;
  s.rest.positions = sampleLatticeBox(lattice, lo, hi, frame);
  s.surface = boxSurface(lo, hi, 2.0 / d);
  return s;
}

double maxDistance(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double m = 0.0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, (a[i] - b[i]).norm());
  return m;
}

SphSkinConfig skinConfig(double h) {
  SphSkinConfig c;
  c.support_radius = h;
  return c;
}

TEST(SphSkin, RigidMotionReproducesSurfaceExactly) {
  const double d = 0.1, h = 2.0 * d;
  Solid s = boxSolid(d, Vec3(-0.3, -0.2, -0.2), Vec3(0.3, 0.2, 0.2));
  // Per-particle rest transforms (as a solid's A_i^0 would be): the skin must use A_i (A_i^0)^-1.
  s.rest.transforms.resize(s.rest.positions.size());
  for (size_t i = 0; i < s.rest.transforms.size(); ++i)
    s.rest.transforms[i] = rotation(0.1 * i, Vec3(1, 2, 3)) * (1.0 + 0.01 * (i % 7));
  SphSkin skin(s.rest, s.surface.positions, skinConfig(h));
  EXPECT_EQ(skin.pointCount(), s.surface.size());
  EXPECT_EQ(skin.orphanCount(), 0u);
  EXPECT_GT(skin.pairCount(), 4 * skin.pointCount());

  const Mat3 r = rotation(1.3, Vec3(-1, 0.5, 2));
  const Vec3 t(2.0, -1.0, 0.5);
  std::vector<Vec3> x;
  std::vector<Mat3> a;
  for (size_t i = 0; i < s.rest.positions.size(); ++i) {
    x.push_back(r * s.rest.positions[i] + t);
    a.push_back(r * s.rest.transforms[i]);
  }
  std::vector<Vec3> expected;
  for (const Vec3& p : s.surface.positions) expected.push_back(r * p + t);

  for (int own_fit = 0; own_fit < 2; ++own_fit) {
    if (own_fit)
      skin.deform(x);
    else
      skin.deform(x, a);
    const double error = maxDistance(skin.points(), expected);
    std::printf("rigid motion (%s transforms): max position error %.3g over %zu points, %zu pairs\n",
                own_fit ? "fitted" : "given", error, skin.pointCount(), skin.pairCount());
    EXPECT_LT(error, 1e-12);
    SurfelCloud out;
    skin.deformSurfels(s.surface, out);
    double normal_error = 0.0, radius_error = 0.0;
    for (size_t p = 0; p < out.size(); ++p) {
      normal_error = std::max(normal_error, (out.normals[p] - r * s.surface.normals[p]).norm());
      radius_error = std::max(radius_error, std::abs(out.radii[p] - s.surface.radii[p]));
      EXPECT_NEAR(out.normals[p].norm(), 1.0, 1e-14);
    }
    EXPECT_LT(normal_error, 1e-12);
    EXPECT_LT(radius_error, 1e-14);
  }
  // The fitted transforms are the rotation composed with the rest transforms.
  std::vector<Mat3> fitted;
  skin.fitTransforms(x, fitted);
  ASSERT_EQ(fitted.size(), x.size());
  for (uint32_t i : skin.boundParticles()) EXPECT_LT((fitted[i] - a[i]).norm(), 1e-12);
}

TEST(SphSkin, AffineMotionHasLinearPrecision) {
  const double d = 0.1, h = 2.0 * d;
  Solid s = boxSolid(d, Vec3(0.0, 0.0, 0.0), Vec3(0.5, 0.3, 0.4));
  SphSkin skin(s.rest, s.surface.positions, skinConfig(h));
  Mat3 f;
  f << 1.3, 0.2, -0.1,  //
      0.05, 0.8, 0.3,   //
      -0.2, 0.1, 1.1;
  const Vec3 t(0.3, 0.1, -0.4);
  std::vector<Vec3> x;
  std::vector<Mat3> a(s.rest.positions.size(), f);
  for (const Vec3& p : s.rest.positions) x.push_back(f * p + t);
  for (int own_fit = 0; own_fit < 2; ++own_fit) {
    if (own_fit)
      skin.deform(x);
    else
      skin.deform(x, a);
    SurfelCloud out;
    s.surface.axes1.assign(s.surface.size(), Vec3(0.01, 0.0, 0.0));
    s.surface.axes2.assign(s.surface.size(), Vec3(0.0, 0.0, 0.02));
    skin.deformSurfels(s.surface, out);
    double position_error = 0.0, normal_error = 0.0, radius_error = 0.0, axis_error = 0.0;
    for (size_t p = 0; p < out.size(); ++p) {
      const Vec3 n0 = s.surface.normals[p];
      const Vec3 area = cofactor(f) * n0;  // Nanson
      position_error = std::max(position_error, (out.positions[p] - (f * s.surface.positions[p] + t)).norm());
      normal_error = std::max(normal_error, (out.normals[p] - area.normalized()).norm());
      radius_error =
          std::max(radius_error, std::abs(out.radii[p] - s.surface.radii[p] * std::sqrt(area.norm())));
      axis_error = std::max(axis_error, (out.axes1[p] - f * s.surface.axes1[p]).norm() +
                                            (out.axes2[p] - f * s.surface.axes2[p]).norm());
      EXPECT_NEAR(out.normals[p].norm(), 1.0, 1e-14);
    }
    std::printf("affine motion (%s transforms): position %.3g normal %.3g radius %.3g axes %.3g\n",
                own_fit ? "fitted" : "given", position_error, normal_error, radius_error, axis_error);
    EXPECT_LT(position_error, 1e-10);
    EXPECT_LT(normal_error, 1e-10);
    EXPECT_LT(radius_error, 1e-10);
    EXPECT_LT(axis_error, 1e-10);
  }
}

TEST(SphSkin, SolidLatticeTransformsDriveTheSkin) {
  // The A_i of SphElasticSolid (lattice coordinates -> world) with the sampling orientation as rest
  // transform.
  const double d = 0.05, h = 2.0 * d;
  const Mat3 q = rotation(0.7, Vec3(1, -2, 1));
  Solid s = boxSolid(d, Vec3(0.0, 0.0, 0.0), Vec3(0.3, 0.2, 0.2), q);
  s.rest.uniform_transform = q;
  SphSkin skin(s.rest, s.surface.positions, skinConfig(h));

  SphElasticConfig e;
  e.lattice_spacing = d;
  const SphKernels kernels(3, h);
  SphElasticSolid solid(e, kernels, 1, q);
  Mat3 f = rotation(0.15, Vec3(0, 1, 1));
  f *= Vec3(1.04, 0.97, 1.02).asDiagonal();
  const Vec3 t(0.01, 0.02, -0.03);
  std::vector<Vec3> x;
  for (const Vec3& p : s.rest.positions) x.push_back(f * p + t);
  SphParticles particles;
  solid.addParticles(particles, x, 1.0);
  // One evaluation from the rest orientation assigns every lattice point correctly (8.21) for a motion this
  // small (in a simulation A_i follows the motion step by step).
  std::vector<Vec3> forces;
  solid.computeForces(particles, forces);
  EXPECT_EQ(solid.stats().unassigned_pairs, 0u);
  ASSERT_EQ(solid.latticeTransforms().size(), x.size());
  skin.deform(particles.positions, solid.latticeTransforms());
  std::vector<Vec3> expected;
  for (const Vec3& p : s.surface.positions) expected.push_back(f * p + t);
  const double error = maxDistance(skin.points(), expected);
  std::printf("SphElasticSolid A_i under a stretch + rotation: max position error %.3g\n", error);
  EXPECT_LT(error, 1e-10);
}

/// Bending of a bar about the z axis with curvature kappa: the centre line y = 0 becomes an arc.
Vec3 bend(const Vec3& p, double kappa) {
  const double radius = 1.0 / kappa - p.y(), angle = kappa * p.x();
  return Vec3(radius * std::sin(angle), 1.0 / kappa - radius * std::cos(angle), p.z());
}
Mat3 bendGradient(const Vec3& p, double kappa) {
  const double radius = 1.0 / kappa - p.y(), angle = kappa * p.x();
  Mat3 g;
  g << radius * kappa * std::cos(angle), -std::sin(angle), 0.0,  //
      radius * kappa * std::sin(angle), std::cos(angle), 0.0,    //
      0.0, 0.0, 1.0;
  return g;
}

TEST(SphSkin, BentBarConvergesToAnalyticSurface) {
  const double kappa = 1.0;  // bar [0, 1] x [-0.1, 0.1]^2 bent by 1 radian
  const Vec3 lo(0.0, -0.1, -0.1), hi(1.0, 0.1, 0.1);
  std::vector<double> spacings = {0.1, 0.05, 0.025}, fitted_errors, exact_errors;
  for (double d : spacings) {
    Solid s = boxSolid(d, lo, hi);
    SphSkin skin(s.rest, s.surface.positions, skinConfig(2.0 * d));
    std::vector<Vec3> x;
    std::vector<Mat3> gradients;
    for (const Vec3& p : s.rest.positions) {
      x.push_back(bend(p, kappa));
      gradients.push_back(bendGradient(p, kappa));
    }
    std::vector<Vec3> expected;
    std::vector<Vec3> expected_normals;
    for (size_t p = 0; p < s.surface.size(); ++p) {
      expected.push_back(bend(s.surface.positions[p], kappa));
      expected_normals.push_back(
          (cofactor(bendGradient(s.surface.positions[p], kappa)) * s.surface.normals[p]).normalized());
    }
    skin.deform(x);
    const double fitted = maxDistance(skin.points(), expected);
    std::vector<Vec3> normals;
    skin.transformNormals(s.surface.normals, normals);
    double angle = 0.0;
    for (size_t p = 0; p < normals.size(); ++p)
      angle = std::max(angle, std::acos(std::min(1.0, normals[p].dot(expected_normals[p]))));
    skin.deform(x, gradients);
    const double exact = maxDistance(skin.points(), expected);
    std::printf(
        "bent bar d = %.3f (h = 2d, %zu particles, %zu points, %zu pairs): max error fitted F %.3g "
        "(%.3g d), exact gradient F %.3g (%.3g d), max normal angle (fitted) %.3g rad\n",
        d, s.rest.positions.size(), skin.pointCount(), skin.pairCount(), fitted, fitted / d, exact, exact / d,
        angle);
    fitted_errors.push_back(fitted);
    exact_errors.push_back(exact);
    EXPECT_LT(fitted, kappa * d * d);  // O(kappa h^2), h = 2d
    EXPECT_LT(angle, 2.0 * kappa * d);
  }
  for (size_t k = 1; k < spacings.size(); ++k) {
    const double order_fitted = std::log(fitted_errors[k - 1] / fitted_errors[k]) / std::log(2.0);
    const double order_exact = std::log(exact_errors[k - 1] / exact_errors[k]) / std::log(2.0);
    std::printf("bent bar convergence order d %.3f -> %.3f: fitted %.2f, exact gradient %.2f\n",
                spacings[k - 1], spacings[k], order_fitted, order_exact);
    EXPECT_GT(order_fitted, 1.7);
    EXPECT_GT(order_exact, 1.7);
  }
}

TEST(SphSkin, RawSphWeightSumsShowWhyTheyAreNormalised) {
  // sum_i V_i W_h(|s - X_i|) of (8.38) is ~1 deep inside and ~1/2 on the surface.
  const double d = 0.05, h = 2.0 * d;
  Solid s = boxSolid(d, Vec3(0.0, 0.0, 0.0), Vec3(0.4, 0.4, 0.4));
  const SphLattice lattice(3, d);
  s.rest.volumes.assign(s.rest.positions.size(), lattice.cellVolume());
  std::vector<Vec3> points = s.surface.positions;
  points.push_back(Vec3(0.2, 0.2, 0.2));
  const SphSkin skin(s.rest, points, skinConfig(h));
  const std::vector<double>& sums = skin.restWeightSums();
  double lo = 1e300, hi = 0.0, mean = 0.0;
  for (size_t p = 0; p + 1 < sums.size(); ++p) {
    lo = std::min(lo, sums[p]);
    hi = std::max(hi, sums[p]);
    mean += sums[p] / (sums.size() - 1);
  }
  std::printf("raw SPH weight sums: interior %.4f, surface points mean %.4f in [%.4f, %.4f]\n", sums.back(),
              mean, lo, hi);
  EXPECT_NEAR(sums.back(), 1.0, 0.05);
  EXPECT_LT(mean, 0.6);  // unnormalised, (8.38) would shrink the surface by ~half towards the origin
  EXPECT_LT(hi, 0.8);
  EXPECT_GT(lo, 0.0);
}

TEST(SphSkin, TwoDimensionalSolidKeepsThePlaneNormal) {
  const double d = 0.1, h = 2.0 * d;
  const SphLattice lattice(2, d);
  SphSkinRest rest;
  rest.positions = sampleLatticeBox(lattice, Vec3(0, 0, 0), Vec3(0.6, 0.4, 0));
  std::vector<Vec3> points = {Vec3(0.0, 0.2, 0.0), Vec3(0.3, 0.4, 0.0), Vec3(0.6, 0.1, 0.0)};
  SphSkinConfig c = skinConfig(h);
  c.dimension = 2;
  SphSkin skin(rest, points, c);
  const Mat3 r = rotation(0.8, Vec3::UnitZ());
  const Vec3 t(1.0, 2.0, 0.0);
  std::vector<Vec3> x;
  for (const Vec3& p : rest.positions) x.push_back(r * p + t);
  skin.deform(x);
  for (size_t p = 0; p < points.size(); ++p)
    EXPECT_LT((skin.points()[p] - (r * points[p] + t)).norm(), 1e-12);
  for (const Mat3& j : skin.jacobians()) EXPECT_LT((j - r).norm(), 1e-12);
}

TEST(SphSkin, MeshKeepsTrianglesAndRotatesNormals) {
  const double d = 0.1;
  Solid s = boxSolid(d, Vec3(0, 0, 0), Vec3(0.3, 0.3, 0.3));
  TriangleMesh mesh;
  mesh.vertices.positions = {Vec3(0, 0, 0.3), Vec3(0.3, 0, 0.3), Vec3(0.3, 0.3, 0.3), Vec3(0, 0.3, 0.3)};
  mesh.vertices.normals.assign(4, Vec3::UnitZ());
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  SphSkin skin(s.rest, mesh.vertices.positions, skinConfig(2.0 * d));
  const Mat3 r = rotation(2.0, Vec3(1, 1, 0));
  std::vector<Vec3> x;
  for (const Vec3& p : s.rest.positions) x.push_back(r * p);
  skin.deform(x);
  TriangleMesh out;
  skin.deformMesh(mesh, out);
  ASSERT_EQ(out.triangles.size(), 2u);
  EXPECT_EQ(out.triangles[1], mesh.triangles[1]);
  for (size_t v = 0; v < 4; ++v) {
    EXPECT_LT((out.vertices.positions[v] - r * mesh.vertices.positions[v]).norm(), 1e-12);
    EXPECT_LT((out.vertices.normals[v] - r * Vec3::UnitZ()).norm(), 1e-12);
  }
}

TEST(SphSkin, EdgeCases) {
  const double d = 0.1, h = 2.0 * d;
  Solid s = boxSolid(d, Vec3(0, 0, 0), Vec3(0.3, 0.3, 0.3));
  // Empty surface: nothing bound, deform is a no-op.
  SphSkin empty(s.rest, {}, skinConfig(h));
  EXPECT_EQ(empty.pointCount(), 0u);
  EXPECT_EQ(empty.pairCount(), 0u);
  empty.deform(s.rest.positions);
  EXPECT_TRUE(empty.points().empty());

  // A point far from every particle: an error naming it, or its nearest particle alone.
  const std::vector<Vec3> far = {Vec3(0.1, 0.1, 0.1), Vec3(2.0, 0.15, 0.15)};
  try {
    SphSkin skin(s.rest, far, skinConfig(h));
    ADD_FAILURE() << "no exception for a point far from the solid";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("surface point 1"), std::string::npos) << error.what();
  }
  SphSkinConfig nearest = skinConfig(h);
  nearest.orphans = SphSkinOrphanPolicy::kNearestParticle;
  SphSkin skin(s.rest, far, nearest);
  EXPECT_EQ(skin.orphanCount(), 1u);
  const Mat3 r = rotation(0.5, Vec3(0, 0, 1));
  std::vector<Vec3> x;
  for (const Vec3& p : s.rest.positions) x.push_back(r * p);
  skin.deform(x);
  EXPECT_LT((skin.points()[1] - r * far[1]).norm(), 1e-12);  // rigid: exact even for the orphan

  // Bad input.
  EXPECT_THROW(SphSkin(s.rest, far, skinConfig(0.0)), std::invalid_argument);
  SphSkinRest no_solid = s.rest;
  no_solid.solid = {static_cast<uint32_t>(s.rest.positions.size())};
  EXPECT_THROW(SphSkin(no_solid, far, nearest), std::invalid_argument);
  SphSkinRest nan_point = s.rest;
  nan_point.positions[0].x() = std::nan("");
  EXPECT_THROW(SphSkin(nan_point, far, nearest), std::invalid_argument);
  SphSkinRest singular = s.rest;
  singular.uniform_transform = Mat3::Zero();
  EXPECT_THROW(SphSkin(singular, far, nearest), std::invalid_argument);
  SphSkinRest nothing;
  EXPECT_THROW(SphSkin(nothing, far, nearest), std::invalid_argument);
  EXPECT_THROW(skin.deform(std::vector<Vec3>(3)), std::invalid_argument);
  EXPECT_THROW(skin.deform(x, std::vector<Mat3>(3)), std::invalid_argument);
  std::vector<Vec3> normals;
  EXPECT_THROW(skin.transformNormals(std::vector<Vec3>(5), normals), std::invalid_argument);
}

TEST(SphSkin, SolidSubsetOnlyBindsItsParticles) {
  const double d = 0.1;
  Solid s = boxSolid(d, Vec3(0, 0, 0), Vec3(0.3, 0.3, 0.3));
  const size_t first = s.rest.positions.size();
  // A second body right next to the first must not be bound.
  Solid other = boxSolid(d, Vec3(0.35, 0, 0), Vec3(0.65, 0.3, 0.3));
  s.rest.positions.insert(s.rest.positions.end(), other.rest.positions.begin(), other.rest.positions.end());
  for (uint32_t i = 0; i < first; ++i) s.rest.solid.push_back(i);
  SphSkin skin(s.rest, s.surface.positions, skinConfig(2.0 * d));
  for (uint32_t i : skin.boundParticles()) EXPECT_LT(i, first);
  // Moving only the other body leaves the skin in place.
  std::vector<Vec3> x = s.rest.positions;
  for (size_t i = first; i < x.size(); ++i) x[i] += Vec3(0.05, 0.3, -0.2);
  skin.deform(x);
  EXPECT_LT(maxDistance(skin.points(), s.surface.positions), 1e-12);
}

}  // namespace
}  // namespace rc
