#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "relaxed_connectivity/mesh/mesh_ray_caster.h"
#include "relaxed_connectivity/scan/procedural_models.h"

namespace rc {
namespace {

Vec3 randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

// Reference: closest hit over all triangles.
RayHit bruteForce(const TriangleMesh& mesh, const Ray& ray) {
  RayHit best;
  const auto& p = mesh.vertices.positions;
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Triangle& tri = mesh.triangles[i];
    double t, u, v;
    if (MeshRayCaster::intersectTriangle(ray.origin, ray.direction, p[tri[0]], p[tri[1]], p[tri[2]],
                                         ray.t_min, best.hit() ? best.t : ray.t_max, &t, &u, &v) &&
        (!best.hit() || t < best.t)) {
      best.t = t;
      best.triangle = static_cast<uint32_t>(i);
      best.u = u;
      best.v = v;
    }
  }
  return best;
}

TEST(MeshRayCaster, FineSphereHitsMatchAnalyticIntersectionWithinSagitta) {
  const double radius = 1.0;
  const int frequency = 48;  // 46080 triangles
  const TriangleMesh mesh = makeIcosphere(radius, frequency);
  const MeshRayCaster caster(mesh);
  EXPECT_EQ(caster.triangleCount(), mesh.triangles.size());
  // Largest distance between a facet and the sphere: R (1 - cos alpha), alpha = the largest angular
  // circumradius of a facet.
  double alpha = 0.0;
  const auto& p = mesh.vertices.positions;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 n = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).normalized();  // circumcentre direction
    for (uint32_t i : t) alpha = std::max(alpha, std::acos(std::min(1.0, n.dot(p[i]) / radius)));
  }
  const double sagitta = radius * (1.0 - std::cos(alpha));
  ASSERT_LT(sagitta, 1e-3);

  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int hits = 0, misses = 0;
  for (int i = 0; i < 20000; ++i) {
    Ray ray;
    ray.origin = (2.0 + 3.0 * uniform(rng)) * randomUnit(rng);
    // Aim at a random point of the disc of radius 1.3 R through the centre, perpendicular to the view.
    const Vec3 forward = -ray.origin.normalized();
    const Vec3 side = forward.unitOrthogonal(), up = forward.cross(side);
    const double b = 1.3 * radius * std::sqrt(uniform(rng)), phi = 2.0 * M_PI * uniform(rng);
    const Vec3 aim = b * (std::cos(phi) * side + std::sin(phi) * up);
    ray.direction = (aim - ray.origin) * (0.5 + uniform(rng));  // not unit length
    // Analytic sphere intersection (smallest root of |o + t d|^2 = R^2).
    const Vec3& o = ray.origin;
    const Vec3& d = ray.direction;
    const double qa = d.squaredNorm(), qb = o.dot(d), qc = o.squaredNorm() - radius * radius;
    const double disc = qb * qb - qa * qc;
    const double impact =
        std::sqrt(std::max(0.0, qc + radius * radius - qb * qb / qa));  // ray-centre distance
    RayHit hit;
    const bool did_hit = caster.intersect(ray, &hit);
    if (impact > radius) {
      EXPECT_FALSE(did_hit) << "ray " << i << " passes the sphere at distance " << impact;
      ++misses;
      continue;
    }
    if (impact > radius - sagitta) continue;  // may graze between the facets and the sphere
    ASSERT_TRUE(did_hit) << "ray " << i << " at impact parameter " << impact;
    ++hits;
    const double t_exact = (-qb - std::sqrt(disc)) / qa;
    const Vec3 point = o + hit.t * d;
    // The hit lies on a facet: between the sphere and the inscribed sagitta shell, and no earlier than the
    // analytic hit.
    EXPECT_LE(point.norm(), radius + 1e-12);
    EXPECT_GE(point.norm(), radius - sagitta - 1e-12);
    EXPECT_GE(hit.t, t_exact - 1e-12);
    // Along the ray the error is the radial error divided by the cosine of the incidence angle.
    const double cos_incidence = std::sqrt(1.0 - (impact / radius) * (impact / radius));
    if (cos_incidence > 0.3) {
      EXPECT_LE((hit.t - t_exact) * d.norm(), sagitta / cos_incidence + 1e-12);
    }
    // Geometric normal: outward, close to the radial direction, and the barycentrics reproduce the point.
    EXPECT_NEAR(hit.normal.norm(), 1.0, 1e-12);
    EXPECT_GT(hit.normal.dot(point.normalized()), std::cos(alpha) - 1e-9);
    const Triangle& tri = mesh.triangles[hit.triangle];
    const Vec3 from_barycentrics = (1.0 - hit.u - hit.v) * p[tri[0]] + hit.u * p[tri[1]] + hit.v * p[tri[2]];
    EXPECT_LT((from_barycentrics - point).norm(), 1e-9);
  }
  EXPECT_GT(hits, 10000);
  EXPECT_GT(misses, 2000);
}

