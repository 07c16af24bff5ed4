#include "relaxed_connectivity/render/splat/camera.h"

#include <gtest/gtest.h>

#include <random>

namespace rc {
namespace {

void expectRoundTrip(const Camera& camera) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pixel_u(0, camera.width - 1), pixel_v(0, camera.height - 1);
  std::uniform_real_distribution<double> depth(0.5, 20);
  for (int trial = 0; trial < 200; ++trial) {
    const double u = pixel_u(rng), v = pixel_v(rng);
    Vec3 origin, direction;
    camera.pixelRay(u, v, &origin, &direction);
    ASSERT_NEAR(direction.norm(), 1.0, 1e-12);
    const Vec3 point = origin + depth(rng) * direction;
    double u2 = 0, v2 = 0;
    ASSERT_TRUE(camera.project(camera.toCamera(point), &u2, &v2));
    EXPECT_NEAR(u2, u, 1e-9);
    EXPECT_NEAR(v2, v, 1e-9);
  }
}

TEST(Camera, PerspectiveRoundTripAndIntrinsics) {
  Camera camera = Camera::perspective(640, 480, M_PI / 2);
  EXPECT_NEAR(camera.fx, 320.0, 1e-12);
  EXPECT_NEAR(camera.cx, 319.5, 1e-12);
  EXPECT_NEAR(camera.cy, 239.5, 1e-12);
  camera.lookAt(Vec3(3, -2, 1.5), Vec3(0.2, 0.1, 0.3));
  expectRoundTrip(camera);
  // A point 1 m in front at 1 m to the right (camera x) projects fx pixels right of the centre.
  double u, v;
  ASSERT_TRUE(camera.project(Vec3(1, 0, 1), &u, &v));
  EXPECT_NEAR(u, camera.cx + camera.fx, 1e-9);
  EXPECT_NEAR(v, camera.cy, 1e-9);
  EXPECT_FALSE(camera.project(Vec3(0, 0, -1), &u, &v));  // behind the camera
}

TEST(Camera, OrthographicRoundTripAndScale) {
  Camera camera = Camera::orthographic(400, 300, 4.0);
  EXPECT_NEAR(camera.ortho_scale, 100.0, 1e-12);
  camera.lookAt(Vec3(0, 0, 10), Vec3(0, 0, 0), Vec3::UnitY());
  expectRoundTrip(camera);
  Vec3 origin0, origin1, direction0, direction1;
  camera.pixelRay(10, 20, &origin0, &direction0);
  camera.pixelRay(110, 20, &origin1, &direction1);
  EXPECT_NEAR((direction0 - direction1).norm(), 0.0, 1e-12);  // parallel rays
  EXPECT_NEAR((origin1 - origin0).norm(), 1.0, 1e-12);        // 100 px = 1 m
}

TEST(Camera, LookAtCentresTargetAndKeepsUpUp) {
  Camera camera = Camera::perspective(101, 81, 1.0);
  const Vec3 target(1, 2, 0.5);
  camera.lookAt(Vec3(-4, 3, 2), target, Vec3::UnitZ());
  double u, v;
  ASSERT_TRUE(camera.project(camera.toCamera(target), &u, &v));
  EXPECT_NEAR(u, camera.cx, 1e-9);
  EXPECT_NEAR(v, camera.cy, 1e-9);
  ASSERT_TRUE(camera.project(camera.toCamera(target + 0.1 * Vec3::UnitZ()), &u, &v));
  EXPECT_LT(v, camera.cy - 1);  // world up appears above the centre (image v points down)
  // Looking straight down along the up vector still gives a valid rigid pose.
  camera.lookAt(Vec3(0, 0, 5), Vec3::Zero(), Vec3::UnitZ());
  EXPECT_NO_THROW(camera.validate());
  ASSERT_TRUE(camera.project(camera.toCamera(Vec3::Zero()), &u, &v));
  EXPECT_NEAR(u, camera.cx, 1e-9);
}

TEST(Camera, ValidateNamesBadField) {
  Camera camera;
  camera.width = 0;
  try {
    camera.validate();
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("width"), std::string::npos);
  }
  camera = Camera();
  camera.fx = -1;
  EXPECT_THROW(camera.validate(), std::invalid_argument);
  camera = Camera();
  camera.far_clip = camera.near_clip;
  EXPECT_THROW(camera.validate(), std::invalid_argument);
  camera = Camera();
  camera.world_T_camera.linear() *= 2.0;
  EXPECT_THROW(camera.validate(), std::invalid_argument);
  EXPECT_THROW(Camera::perspective(10, 10, 0.0), std::invalid_argument);
  EXPECT_THROW(Camera::orthographic(10, 10, -1.0), std::invalid_argument);
}

}  // namespace
}  // namespace rc
