#include "relaxed_connectivity/render/splat/environment_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "relaxed_connectivity/render/splat/differential_renderer.h"
#include "relaxed_connectivity/render/splat/image_io.h"

namespace rc {
namespace {

/// The plane z = 0 over [-0.2, 0.2]^2, normals up, grey, every surfel of reflectivity r.
SurfelCloud reflectivePlane(float r) {
  SurfelCloud c;
  for (int i = -40; i <= 40; ++i)
    for (int j = -40; j <= 40; ++j) {
      c.positions.push_back(Vec3(0.005 * i, 0.005 * j, 0));
      c.normals.push_back(Vec3::UnitZ());
      c.radii.push_back(0.004);
      c.colors.push_back(Rgba{128, 128, 128, 255});
    }
  Attribute& a = c.attributes.add(kReflectivityAttribute, ScalarType::kFloat32, 1, c.size());
  for (size_t i = 0; i < c.size(); ++i) a.set(i, r);
  return c;
}

Camera obliqueCamera() {
  Camera camera = Camera::perspective(160, 120, 50 * M_PI / 180);
  camera.lookAt(Vec3(0, -0.5, 0.5), Vec3::Zero());
  return camera;
}

TEST(EnvironmentMap, StudioSkyFloorAndLight) {
  const EnvironmentMap studio = EnvironmentMap::studio();
  const Vec3 up = studio.radiance(Vec3::UnitZ()), down = studio.radiance(-Vec3::UnitZ());
  EXPECT_GT(up.z(), up.x());              // blue-grey sky
  EXPECT_GT(up.sum(), down.sum() + 0.5);  // brighter than the floor
  const Vec3 key = studio.radiance(Vec3(-0.3, 0.5, 0.8).normalized());
  EXPECT_GT(key.sum(), up.sum());  // the light box
  for (int k = 0; k < 200; ++k) {
    const double a = 0.7 * k, b = 0.31 * k;
    const Vec3 d(std::cos(a) * std::sin(b), std::sin(a) * std::sin(b), std::cos(b));
    const Vec3 c = studio.radiance(d);
    ASSERT_TRUE(c.allFinite() && c.minCoeff() >= 0 && c.maxCoeff() <= 1) << d.transpose();
  }
}

TEST(EnvironmentMap, EquirectangularImageIsZUp) {
  const std::string path = std::string(::testing::TempDir()) + "/env_" + std::to_string(::getpid()) + ".png";
  std::vector<Rgba> pixels(8 * 4);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x)
      pixels[size_t(y) * 8 + x] = y < 2 ? Rgba{255, 0, 0, 255} : Rgba{0, 255, 0, 255};
  writePng(path, pixels, 8, 4);
  const EnvironmentMap map = EnvironmentMap::fromEquirectangularPng(path);
  std::remove(path.c_str());
  EXPECT_EQ(map.radiance(Vec3(0.1, 0, 1).normalized()), Vec3(1, 0, 0));  // up: the top rows
  EXPECT_EQ(map.radiance(Vec3(0.1, 0, -1).normalized()), Vec3(0, 1, 0));
  try {
    EnvironmentMap::fromEquirectangularPng("/nonexistent/sky.png");
    FAIL() << "a missing file was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/sky.png"), std::string::npos) << e.what();
  }
}

// A mirror-like plane seen from above shows the environment reflected at each surfel (5.7); reflectivity 0
// leaves the colour.
TEST(EnvironmentMap, ReflectivePlaneShowsTheReflectedEnvironment) {
  const EnvironmentMap studio = EnvironmentMap::studio();
  SplatConfig config;
  config.shading = false;
  config.environment = &studio;
  const Camera camera = obliqueCamera();
  RenderImages mirror, matte;
  SurfelRenderer(config).render(reflectivePlane(1.0f), camera, &mirror);
  SurfelRenderer(config).render(reflectivePlane(0.0f), camera, &matte);
  const size_t centre = size_t(60) * 160 + 80;
  EXPECT_EQ(matte.color[centre], (Rgba{128, 128, 128, 255}));
  const Rgba expected = reflectedColor(Rgba{128, 128, 128, 255}, 1.0, Vec3::Zero(), Vec3::UnitZ(),
                                       camera.world_T_camera.translation(), studio);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(mirror.color[centre][k], expected[k], 3) << k;
  EXPECT_GT(std::abs(int(mirror.color[centre][2]) - 128), 20);  // the sky, not the grey
  EXPECT_EQ(
      reflectedColor(Rgba{10, 20, 30, 255}, std::nan(""), Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitZ(), studio),
      (Rgba{10, 20, 30, 255}));
}

// Differential updates of reflective surfels use the same camera, so un-splatting cancels: a recoloured
// patch matches a full render to one level.
TEST(EnvironmentMap, DifferentialUpdatesOfReflectiveSurfels) {
  const EnvironmentMap studio = EnvironmentMap::studio();
  DifferentialRenderConfig config;
  config.splat.threads = 2;
  config.splat.environment = &studio;
  const Camera camera = obliqueCamera();
  SurfelCloud state = reflectivePlane(0.6f);
  DifferentialSurfelRenderer renderer(config);
  renderer.renderFull(state, camera);
  std::vector<size_t> patch;
  for (size_t i = 0; i < state.size(); i += 7) patch.push_back(i);
  SurfelCloud removed = state;
  removed.select(patch);
  for (size_t i : patch) state.colors[i] = Rgba{200, 40, 40, 255};
  SurfelCloud added = state;
  added.select(patch);
  DifferentialStats stats;
  renderer.update(state, removed, added, camera, &stats);
  ASSERT_EQ(stats.update, RenderUpdate::kDifferential);
  DifferentialSurfelRenderer reference(config);
  reference.renderFull(state, camera);
  int worst = 0;
  for (size_t p = 0; p < reference.images().color.size(); ++p)
    for (int k = 0; k < 3; ++k)
      worst =
          std::max(worst, std::abs(int(renderer.images().color[p][k]) - int(reference.images().color[p][k])));
  EXPECT_LE(worst, 1);
}

}  // namespace
}  // namespace rc
