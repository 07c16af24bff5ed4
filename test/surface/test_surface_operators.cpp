// Ray intersection (Algorithm 3.1), inside/outside (3.9), normal and radius estimation, analytic references.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/core/neighbor_lists.h"
#include "relaxed_connectivity/surface/analytic_shapes.h"
#include "relaxed_connectivity/surface/inside_outside.h"
#include "relaxed_connectivity/surface/mls_fits.h"
#include "relaxed_connectivity/surface/mls_surface.h"
#include "relaxed_connectivity/surface/normal_estimation.h"
#include "relaxed_connectivity/surface/radius_estimation.h"
#include "relaxed_connectivity/surface/ray_intersection.h"

namespace rc {
namespace {

MlsConfig planeConfig(double support) {
  MlsConfig c;
  c.fit = MlsFit::kPlane;
  c.weight = WeightFunction::wendland(support);
  return c;
}

Vec3 randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0, 1);
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

TEST(AnalyticShapes, ClosestPointsNormalsAndSamples) {
  const AnalyticTorus torus(Vec3(0.1, 0.2, -0.3), 1.0, 0.3);
  const AnalyticSphere sphere(Vec3(0.1, 0.2, -0.3), 0.7);
  std::mt19937_64 rng(1);
  for (const AnalyticSurface* s :
       {static_cast<const AnalyticSurface*>(&torus), static_cast<const AnalyticSurface*>(&sphere)}) {
    for (int i = 0; i < 1000; ++i) {
      const Vec3 x = Vec3(0.1, 0.2, -0.3) + 1.5 * randomUnit(rng) * std::sqrt((i + 1) / 1000.0);
      const Vec3 c = s->closestPoint(x);
      EXPECT_NEAR(s->signedDistance(c), 0.0, 1e-12);
      EXPECT_NEAR((x - c).norm(), std::abs(s->signedDistance(x)), 1e-12);
      EXPECT_NEAR(s->signedDistance(c + 1e-3 * s->normal(x)), 1e-3, 1e-9);  // outward
    }
    for (SamplingPattern pattern : {SamplingPattern::kFibonacci, SamplingPattern::kUniformRandom}) {
      const SurfelCloud cloud = s->sample(3000, {pattern, 0.0, 2});
      ASSERT_EQ(cloud.size(), 3000u);
      for (size_t i = 0; i < cloud.size(); ++i) {
        EXPECT_NEAR(s->signedDistance(cloud.positions[i]), 0.0, 1e-12);
        EXPECT_NEAR(cloud.normals[i].dot(s->normal(cloud.positions[i])), 1.0, 1e-12);
      }
      // Area-uniform: the fraction of samples on the outer half of the torus (cos v > 0) is (pi R + 2r)/(2 pi
      // R).
      if (s == &torus) {
        size_t outer = 0;
        for (const Vec3& p : cloud.positions) outer += std::hypot(p.x() - 0.1, p.y() - 0.2) > 1.0;
        EXPECT_NEAR(outer / 3000.0, (M_PI + 0.6) / (2 * M_PI), 0.02);
      }
    }
  }
  const SurfelCloud noisy = sphere.sample(20000, {SamplingPattern::kFibonacci, 0.01, 2});
  double ss = 0;
  for (const Vec3& p : noisy.positions) ss += std::pow(sphere.signedDistance(p), 2);
  EXPECT_NEAR(std::sqrt(ss / 20000), 0.01, 0.0005);  // normal component of isotropic noise
  double t;
  ASSERT_TRUE(torus.intersectRay(Vec3(0.1 + 1.0, 0.2, 2), Vec3(0, 0, -1), 0, &t));
  EXPECT_NEAR(t, 2.0, 1e-10);  // top of the tube at z = -0.3 + 0.3
  EXPECT_FALSE(torus.intersectRay(Vec3(0.1, 0.2, 2), Vec3(0, 0, -1), 0, &t));  // through the hole
  ASSERT_TRUE(sphere.intersectRay(Vec3(0.1, 0.2, 2), Vec3(0, 0, -2), 0, &t));
  EXPECT_NEAR(t, (2.3 - 0.7) / 2, 1e-12);
}

TEST(RayIntersection, HitsMatchAnalyticSphereAndTorus) {
  const AnalyticSphere sphere(Vec3(0, 0, 0), 1.0);
  const AnalyticTorus torus(Vec3(0, 0, 0), 1.0, 0.4);
  std::mt19937_64 rng(7);
  for (const AnalyticSurface* s :
       {static_cast<const AnalyticSurface*>(&sphere), static_cast<const AnalyticSurface*>(&torus)}) {
    const SurfelCloud cloud = s->sample(30000);
    const double h = s->spacing(cloud.size());
    MlsSurface surface(cloud, planeConfig(3 * h));
    size_t analytic_hits = 0, agree = 0, misses_ok = 0, analytic_misses = 0;
    double max_error = 0, max_fixed_point = 0;
    for (int i = 0; i < 300; ++i) {
      const Vec3 origin = 3.0 * randomUnit(rng);
      const Vec3 dir = (1.2 * randomUnit(rng) - origin) * 0.7;  // aim through the object's region
      double t_true;
      const bool truth = s->intersectRay(origin, dir, 0, &t_true);
      const MlsRayHit hit = intersectRayMlsRobust(surface, origin, dir);
      if (!truth) {
        ++analytic_misses;
        misses_ok += !hit.hit;
        continue;
      }
      // Grazing rays can legitimately differ between the MLS and the true surface.
      const Vec3 p_true = origin + t_true * dir;
      if (std::abs(s->normal(p_true).dot(dir.normalized())) < 0.3) continue;
      ++analytic_hits;
      if (!hit.hit) continue;
      const double err = (hit.point - p_true).norm();
      max_error = std::max(max_error, err);
      agree += err < 10 * h * h;
      EXPECT_NEAR((origin + hit.t * dir - hit.point).norm(), 0.0, 1e-12);
      const MlsProjection proj = surface.project(hit.point);
      ASSERT_TRUE(proj.valid);
      max_fixed_point = std::max(max_fixed_point, (proj.point - hit.point).norm());
      EXPECT_GT(hit.normal.dot(s->normal(hit.point)), 0.99);
    }
    std::printf("ray: hits %zu agree %zu max err %.3e (h^2 = %.3e), misses %zu/%zu, fixed point %.2e\n",
                analytic_hits, agree, max_error, h * h, misses_ok, analytic_misses, max_fixed_point);
    EXPECT_GT(analytic_hits, 100u);
    EXPECT_EQ(agree, analytic_hits);
    EXPECT_EQ(misses_ok, analytic_misses);
    EXPECT_LT(max_fixed_point, 1e-8 * surface.supportRadius());  // the hit lies on the plane-MLS surface
  }
}

TEST(RayIntersection, AlgorithmFromNearbyStartAndBadInput) {
  const AnalyticSphere sphere(Vec3(0, 0, 0), 1.0);
  const SurfelCloud cloud = sphere.sample(20000);
  const double support = 3 * sphere.spacing(cloud.size());
  MlsSurface surface(cloud, planeConfig(support));
  std::mt19937_64 rng(3);
  for (int i = 0; i < 100; ++i) {
    const Vec3 p = randomUnit(rng), d = -(p + 0.3 * randomUnit(rng)).normalized();
    const Vec3 start = p - 0.5 * support * d;
    const MlsRayHit hit = intersectRayMls(surface, start, d);
    ASSERT_TRUE(hit.hit);
    EXPECT_LT(std::abs(sphere.signedDistance(hit.point)), 5e-3);
    EXPECT_LT(hit.iterations, 20);
  }
  // Start far from the samples: the plane fit has no neighbours, no hit (the robust wrapper handles this).
  EXPECT_FALSE(intersectRayMls(surface, Vec3(0, 0, 5), Vec3(0, 0, -1)).hit);
  EXPECT_TRUE(intersectRayMlsRobust(surface, Vec3(0, 0, 5), Vec3(0, 0, -1)).hit);
  RayIntersectionConfig behind;
  behind.t_max = 3.5;  // the sphere starts at t = 4
  EXPECT_FALSE(intersectRayMlsRobust(surface, Vec3(0, 0, 5), Vec3(0, 0, -1), behind).hit);
  EXPECT_FALSE(intersectRayMlsRobust(surface, Vec3(0, 0, 5), Vec3(0, 0, 1)).hit);  // pointing away
  EXPECT_FALSE(intersectRayMlsRobust(surface, Vec3(0, 0, 5), Vec3::Zero()).hit);
  EXPECT_FALSE(intersectRayMlsRobust(surface, Vec3(NAN, 0, 5), Vec3(0, 0, -1)).hit);
  const SurfelCloud empty;
  MlsSurface none(empty, planeConfig(0.1));
  EXPECT_FALSE(intersectRayMlsRobust(none, Vec3(0, 0, 5), Vec3(0, 0, -1)).hit);
}

TEST(InsideOutside, MisclassificationOnlyNearTheSurface) {
  const AnalyticTorus torus(Vec3(0, 0, 0), 1.0, 0.4);
  const SurfelCloud cloud = torus.sample(20000, {SamplingPattern::kUniformRandom, 0.002, 4});
  const double h = torus.spacing(cloud.size());
  for (MlsFit fit : {MlsFit::kPlane, MlsFit::kSphere}) {
    MlsConfig config = planeConfig(4 * h);
    config.fit = fit;
    MlsSurface surface(cloud, config);
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> uni(-1.5, 1.5);
    std::vector<Vec3> xs;
    for (int i = 0; i < 20000; ++i) xs.emplace_back(uni(rng), uni(rng), 0.4 * uni(rng));
    std::vector<Containment> out;
    classifyPoints(surface, xs, out);
    // Bands of |signed distance| in units of h: [0, 0.1), [0.1, 0.5), [0.5, 2), [2, inf).
    size_t count[4] = {0, 0, 0, 0}, wrong[4] = {0, 0, 0, 0}, unknown[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < xs.size(); ++i) {
      const double sd = torus.signedDistance(xs[i]), a = std::abs(sd) / h;
      const int band = a < 0.1 ? 0 : a < 0.5 ? 1 : a < 2 ? 2 : 3;
      ++count[band];
      if (out[i] == Containment::kUnknown) {
        ++unknown[band];
        continue;
      }
      wrong[band] += (out[i] == Containment::kOutside) != (sd > 0);
    }
    for (int b = 0; b < 4; ++b)
      std::printf("%s band %d: %zu points, %zu wrong, %zu unknown\n", mlsFitName(fit), b, count[b], wrong[b],
                  unknown[b]);
    EXPECT_LT(static_cast<double>(wrong[0]) / count[0], 0.5);
    EXPECT_EQ(wrong[1], 0u);
    EXPECT_EQ(wrong[2], 0u);
    EXPECT_EQ(wrong[3], 0u);
    EXPECT_EQ(unknown[1] + unknown[2], 0u);  // within the support: always decided
    EXPECT_GT(unknown[3], count[3] / 2);     // far away: no samples in the support, no decision
  }
  SurfelCloud no_normals = cloud;
  no_normals.normals.clear();
  MlsSurface unoriented(no_normals, planeConfig(4 * h));
  EXPECT_THROW(classifyPoint(unoriented, Vec3::Zero()), std::invalid_argument);
  MlsSurface surface(cloud, planeConfig(4 * h));
  EXPECT_EQ(classifyPoint(surface, Vec3(NAN, 0, 0)), Containment::kUnknown);
}

TEST(NormalEstimation, PcaWithConsistentOrientation) {
  const AnalyticTorus torus(Vec3(0.2, 0, 0.1), 1.0, 0.4);
  for (bool viewpoint : {false, true}) {
    SurfelCloud cloud = torus.sample(20000, {SamplingPattern::kUniformRandom, 0.0, 6});
    cloud.normals.clear();
    NormalEstimationConfig config;
    config.k = 12;
    if (viewpoint) config.viewpoint = Vec3(0.2, 0, 5);  // above: normals face up
    estimateNormals(cloud, config);
    ASSERT_EQ(cloud.normals.size(), cloud.size());
    ASSERT_EQ(cloud.curvature.size(), cloud.size());
    size_t outward = 0, toward_view = 0;
    double max_angle = 0;
    for (size_t i = 0; i < cloud.size(); ++i) {
      const Vec3 nt = torus.normal(cloud.positions[i]);
      const double c = cloud.normals[i].dot(nt);
      outward += c > 0;
      toward_view += viewpoint && cloud.normals[i].dot(*config.viewpoint - cloud.positions[i]) >= 0;
      max_angle = std::max(max_angle, std::acos(std::min(1.0, std::abs(c))));
      EXPECT_GE(cloud.curvature[i], 0.0f);
      EXPECT_LE(cloud.curvature[i], 1.0f / 3.0f + 1e-6f);
    }
    EXPECT_LT(max_angle, 0.2);
    if (viewpoint)
      EXPECT_EQ(toward_view, cloud.size());
    else
      EXPECT_EQ(outward, cloud.size());  // consistent on the closed torus, outward from the +z start
  }
  SurfelCloud sphere_cloud =
      AnalyticSphere(Vec3::Zero(), 1.0).sample(5000, {SamplingPattern::kUniformRandom, 0, 2});
  const std::vector<Vec3> truth = sphere_cloud.normals;
  std::mt19937_64 rng(1);
  size_t flipped_in = 0;
  for (Vec3& n : sphere_cloud.normals)
    if (rng() % 2) n = -n, ++flipped_in;
  const size_t flipped = orientNormalsConsistently(sphere_cloud, 10);
  EXPECT_EQ(flipped, flipped_in);
  for (size_t i = 0; i < truth.size(); ++i) EXPECT_GT(sphere_cloud.normals[i].dot(truth[i]), 0.999);

  SurfelCloud tiny;
  tiny.positions = {Vec3::Zero(), Vec3::UnitX()};
  EXPECT_THROW(estimateNormals(tiny, {}), std::invalid_argument);
  NormalEstimationConfig bad_k;
  bad_k.k = 2;
  EXPECT_THROW(estimateNormals(sphere_cloud, bad_k), std::invalid_argument);
}

TEST(NormalEstimation, PlaneNormalsFromListsAndTree) {
  const AnalyticTorus torus(Vec3::Zero(), 1.0, 0.4);
  SurfelCloud cloud = torus.sample(10000, {SamplingPattern::kUniformRandom, 0.0, 12});
  const double h = torus.spacing(cloud.size()), support = 3 * h;
  cloud.positions.push_back(Vec3(5, 5, 5));  // isolated: no normal
  for (const WeightFunction& weight :
       {WeightFunction::wendland(support), WeightFunction::clippedGaussian(support, 1.0)}) {
    NeighborLists lists;
    lists.build(cloud.positions, 1.2 * support);
    std::vector<Vec3> from_lists, from_tree;
    estimatePlaneNormals(cloud.positions, lists, weight, support, 4, from_lists);
    KdTree tree(cloud.positions);
    estimatePlaneNormals(cloud.positions, tree, weight, support, 4, from_tree);
    ASSERT_EQ(from_lists.size(), cloud.size());
    ASSERT_EQ(from_tree.size(), cloud.size());
    EXPECT_TRUE(from_lists.back().isZero());
    EXPECT_TRUE(from_tree.back().isZero());
    double max_angle = 0, max_diff = 0;
    for (size_t i = 0; i + 1 < cloud.size(); ++i) {
      max_diff = std::max(max_diff, std::min((from_lists[i] - from_tree[i]).norm(),
                                             (from_lists[i] + from_tree[i]).norm()));  // unoriented
      max_angle =
          std::max(max_angle, std::acos(std::min(1.0, std::abs(from_lists[i].dot(cloud.normals[i])))));
    }
    EXPECT_LT(max_diff, 1e-12);
    // Clean random samples: the covariance normal tilts by O(h / feature size) and more where a neighbourhood
    // is lopsided; measured 0.106 (W), 0.115 (G).
    EXPECT_LT(max_angle, 0.125) << weightKindName(weight.kind);
    EXPECT_THROW(estimatePlaneNormals(cloud.positions, lists, weight, 1.3 * support, 4, from_lists),
                 std::invalid_argument);
  }
  cloud.positions[3] = Vec3(NAN, 0, 0);
  KdTree tree(cloud.positions);
  std::vector<Vec3> normals;
  estimatePlaneNormals(cloud.positions, tree, WeightFunction::wendland(support), support, 4, normals);
  EXPECT_TRUE(normals[3].isZero());  // a non-finite sample gets no normal (and no crash)
}

TEST(NormalEstimation, SphereRefinementSmoothsNoisyPlaneNormals) {
  // Noisy random samples of a torus (0.3 h): the plane normals (3.5) carry the noise of their few neighbours;
  // a pass of sphere fits averages them as the fit weighs them (the gradient fitted to the normals) and keeps
  // the curvature the positions give. On clean samples it changes them little (measured: mean 0.0181 ->
  // 0.0178 rad, Wendland). Lists and tree give the same normals; isolated samples keep a zero normal; signs
  // are kept.
  const AnalyticTorus torus(Vec3::Zero(), 1.0, 0.4);
  const double h = torus.spacing(10000), support = 3 * h;
  SurfelCloud cloud = torus.sample(10000, {SamplingPattern::kUniformRandom, 0.3 * h, 12});
  cloud.positions.push_back(Vec3(5, 5, 5));
  auto angles = [&](const std::vector<Vec3>& normals, double* max_angle) {
    double sum = 0;
    *max_angle = 0;
    for (size_t i = 0; i + 1 < cloud.size(); ++i) {
      const double a = std::acos(std::min(1.0, std::abs(normals[i].dot(cloud.normals[i]))));
      sum += a, *max_angle = std::max(*max_angle, a);
    }
    return sum / static_cast<double>(cloud.size() - 1);
  };
  for (const WeightFunction& weight :
       {WeightFunction::wendland(support), WeightFunction::clippedGaussian(support, 1.0)}) {
    NeighborLists lists;
    lists.build(cloud.positions, support);
    KdTree tree(cloud.positions);
    std::vector<Vec3> plane, from_lists, from_tree;
    estimatePlaneNormals(cloud.positions, lists, weight, support, 4, plane);
    from_lists = from_tree = plane;
    refineNormalsBySpheres(cloud.positions, lists, weight, support, 4, from_lists);
    refineNormalsBySpheres(cloud.positions, tree, weight, support, 4, from_tree);
    double max_plane = 0, max_refined = 0, max_diff = 0;
    const double mean_plane = angles(plane, &max_plane), mean_refined = angles(from_lists, &max_refined);
    size_t sign_changes = 0;
    for (size_t i = 0; i + 1 < cloud.size(); ++i) {
      max_diff = std::max(max_diff, (from_lists[i] - from_tree[i]).norm());
      sign_changes += from_lists[i].dot(plane[i]) < 0;
    }
    std::printf("%s: mean / max angle to the exact normals, plane %.4f / %.4f, refined %.4f / %.4f\n",
                weightKindName(weight.kind), mean_plane, max_plane, mean_refined, max_refined);
    EXPECT_LT(max_diff, 1e-12);
    EXPECT_EQ(sign_changes, 0u);
    EXPECT_TRUE(from_lists.back().isZero());
    // Measured: mean 0.154 -> 0.108 rad (W), 0.064 -> 0.044 (G); max 1.54 -> 1.36, 0.38 -> 0.18.
    EXPECT_LT(mean_refined, 0.75 * mean_plane);
    EXPECT_LT(max_refined, max_plane);
    std::vector<Vec3> short_list(3);
    EXPECT_THROW(refineNormalsBySpheres(cloud.positions, tree, weight, support, 4, short_list),
                 std::invalid_argument);
    EXPECT_THROW(refineNormalsBySpheres(cloud.positions, lists, weight, 1.1 * support, 4, from_lists),
                 std::invalid_argument);
  }
}

TEST(RadiusEstimation, SampleSpacingOfUniformSamples) {
  // On a uniform random sample, sqrt(area / n) to within the 6th neighbour's sampling error.
  const AnalyticSphere sphere(Vec3::Zero(), 2.0);
  const SurfelCloud cloud = sphere.sample(20000, {SamplingPattern::kUniformRandom, 0.0, 5});
  const double h = sphere.spacing(cloud.size()), measured = sampleSpacing(cloud.positions);
  std::printf("sample spacing %.5f, sqrt(area / n) %.5f\n", measured, h);
  EXPECT_NEAR(measured, h, 0.05 * h);
  EXPECT_THROW(sampleSpacing(std::vector<Vec3>(6, Vec3::Zero())), std::invalid_argument);
}

TEST(MlsLocalSamples, GaussianWeightsAndLocalOrientation) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uni(-1, 1);
  std::vector<Vec3> pos, nrm;
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < 200; ++i) {
    pos.emplace_back(uni(rng), uni(rng), 0.1 * uni(rng));
    nrm.push_back(Vec3(0.1 * uni(rng), 0.1 * uni(rng), 1).normalized() * (rng() % 2 ? 1.0 : -1.0));
    ids.push_back(i);
  }
  const Vec3 p(0.1, -0.2, 0);
  size_t nearest = 0;
  for (size_t i = 0; i < pos.size(); ++i)
    if ((pos[i] - p).norm() < (pos[nearest] - p).norm()) nearest = i;
  nrm[nearest].setZero();  // a failed estimate is no reference: the next nearest orients the rest
  size_t second = nearest == 0 ? 1 : 0;
  for (size_t i = 0; i < pos.size(); ++i)
    if (i != nearest && (pos[i] - p).norm() < (pos[second] - p).norm()) second = i;
  const double support = 0.7;
  for (const WeightFunction& weight : {WeightFunction::clippedGaussian(0.35, 2.0),
                                       WeightFunction::gaussian(0.175), WeightFunction::wendland(support)}) {
    const double r = std::isfinite(weight.support()) ? weight.support() : 4 * weight.scale;
    MlsLocalSamples s;
    const size_t count = s.gather(pos.data(), nrm.data(), ids.data(), ids.size(), MlsLocalSamples::kNoExtra,
                                  p, r, weight, true);
    size_t inside = 0;
    for (const Vec3& q : pos) inside += (q - p).norm() < r;
    ASSERT_EQ(count, inside) << weightKindName(weight.kind);
    const double sign = nrm[second].z() > 0 ? 1.0 : -1.0;
    for (size_t k = 0; k < count; ++k) {
      const double d2 = s.sq_norm[k] * r * r;
      EXPECT_NEAR(s.w[k], weight.fromSquared(d2), 1e-15) << weightKindName(weight.kind);
      const Vec3 n(s.nx[k], s.ny[k], s.nz[k]);
      if (!n.isZero()) {
        EXPECT_GT(sign * n.z(), 0.9);
      }
    }
    for (size_t k = count; k < s.padded; ++k) EXPECT_EQ(s.w[k], 0.0);
  }
}