TEST(MeshRayCaster, MatchesBruteForceOnRandomTriangleSoup) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  TriangleMesh soup;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 centre(uniform(rng), uniform(rng), uniform(rng));
    for (int k = 0; k < 3; ++k)
      soup.vertices.positions.push_back(centre + 0.1 * Vec3(uniform(rng), uniform(rng), uniform(rng)));
    soup.triangles.push_back({uint32_t(3 * i), uint32_t(3 * i + 1), uint32_t(3 * i + 2)});
  }
  for (int leaf : {1, 4, 8}) {
    MeshRayCaster::Options options;
    options.max_leaf_size = leaf;
    const MeshRayCaster caster(soup, options);
    EXPECT_GT(caster.depth(), 5);
    std::vector<Ray> rays(2000);
    for (Ray& ray : rays) {
      ray.origin = 1.5 * Vec3(uniform(rng), uniform(rng), uniform(rng));
      ray.direction = Vec3(uniform(rng), uniform(rng), uniform(rng));
      if (uniform(rng) > 0.5) ray.t_min = 0.3 * (uniform(rng) + 1.0);
      if (uniform(rng) > 0.5) ray.t_max = 0.5 + uniform(rng);
    }
    std::vector<RayHit> hits;
    caster.intersectBatch(rays, hits);
    ASSERT_EQ(hits.size(), rays.size());
    int hit_count = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      const RayHit expected = bruteForce(soup, rays[i]);
      RayHit single;
      const bool did_hit = caster.intersect(rays[i], &single);
      ASSERT_EQ(did_hit, expected.hit()) << "ray " << i;
      EXPECT_EQ(caster.occluded(rays[i]), expected.hit()) << "ray " << i;
      EXPECT_EQ(hits[i].hit(), expected.hit()) << "ray " << i;
      if (!expected.hit()) continue;
      ++hit_count;
      EXPECT_EQ(single.t, hits[i].t);
      EXPECT_NEAR(single.t, expected.t, 1e-12) << "ray " << i;
      if (single.triangle != expected.triangle) {  // only a tie at the same t may pick another triangle
        EXPECT_NEAR(single.t, expected.t, 1e-12);
      } else {
        EXPECT_NEAR(single.u, expected.u, 1e-9);
        EXPECT_NEAR(single.v, expected.v, 1e-9);
      }
      EXPECT_GE(single.t, rays[i].t_min);
      EXPECT_LE(single.t, rays[i].t_max);
    }
    EXPECT_GT(hit_count, 400) << "leaf " << leaf;
  }
}

