// CSG scene files (config/scenes), the loader and the patch samplers.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "relaxed_connectivity/render/csg/patch_sampling.h"
#include "relaxed_connectivity/render/scene/csg_scene.h"
#include "scene_test_support.h"

namespace rc {
namespace {

const std::string kSceneDir = sceneDir();

int32_t attr(const SurfelCloud& c, const char* name, size_t i) {
  return int32_t(c.attributes.find(name)->get(i));
}

/// Fraction of `points` (on the surface) that lie on no surfel disc (ellipse if axes are present).
double uncoveredFraction(const SurfelCloud& cloud, const std::vector<Vec3>& points) {
  size_t uncovered = 0;
  for (const Vec3& p : points) {
    bool covered = false;
    for (size_t i = 0; i < cloud.size() && !covered; ++i) {
      const Vec3 d = p - cloud.positions[i];
      if (d.norm() > cloud.radii[i] * 1.01 + 1e-12) continue;
      if (!cloud.hasAxes()) {
        covered = (d - d.dot(cloud.normals[i]) * cloud.normals[i]).norm() <= cloud.radii[i];
      } else {
        const double a = d.dot(cloud.axes1[i]) / cloud.axes1[i].squaredNorm();
        const double b = d.dot(cloud.axes2[i]) / cloud.axes2[i].squaredNorm();
        covered = a * a + b * b <= 1.0;
      }
    }
    uncovered += !covered;
  }
  return double(uncovered) / points.size();
}

std::vector<Vec3> randomUnitVectors(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::vector<Vec3> out(n);
  for (Vec3& v : out) v = Vec3(g(rng), g(rng), g(rng)).normalized();
  return out;
}

TEST(PatchSampling, SphereOnSurfaceAndCovering) {
  PatchSampling s;
  s.samples = 800;
  const SurfelCloud c = sampleSphere(Vec3(1, 2, 3), 0.5, s);
  ASSERT_EQ(c.size(), 800u);
  for (size_t i = 0; i < c.size(); ++i) {
    EXPECT_NEAR((c.positions[i] - Vec3(1, 2, 3)).norm(), 0.5, 1e-12);
    EXPECT_NEAR((c.normals[i] - (c.positions[i] - Vec3(1, 2, 3)) / 0.5).norm(), 0, 1e-12);
  }
  std::vector<Vec3> probes = randomUnitVectors(400, 3);
  for (Vec3& p : probes) p = Vec3(1, 2, 3) + 0.5 * p;
  EXPECT_EQ(uncoveredFraction(c, probes), 0.0);
  s.radius_scale = 0.5;  // half the covering radius leaves holes: the check can fail
  EXPECT_GT(uncoveredFraction(sampleSphere(Vec3(1, 2, 3), 0.5, s), probes), 0.2);
}

TEST(PatchSampling, EllipsoidEllipticalSurfels) {
  PatchSampling s;
  s.spacing = 0.05;
  const Vec3 axes(1.0, 0.3, 0.4);
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.4, Vec3(1, 1, 0).normalized()).matrix();
  const SurfelCloud c = sampleEllipsoid(Vec3(0, 0, 1), axes, rot, s);
  const AnalyticSolid e = AnalyticSolid::ellipsoid(Vec3(0, 0, 1), axes, rot);
  ASSERT_TRUE(c.hasAxes());
  // Knud Thomsen's area of this ellipsoid is 3.624: 3.624 / 0.05^2 = 1450 surfels.
  EXPECT_NEAR(double(c.size()), 1450, 5);
  for (size_t i = 0; i < c.size(); ++i) {
    EXPECT_NEAR(e.implicit(c.positions[i]), 0, 1e-12);
    EXPECT_NEAR(c.normals[i].dot(c.axes1[i]), 0, 1e-12);
    EXPECT_NEAR(c.normals[i].dot(c.axes2[i]), 0, 1e-12);
    EXPECT_NEAR(c.axes1[i].dot(c.axes2[i]), 0, 1e-12);
    EXPECT_GT((c.positions[i] + 1e-3 * c.normals[i] - Vec3(0, 0, 1)).norm(),
              (c.positions[i] - Vec3(0, 0, 1)).norm());  // outward
  }
  std::vector<Vec3> probes = randomUnitVectors(300, 5);
  for (Vec3& p : probes) p = Vec3(0, 0, 1) + rot * p.cwiseProduct(axes);
  EXPECT_EQ(uncoveredFraction(c, probes), 0.0);
}

TEST(PatchSampling, SquareAndBoxFaces) {
  PatchSampling s;
  s.samples = 25;
  const SurfelCloud sq = samplePlaneSquare(Vec3(0, 0, 1), Vec3(0, 0, 2), Vec3(1, 0, 0), 2.0, s);
  ASSERT_EQ(sq.size(), 25u);
  Vec3 lo, hi;
  ASSERT_TRUE(sq.bounds(&lo, &hi));
  EXPECT_NEAR(lo.x(), -0.8, 1e-12);  // cell 0.4, centres at +-0.8
  EXPECT_NEAR(hi.y(), 0.8, 1e-12);
  EXPECT_NEAR(sq.radii[0], 1.5 * 0.4 / std::sqrt(2.0), 1e-12);
  s.samples = 1;
  EXPECT_NEAR(samplePlaneSquare(Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX(), 1.0, s).radii[0],
              1.5 * std::sqrt(0.5), 1e-12);  // one surfel covers its face
  s.samples = 16;
  const SurfelCloud box = sampleBoxFaces(Vec3::Zero(), Vec3(1, 1, 0.5), Eigen::Matrix3d::Identity(), s);
  // 2x2 faces: cell 0.5 -> 4x4; 2x1 faces: cell sqrt(1/8) -> 6x3.
  ASSERT_EQ(box.size(), 2u * (16 + 18 + 18));
  for (size_t i = 0; i < box.size(); ++i)
    EXPECT_NEAR(box.normals[i].dot(box.positions[i]),
                box.positions[i].cwiseAbs().cwiseProduct(box.normals[i].cwiseAbs()).sum(), 1e-12);
}

TEST(CsgSceneFiles, CubeDensities) {
  const CsgScene scene = loadCsgScene(kSceneDir + "cube_densities.yaml");
  ASSERT_EQ(scene.patches.size(), 6u);
  const size_t expected[6] = {1, 1, 25, 25, 900, 900};
  for (size_t p = 0; p < 6; ++p)
    EXPECT_EQ(scene.patches[p].surfel_count, expected[p]) << scene.patches[p].name;
  EXPECT_EQ(scene.surfels.size(), 1852u);
  for (size_t i = 0; i < scene.surfels.size(); ++i) {
    const int p = attr(scene.surfels, "patch_id", i);
    const AnalyticSolid& plane = scene.patches[p].solid;
    EXPECT_NEAR(plane.implicit(scene.surfels.positions[i]), 0, 1e-12);
    EXPECT_NEAR((scene.surfels.normals[i] - plane.normal).norm(), 0, 1e-12);
    EXPECT_EQ(attr(scene.surfels, kSurfelRoleAttribute, i), surfelRoleValue(SurfelRole::kSurface));
  }
  EXPECT_EQ(scene.csgTree().patches().size(), 6u);
  EXPECT_EQ(scene.cameras.size(), 2u);
  EXPECT_FALSE(scene.isDynamic());
  const AnalyticCsgCaster cube = scene.analyticCaster();
  EXPECT_TRUE(cube.contains(Vec3(0.49, -0.49, 0.49)));
  EXPECT_FALSE(cube.contains(Vec3(0.51, 0, 0)));
}

TEST(CsgSceneFiles, IcosahedronOneSurfelPerFace) {
  const CsgScene scene = loadCsgScene(kSceneDir + "icosahedron.yaml");
  ASSERT_EQ(scene.surfels.size(), 20u);
  const AnalyticCsgCaster ico = scene.analyticCaster();
  for (size_t i = 0; i < 20; ++i) {
    EXPECT_NEAR(scene.surfels.positions[i].norm(), 0.794654472, 1e-8);  // inradius
    EXPECT_GT(scene.surfels.radii[i], 0.6070619982);                    // covers its triangle
    EXPECT_FALSE(ico.contains(scene.surfels.positions[i] * 1.001));
    EXPECT_TRUE(ico.contains(scene.surfels.positions[i] * 0.999));
  }
  // The 12 vertices (distance 1) are on the boundary: just inside at 0.999.
  const double phi = (1 + std::sqrt(5.0)) / 2;
  const Vec3 vertex = Vec3(0, 1, phi).normalized();
  EXPECT_TRUE(ico.contains(0.999 * vertex));
  EXPECT_FALSE(ico.contains(1.001 * vertex));
}

TEST(CsgSceneFiles, TextureSquareSplitsTheSphere) {
  const CsgScene scene = loadCsgScene(kSceneDir + "texture_square.yaml");
  ASSERT_EQ(scene.patches.size(), 10u);
  EXPECT_EQ(scene.patches[1].name, "ball_square");
  EXPECT_EQ(scene.patches[2].role, SurfelRole::kTextureDiscontinuity);
  EXPECT_EQ(scene.patches[2].name, "square_a0");
  EXPECT_EQ(scene.patches[9].name, "square_b3");
  EXPECT_EQ(scene.csg_expression,
            "((ball_square | !(square_a0 & square_a1 & square_a2 & square_a3)) & "
            "(ball | (square_b0 & square_b1 & square_b2 & square_b3)))");
  ASSERT_EQ(scene.texture_squares.size(), 1u);
  const TextureSquare& sq = scene.texture_squares[0];
  size_t inside = 0, border = 0;
  for (size_t i = 0; i < scene.surfels.size(); ++i) {
    const int p = attr(scene.surfels, "patch_id", i);
    const Vec3& x = scene.surfels.positions[i];
    EXPECT_EQ(attr(scene.surfels, kSurfelRoleAttribute, i),
              surfelRoleValue(p >= 2 ? SurfelRole::kTextureDiscontinuity : SurfelRole::kSurface));
    if (p >= 2) {
      ++border;
      EXPECT_NEAR(x.norm(), 1.0, 1e-12);
      EXPECT_NEAR(scene.surfels.normals[i].dot(x), 0, 1e-12);  // on a pyramid plane through the centre
    } else {
      EXPECT_NEAR(x.norm(), 1.0, 1e-12);
      // Each colour patch holds its side plus the surfels closer than 0.9 radii to the border (pyramid
      // planes).
      const Vec3 w = sq.direction, u = (sq.up - sq.up.dot(w) * w).normalized(), v = w.cross(u);
      const double t = std::tan(sq.half_angle);
      double beyond = -1e9;
      for (const Vec3& n : {Vec3(u - t * w), Vec3(-u - t * w), Vec3(v - t * w), Vec3(-v - t * w)})
        beyond = std::max(beyond, x.dot(n.normalized()));
      EXPECT_EQ(sq.contains(x), beyond < 0);
      if (p == 1) {
        inside += beyond < 0;
        EXPECT_LT(beyond, 0.9 * scene.surfels.radii[i] + 1e-12);
      } else {
        EXPECT_GT(beyond, -0.9 * scene.surfels.radii[i] - 1e-12);
      }
    }
  }
  // The square spans about (2 tan 22 deg)^2 / (1 + ...) ~ 0.6 sr; at spacing 0.025 that is ~ 900 surfels.
  EXPECT_GT(inside, 700u);
  EXPECT_LT(inside, 1100u);
  EXPECT_GT(border, 2u * 4 * 25);
  EXPECT_THROW(scene.analyticCaster(), std::invalid_argument);
  EXPECT_EQ(scene.analyticGeometryCaster().cast(Vec3(0, -5, 0), Vec3::UnitY()).patch, 0);
}

TEST(CsgSceneFiles, OrbitMovesTheBall) {
  const CsgScene scene = loadCsgScene(kSceneDir + "orbit.yaml");
  ASSERT_TRUE(scene.isDynamic());
  const CsgScenePatch& ball = scene.patches[6];
  EXPECT_EQ(ball.name, "ball");
  const SurfelCloud moved = scene.atTime(2.0);  // 45 deg/s: a quarter turn about z
  for (size_t i = ball.first_surfel; i < ball.first_surfel + ball.surfel_count; ++i) {
    const Vec3& a = scene.surfels.positions[i];
    EXPECT_NEAR((moved.positions[i] - Vec3(-a.y(), a.x(), a.z())).norm(), 0, 1e-12);
    EXPECT_NEAR((moved.positions[i] - Vec3(0, 0.65, 0.2)).norm(), 0.4, 1e-12);
  }
  EXPECT_EQ(moved.positions[0], scene.surfels.positions[0]);  // box faces do not move
  const std::vector<AnalyticSolid> solids = scene.solidsAt(2.0);
  EXPECT_NEAR((solids[6].center - Vec3(0, 0.65, 0.2)).norm(), 0, 1e-12);
  EXPECT_FALSE(scene.analyticCaster(2.0).contains(Vec3(0, 0.45, 0.2)));
  EXPECT_TRUE(scene.analyticCaster(0.0).contains(Vec3(0, 0.45, 0.2)));
}

TEST(CsgSceneFiles, AllFilesLoadAndUseEveryPatch) {
  for (const char* name : {"cube_densities", "icosahedron", "spikes", "femur", "texture_square", "orbit"}) {
    const CsgScene scene = loadCsgScene(kSceneDir + name + ".yaml");
    EXPECT_EQ(scene.name, name);
    EXPECT_FALSE(scene.cameras.empty());
    EXPECT_EQ(scene.csgTree().patches().size(), scene.patches.size()) << name;
    scene.surfels.validate();
  }
}

TEST(CsgSceneErrors, NameFileLineAndProblem) {
  auto message = [](const std::string& yaml) {
    try {
      parseCsgScene(yaml, "bad.yaml");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string cam =
      "cameras:\n  - {width: 10, height: 10, fov: 40, eye: [0, -3, 0], target: [0, 0, 0]}\n";
  EXPECT_EQ(
      message("patches:\n  - {name: a, shape: cone, center: [0, 0, 0], radius: 1, samples: 10}\ncsg: a\n" +
              cam)
          .rfind("bad.yaml:2:", 0),
      0u);
  EXPECT_NE(message("patches:\n  - {name: a, shape: cone, samples: 10}\ncsg: a\n" + cam)
                .find("unknown shape 'cone'"),
            std::string::npos);
  EXPECT_NE(
      message("patches:\n  - {name: a, shape: sphere, center: [0, 0], radius: 1, samples: 10}\ncsg: a\n" +
              cam)
          .find("expected [x, y, z]"),
      std::string::npos);
  EXPECT_NE(message("patches:\n  - {name: a, shape: sphere, center: [0, 0, 0], radius: 1}\ncsg: a\n" + cam)
                .find("needs 'samples' or 'spacing'"),
            std::string::npos);
  const std::string two =
      "patches:\n  - {name: a, shape: sphere, center: [0, 0, 0], radius: 1, samples: 10}\n"
      "  - {name: b, shape: sphere, center: [1, 0, 0], radius: 1, samples: 10}\n";
  EXPECT_NE(message(two + "csg: a - c\n" + cam).find("bad.yaml:4:"), std::string::npos);
  EXPECT_NE(message(two + "csg: a\n" + cam).find("patch 'b' is not used"), std::string::npos);
  EXPECT_NE(message(two + "csg: a | b\ncameras: []\n").find("non-empty"), std::string::npos);
  EXPECT_NE(message(two + "csg: a | b\n" + cam + "colour: [1, 2, 3]\n").find("unknown key 'colour'"),
            std::string::npos);
  EXPECT_NE(message("patches: [\n").find("YAML syntax error"), std::string::npos);
  EXPECT_THROW(loadCsgScene("/nonexistent/scene.yaml"), std::runtime_error);
}

}  // namespace
}  // namespace rc