TEST(RadiusEstimation, DiscsCoverTheSurface) {
  const AnalyticSphere sphere(Vec3::Zero(), 1.0);
  const AnalyticTorus torus(Vec3::Zero(), 1.0, 0.4);
  for (const AnalyticSurface* s :
       {static_cast<const AnalyticSurface*>(&sphere), static_cast<const AnalyticSurface*>(&torus)}) {
    SurfelCloud cloud = s->sample(5000, {SamplingPattern::kUniformRandom, 0.0, 12});
    estimateRadii(cloud, {});
    ASSERT_EQ(cloud.radii.size(), cloud.size());
    double max_r = 0, mean_r = 0;
    for (double r : cloud.radii) max_r = std::max(max_r, r), mean_r += r / cloud.size();
    KdTree tree(cloud.positions);
    const SurfelCloud probes = s->sample(50000, {SamplingPattern::kUniformRandom, 0.0, 77});
    size_t uncovered = 0;
    std::vector<Neighbor> nbrs;
    for (const Vec3& y : probes.positions) {
      tree.radius(y, max_r * 1.01, nbrs);
      bool covered = false;
      for (const Neighbor& nb : nbrs) {
        const Vec3 d = y - cloud.positions[nb.index];
        const Vec3& n = cloud.normals[nb.index];
        if ((d - n * n.dot(d)).norm() <= cloud.radii[nb.index]) {
          covered = true;
          break;
        }
      }
      uncovered += !covered;
    }
    const double h = s->spacing(cloud.size());
    std::printf("radii: mean %.3f h, max %.3f h, uncovered %zu of %zu\n", mean_r / h, max_r / h, uncovered,
                probes.size());
    EXPECT_EQ(uncovered, 0u);
    EXPECT_LT(mean_r, 1.5 * h);  // not trivially huge
  }
  SurfelCloud no_normals;
  no_normals.positions = {Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()};
  EXPECT_THROW(estimateRadii(no_normals, {}), std::invalid_argument);
}

}  // namespace
}  // namespace rc