TEST(MeshRayCaster, RaysThroughBoxVerticesAndEdgesDoNotMiss) {
  const Vec3 size(1.0, 0.8, 0.6);
  const TriangleMesh box = makeBox(size, 3);
  const MeshRayCaster caster(box);
  const auto& p = box.vertices.positions;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // Targets: every vertex and points on every triangle edge (including the quad diagonals).
  std::vector<Vec3> targets(p.begin(), p.end());
  for (const Triangle& t : box.triangles)
    for (int k = 0; k < 3; ++k) {
      targets.push_back(0.5 * (p[t[k]] + p[t[(k + 1) % 3]]));
      const double s = uniform(rng);
      targets.push_back((1.0 - s) * p[t[k]] + s * p[t[(k + 1) % 3]]);
    }
  int misses_inside = 0, misses_outside = 0;
  for (const Vec3& target : targets) {
    // From the centre: the ray leaves through the target.
    Ray from_inside;
    from_inside.origin = Vec3::Zero();
    from_inside.direction = target;
    RayHit hit;
    if (!caster.intersect(from_inside, &hit))
      ++misses_inside;
    else
      EXPECT_NEAR(hit.t, 1.0, 1e-9);
    // From outside, on the side the target faces (the first surface met is at the target).
    Vec3 outward = Vec3::Zero();
    for (int k = 0; k < 3; ++k)
      if (std::abs(std::abs(target[k]) - 0.5 * size[k]) < 1e-12) outward[k] = std::copysign(1.0, target[k]);
    for (int trial = 0; trial < 4; ++trial) {
      Vec3 direction = outward.normalized() + 0.4 * randomUnit(rng);
      if (direction.dot(outward) <= 0.1 * outward.norm()) direction = outward;
      Ray from_outside;
      from_outside.origin = target + 3.0 * direction.normalized();
      from_outside.direction = target - from_outside.origin;
      RayHit outer;
      if (!caster.intersect(from_outside, &outer))
        ++misses_outside;
      else
        EXPECT_NEAR(outer.t, 1.0, 1e-9);
    }
  }
  EXPECT_EQ(misses_inside, 0);
  EXPECT_EQ(misses_outside, 0);
  // Axis-aligned rays along lattice lines (exactly through rows of vertices and edges).
  int axis_misses = 0;
  for (int i = 0; i <= 3; ++i)
    for (int j = 0; j <= 3; ++j) {
      Ray ray;
      ray.origin = Vec3(-2.0, -0.4 + 0.8 * i / 3.0, -0.3 + 0.6 * j / 3.0);
      ray.direction = Vec3::UnitX();
      RayHit hit;
      if (!caster.intersect(ray, &hit))
        ++axis_misses;
      else
        EXPECT_NEAR(hit.t, 1.5, 1e-12);
    }
  EXPECT_EQ(axis_misses, 0);
}

TEST(MeshRayCaster, RaysThroughSharedEdgesOfClosedMeshesNeverLeak) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (const char* name : {"icosphere", "blob", "uv_sphere"}) {
    const TriangleMesh mesh = makeModel(name, 24);
    const MeshRayCaster caster(mesh);
    const auto& p = mesh.vertices.positions;
    int leaks = 0;
    for (int i = 0; i < 20000; ++i) {
      const Triangle& t = mesh.triangles[rng() % mesh.triangles.size()];
      const int k = static_cast<int>(rng() % 3);
      const double s = i % 4 == 0 ? 0.0 : uniform(rng);  // every 4th ray exactly through a vertex
      const Vec3 edge_point = (1.0 - s) * p[t[k]] + s * p[t[(k + 1) % 3]];
      Ray ray;  // star-shaped meshes: every ray from the centre leaves through the surface once
      ray.origin = Vec3::Zero();
      ray.direction = edge_point;
      RayHit hit;
      if (!caster.intersect(ray, &hit))
        ++leaks;
      else
        EXPECT_NEAR(hit.t, 1.0, 1e-9);
    }
    EXPECT_EQ(leaks, 0) << name;
  }
}

TEST(MeshRayCaster, GeometricallySpacedTrianglesKeepTheTreeShallow) {
  // Centroids at x = 0.8^i: binned SAH splits off only a few triangles per level; the median fallback bounds
  // the depth.
  TriangleMesh mesh;
  const int n = 1000;  // x down to 1e-97: tiny but far from underflow in the triangle test
  for (int i = 0; i < n; ++i) {
    const double x = std::pow(0.8, i), s = 0.1 * x;
    const uint32_t base = static_cast<uint32_t>(mesh.vertices.positions.size());
    mesh.vertices.positions.push_back(Vec3(x, -s, -s));
    mesh.vertices.positions.push_back(Vec3(x, s, -s));
    mesh.vertices.positions.push_back(Vec3(x, 0.0, s));
    mesh.triangles.push_back({base, base + 1, base + 2});
  }
  const MeshRayCaster caster(mesh);
  EXPECT_LE(caster.depth(), 128);
  EXPECT_GT(caster.depth(), 64);  // the median fallback was needed
  for (int i = 0; i < n; i += 37) {
    const double x = std::pow(0.8, i);
    Ray towards;  // along -x from beyond triangle 0: the first triangle met is 0
    towards.origin = Vec3(2.0, 0.0, 0.0);
    towards.direction = Vec3(-1.0, 0.0, 0.0);
    RayHit hit;
    ASSERT_TRUE(caster.intersect(towards, &hit));
    EXPECT_EQ(hit.triangle, 0u);
    Ray through;  // straight at triangle i from the +x side, starting between triangles i - 1 and i
    through.origin = Vec3(x * 1.1, 0.0, 0.0);
    through.direction = Vec3(-1.0, 0.0, 0.0);
    ASSERT_TRUE(caster.intersect(through, &hit)) << i;
    EXPECT_EQ(hit.triangle, static_cast<uint32_t>(i));
    EXPECT_NEAR(hit.t, 0.1 * x, 1e-12 * x);
  }
}

TEST(MeshRayCaster, EmptyAndInvalidMeshes) {
  const TriangleMesh empty;
  const MeshRayCaster caster(empty);
  Ray ray;
  RayHit hit;
  EXPECT_FALSE(caster.intersect(ray, &hit));
  EXPECT_FALSE(hit.hit());
  EXPECT_FALSE(caster.occluded(ray));

  TriangleMesh bad = makeBox(Vec3(1, 1, 1), 1);
  bad.triangles[3][1] = 1000;
  try {
    MeshRayCaster broken(bad);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 3"), std::string::npos) << e.what();
  }
  TriangleMesh nan_vertex = makeBox(Vec3(1, 1, 1), 1);
  nan_vertex.vertices.positions[2].x() = std::nan("");
  EXPECT_THROW(MeshRayCaster{nan_vertex}, std::invalid_argument);
  MeshRayCaster::Options options;
  options.max_leaf_size = 0;
  EXPECT_THROW(MeshRayCaster(empty, options), std::invalid_argument);
}

TEST(MeshRayCaster, RespectsRayIntervalAndRebuildsAfterMeshChange) {
  TriangleMesh box = makeBox(Vec3(2, 2, 2), 2);  // faces at +-1
  MeshRayCaster caster(box);
  Ray ray;
  ray.origin = Vec3(-5.0, 0.1, 0.2);
  ray.direction = Vec3::UnitX();
  RayHit hit;
  ASSERT_TRUE(caster.intersect(ray, &hit));
  EXPECT_NEAR(hit.t, 4.0, 1e-12);
  EXPECT_TRUE(hit.normal.isApprox(-Vec3::UnitX(), 1e-12));
  ray.t_min = 4.5;  // skip the near face: the far face at t = 6
  ASSERT_TRUE(caster.intersect(ray, &hit));
  EXPECT_NEAR(hit.t, 6.0, 1e-12);
  EXPECT_TRUE(hit.normal.isApprox(Vec3::UnitX(), 1e-12));
  ray.t_max = 5.5;
  EXPECT_FALSE(caster.intersect(ray, &hit));
  EXPECT_FALSE(caster.occluded(ray));

  for (Vec3& v : box.vertices.positions) v.x() += 10.0;
  caster.rebuild();
  ray = Ray();
  ray.origin = Vec3(-5.0, 0.1, 0.2);
  ray.direction = Vec3::UnitX();
  ASSERT_TRUE(caster.intersect(ray, &hit));
  EXPECT_NEAR(hit.t, 14.0, 1e-12);
}

}  // namespace
}  // namespace rc
