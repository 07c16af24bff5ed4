#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>

#include "relaxed_connectivity/scan/depth_sensor.h"
#include "relaxed_connectivity/scan/procedural_models.h"
#include "relaxed_connectivity/scan/sensor_trajectory.h"

namespace rc {
namespace {

constexpr double kPi = 3.14159265358979323846;

TriangleMesh translated(TriangleMesh mesh, const Vec3& offset) {
  for (Vec3& p : mesh.vertices.positions) p += offset;
  return mesh;
}

DepthSensorConfig smallConfig(uint32_t width = 160, uint32_t height = 120) {
  DepthSensorConfig config;
  config.intrinsics = PinholeIntrinsics::fromHorizontalFov(width, height, 60.0 * kPi / 180.0);
  config.min_range = 0.1;
  config.max_range = 20.0;
  return config;
}

struct DepthStatistics {
  size_t valid = 0;
  double mean = 0.0, stddev = 0.0;
};

DepthStatistics depthStatistics(const SurfelCloud& cloud) {
  DepthStatistics s;
  double sum = 0.0, sum_sq = 0.0;
  for (const Vec3& p : cloud.positions)
    if (p.allFinite()) {
      ++s.valid;
      sum += p.z();
      sum_sq += p.z() * p.z();
    }
  s.mean = sum / s.valid;
  s.stddev = std::sqrt(std::max(0.0, sum_sq / s.valid - s.mean * s.mean));
  return s;
}

// A large plane z = distance in front of a sensor at the origin looking along +z (identity pose).
TriangleMesh planeAt(double distance) {
  return makeGroundPlane(distance, 100.0, 4);
}

TEST(DepthSensor, NoiselessPlaneGivesExactDepthAndPinholeGeometry) {
  const TriangleMesh plane = planeAt(2.0);
  const MeshRayCaster caster(plane);
  const DepthSensorConfig config = smallConfig();
  const DepthSensor sensor(config);
  const SurfelCloud cloud = sensor.capture(caster, Eigen::Isometry3d::Identity());
  ASSERT_EQ(cloud.size(), 160u * 120u);
  EXPECT_TRUE(cloud.isOrganized());
  EXPECT_EQ(cloud.frame_id, config.frame_id);
  const PinholeIntrinsics& k = config.intrinsics;
  for (uint32_t v = 0; v < k.height; ++v)
    for (uint32_t u = 0; u < k.width; ++u) {
      const Vec3& p = cloud.positions[v * k.width + u];
      ASSERT_TRUE(p.allFinite());
      EXPECT_NEAR(p.z(), 2.0, 1e-12);
      EXPECT_NEAR(p.x(), 2.0 * (u - k.cx) / k.fx, 1e-12);
      EXPECT_NEAR(p.y(), 2.0 * (v - k.cy) / k.fy, 1e-12);
      double pu, pv;
      ASSERT_TRUE(sensor.project(p, &pu, &pv));
      EXPECT_NEAR(pu, u, 1e-9);
      EXPECT_NEAR(pv, v, 1e-9);
      // The plane faces away from the sensor (+z normal): the output normal is flipped to face it.
      EXPECT_TRUE(cloud.normals[v * k.width + u].isApprox(-Vec3::UnitZ(), 1e-12));
    }
  // Horizontal field of view: the outermost pixel centres lie within +-30 degrees.
  EXPECT_NEAR(k.fx, 80.0 / std::tan(30.0 * kPi / 180.0), 1e-9);
}

TEST(DepthSensor, NoiseMeanAndStddevMatchTheConfiguredModel) {
  DepthSensorConfig config = smallConfig();
  config.noise.sigma_constant = 0.002;
  config.noise.sigma_quadratic = 0.003;
  config.seed = 42;
  const DepthSensor sensor(config);
  for (double distance : {1.0, 2.0, 4.0}) {
    const TriangleMesh plane = planeAt(distance);
    const MeshRayCaster caster(plane);
    const DepthStatistics s = depthStatistics(sensor.capture(caster, Eigen::Isometry3d::Identity()));
    ASSERT_EQ(s.valid, 160u * 120u);
    const double sigma = 0.002 + 0.003 * distance * distance;
    // 19200 samples: the mean has standard error sigma / 139, the stddev a relative error of 0.5 %.
    EXPECT_NEAR(s.mean, distance, 4.0 * sigma / std::sqrt(19200.0)) << distance;
    EXPECT_NEAR(s.stddev, sigma, 0.03 * sigma) << distance;
  }
}

TEST(DepthSensor, NoiseIsGaussian) {
  DepthSensorConfig config = smallConfig();
  config.noise.sigma_constant = 0.01;
  config.seed = 3;
  const TriangleMesh plane = planeAt(1.5);
  const MeshRayCaster caster(plane);
  const SurfelCloud cloud = DepthSensor(config).capture(caster, Eigen::Isometry3d::Identity());
  size_t within_one = 0, within_two = 0;
  for (const Vec3& p : cloud.positions) {
    const double z = std::abs(p.z() - 1.5) / 0.01;
    within_one += z < 1.0;
    within_two += z < 2.0;
  }
  EXPECT_NEAR(within_one / 19200.0, 0.6827, 0.015);
  EXPECT_NEAR(within_two / 19200.0, 0.9545, 0.008);
}

TEST(DepthSensor, DropoutRemovesTheConfiguredFraction) {
  DepthSensorConfig config = smallConfig();
  config.noise.dropout_probability = 0.2;
  config.seed = 9;
  const TriangleMesh plane = planeAt(3.0);
  const MeshRayCaster caster(plane);
  const DepthSensor sensor(config);
  const SurfelCloud cloud = sensor.capture(caster, Eigen::Isometry3d::Identity());
  size_t nan_count = 0;
  for (size_t i = 0; i < cloud.size(); ++i)
    if (!cloud.positions[i].allFinite()) {
      ++nan_count;
      EXPECT_FALSE(cloud.normals[i].allFinite());
    }
  // Binomial(19200, 0.2): standard deviation 0.0029 in the fraction.
  EXPECT_NEAR(nan_count / 19200.0, 0.2, 0.012);
  // Unorganised output keeps exactly the returns.
  config.organized = false;
  const SurfelCloud returns = DepthSensor(config).capture(caster, Eigen::Isometry3d::Identity());
  EXPECT_EQ(returns.size(), cloud.size() - nan_count);
  EXPECT_EQ(returns.width, 0u);
  EXPECT_EQ(returns.height, 0u);
  for (const Vec3& p : returns.positions) EXPECT_TRUE(p.allFinite());
}

TEST(DepthSensor, SmallBoxOccludesTheSphereBehindIt) {
  TriangleMesh scene = translated(makeIcosphere(0.5, 16), Vec3(0, 0, 3.0));
  appendMesh(scene, translated(makeBox(Vec3(0.2, 0.2, 0.2), 2), Vec3(0, 0, 1.5)));  // front face at z = 1.4
  const MeshRayCaster caster(scene);
  const DepthSensorConfig config = smallConfig(161, 121);
  const DepthSensor sensor(config);
  const SurfelCloud cloud = sensor.capture(caster, Eigen::Isometry3d::Identity());
  size_t box_pixels = 0, sphere_pixels = 0;
  for (const Vec3& p : cloud.positions) {
    if (!p.allFinite()) continue;
    // A pixel whose ray passes through the box's front face sees the box, never the sphere.
    const bool through_box =
        std::abs(p.x() / p.z()) < 0.1 / 1.4 - 1e-9 && std::abs(p.y() / p.z()) < 0.1 / 1.4 - 1e-9;
    if (through_box) {
      EXPECT_NEAR(p.z(), 1.4, 1e-9);
      ++box_pixels;
    } else if (p.z() > 2.0) {
      EXPECT_GT(p.z(), 2.5 - 1e-3);  // the sphere's front at 2.5 (minus the tessellation sagitta)
      ++sphere_pixels;
    }
  }
  // The box subtends +-0.0714 rad, i.e. about 2 * 0.0714 * fx = 20 pixels per side.
  EXPECT_GT(box_pixels, 300u);
  EXPECT_GT(sphere_pixels, 1000u);
  // Without the box, the same centre pixels see the sphere.
  const TriangleMesh sphere_only = translated(makeIcosphere(0.5, 16), Vec3(0, 0, 3.0));
  const MeshRayCaster sphere_caster(sphere_only);
  const SurfelCloud unoccluded = sensor.capture(sphere_caster, Eigen::Isometry3d::Identity());
  const size_t centre = 60 * 161 + 80;
  EXPECT_NEAR(cloud.positions[centre].z(), 1.4, 1e-9);
  EXPECT_NEAR(unoccluded.positions[centre].z(), 2.5, 1e-3);
}

TEST(DepthSensor, OpticalFrameConvention) {
  // Sensor at the origin looking along world +x with world z up: optical z = world x, x = -world y (right),
  // y = -world z (down).
  TriangleMesh scene = translated(makeBox(Vec3(0.2, 0.2, 0.2), 1), Vec3(5.0, 0.0, 0.0));
  appendMesh(scene, translated(makeBox(Vec3(0.2, 0.2, 0.2), 1), Vec3(5.0, 0.0, 1.0)));   // above
  appendMesh(scene, translated(makeBox(Vec3(0.2, 0.2, 0.2), 1), Vec3(5.0, -1.0, 0.0)));  // right
  const MeshRayCaster caster(scene);
  const DepthSensorConfig config = smallConfig(161, 121);  // odd size: the centre pixel looks straight ahead
  const DepthSensor sensor(config);
  const Eigen::Isometry3d world_T_sensor = lookAt(Vec3::Zero(), Vec3(1.0, 0.0, 0.0));
  const SurfelCloud cloud = sensor.capture(caster, world_T_sensor);
  const Vec3& ahead = cloud.positions[60 * 161 + 80];
  ASSERT_TRUE(ahead.allFinite());
  EXPECT_EQ(ahead.x(), 0.0);
  EXPECT_EQ(ahead.y(), 0.0);
  EXPECT_NEAR(ahead.z(), 4.9, 1e-12);
  // Every return maps back to the world point it came from, and each box shows up where expected.
  size_t above = 0, right = 0;
  for (const Vec3& p : cloud.positions) {
    if (!p.allFinite()) continue;
    const Vec3 world = world_T_sensor * p;
    if (world.z() > 0.8) {
      ++above;
      EXPECT_LT(p.y(), 0.0);
      EXPECT_NEAR(p.x(), 0.0, 0.11);
    }
    if (world.y() < -0.8) {
      ++right;
      EXPECT_GT(p.x(), 0.0);
      EXPECT_NEAR(p.y(), 0.0, 0.11);
    }
  }
  EXPECT_GT(above, 10u);
  EXPECT_GT(right, 10u);
}

TEST(DepthSensor, NanCountEqualsMissCountAndColoursComeFromTheMesh) {
  TriangleMesh sphere = translated(makeIcosphere(0.5, 12), Vec3(0.1, -0.2, 2.0));
  for (Rgba& c : sphere.vertices.colors) c = {200, 40, 10, 255};
  const MeshRayCaster caster(sphere);
  DepthSensorConfig config = smallConfig();
  config.max_range = 2.0;  // cuts off the sphere's far rim: those pixels are misses too
  const DepthSensor sensor(config);
  const Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const SurfelCloud cloud = sensor.capture(caster, pose);
  ASSERT_EQ(cloud.size(), size_t(config.intrinsics.width) * config.intrinsics.height);
  ASSERT_TRUE(cloud.hasColors());
  size_t misses = 0, nans = 0;
  for (uint32_t v = 0; v < config.intrinsics.height; ++v)
    for (uint32_t u = 0; u < config.intrinsics.width; ++u) {
      Ray ray = sensor.pixelRay(u, v, pose);
      RayHit hit;
      const bool ok = caster.intersect(ray, &hit) && hit.t >= config.min_range && hit.t <= config.max_range;
      misses += !ok;
      const size_t i = v * config.intrinsics.width + u;
      nans += !cloud.positions[i].allFinite();
      if (ok) {
        EXPECT_EQ(cloud.colors[i], (Rgba{200, 40, 10, 255}));
        EXPECT_NEAR(cloud.normals[i].norm(), 1.0, 1e-9);
        EXPECT_LT(cloud.normals[i].dot(cloud.positions[i]), 0.0);  // faces the sensor
      }
    }
  EXPECT_EQ(nans, misses);
  EXPECT_GT(misses, 1000u);
  EXPECT_LT(misses, cloud.size() - 1000u);

  // A mesh without colours gives a cloud without colours.
  TriangleMesh plain = sphere;
  plain.vertices.colors.clear();
  const MeshRayCaster plain_caster(plain);
  EXPECT_FALSE(sensor.capture(plain_caster, pose).hasColors());
}

TEST(DepthSensor, SurfaceCloserThanMinRangeBlocksTheView) {
  TriangleMesh scene = planeAt(0.3);
  appendMesh(scene, planeAt(2.0));
  const MeshRayCaster caster(scene);
  DepthSensorConfig config = smallConfig();
  config.min_range = 0.5;
  const SurfelCloud cloud = DepthSensor(config).capture(caster, Eigen::Isometry3d::Identity());
  for (const Vec3& p : cloud.positions) EXPECT_FALSE(p.allFinite());
}

TEST(DepthSensor, DeterministicForASeedAndIndependentOfThreads) {
  const TriangleMesh blob = translated(makeBlob(0.5, 0.3, 16), Vec3(0, 0, 1.5));
  const MeshRayCaster caster(blob);
  DepthSensorConfig config = smallConfig();
  config.noise.sigma_constant = 0.001;
  config.noise.sigma_quadratic = 0.002;
  config.noise.dropout_probability = 0.1;
  config.seed = 1234;
  const DepthSensor sensor(config);
  auto same = [](const SurfelCloud& a, const SurfelCloud& b) {
    if (a.size() != b.size()) return false;
    return std::memcmp(a.positions.data(), b.positions.data(), a.size() * sizeof(Vec3)) == 0;
  };
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const SurfelCloud single = sensor.capture(caster, Eigen::Isometry3d::Identity(), 5);
  omp_set_num_threads(std::max(2, threads));
  const SurfelCloud multi = sensor.capture(caster, Eigen::Isometry3d::Identity(), 5);
  omp_set_num_threads(threads);
  EXPECT_TRUE(same(single, multi));
  EXPECT_TRUE(same(single, DepthSensor(config).capture(caster, Eigen::Isometry3d::Identity(), 5)));
  EXPECT_FALSE(same(single, sensor.capture(caster, Eigen::Isometry3d::Identity(), 6)));
  config.seed = 1235;
  EXPECT_FALSE(same(single, DepthSensor(config).capture(caster, Eigen::Isometry3d::Identity(), 5)));
}

void expectInvalid(const DepthSensorConfig& config, const std::string& field) {
  try {
    DepthSensor sensor(config);
    FAIL() << "expected std::invalid_argument for " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

TEST(DepthSensor, BadConfigThrowsNamingTheField) {
  DepthSensorConfig config = smallConfig();
  config.intrinsics.fx = 0.0;
  expectInvalid(config, "fx");
  config = smallConfig();
  config.intrinsics.fy = -5.0;
  expectInvalid(config, "fy");
  config = smallConfig();
  config.intrinsics.width = 0;
  expectInvalid(config, "width");
  config = smallConfig();
  config.intrinsics.height = 0;
  expectInvalid(config, "height");
  config = smallConfig();
  config.min_range = 5.0;
  config.max_range = 1.0;
  expectInvalid(config, "max_range");
  config = smallConfig();
  config.min_range = -1.0;
  expectInvalid(config, "min_range");
  config = smallConfig();
  config.noise.sigma_constant = -0.1;
  expectInvalid(config, "sigma_constant");
  config = smallConfig();
  config.noise.dropout_probability = 1.5;
  expectInvalid(config, "dropout_probability");
  config = smallConfig();
  config.intrinsics.cx = std::nan("");
  expectInvalid(config, "cx");
  EXPECT_THROW(PinholeIntrinsics::fromHorizontalFov(640, 480, 0.0), std::invalid_argument);
  EXPECT_THROW(PinholeIntrinsics::fromHorizontalFov(640, 480, kPi), std::invalid_argument);
  EXPECT_THROW(PinholeIntrinsics::fromHorizontalFov(0, 480, 1.0), std::invalid_argument);
}

TEST(SensorTrajectory, LookAtBuildsARightHandedOpticalFrame) {
  const Vec3 eye(1.0, 2.0, 3.0), target(-1.0, 0.5, 0.0);
  const Eigen::Isometry3d pose = lookAt(eye, target);
  const Eigen::Matrix3d r = pose.linear();
  EXPECT_TRUE((r.transpose() * r).isIdentity(1e-12));
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
  EXPECT_TRUE(pose.translation().isApprox(eye));
  EXPECT_TRUE(r.col(2).isApprox((target - eye).normalized(), 1e-12));  // z forward
  EXPECT_NEAR(r.col(0).z(), 0.0, 1e-12);                               // x horizontal
  EXPECT_LT(r.col(1).z(), 0.0);                                        // y down
  // Straight down still gives a valid frame.
  const Eigen::Isometry3d down = lookAt(Vec3(0, 0, 2), Vec3::Zero());
  EXPECT_TRUE(down.linear().col(2).isApprox(-Vec3::UnitZ(), 1e-12));
  EXPECT_NEAR(down.linear().determinant(), 1.0, 1e-12);
  EXPECT_THROW(lookAt(eye, eye), std::invalid_argument);
}

TEST(SensorTrajectory, OrbitCirclesTheTargetLookingAtIt) {
  OrbitParameters orbit;
  orbit.target = Vec3(0.5, -0.2, 0.1);
  orbit.radius = 2.0;
  orbit.height = 0.8;
  orbit.angular_speed = 0.4;
  orbit.height_amplitude = 0.3;
  orbit.height_period = 7.0;
  double min_height = 1e9, max_height = -1e9;
  for (int i = 0; i <= 700; ++i) {
    const double t = 0.01 * i;
    const Eigen::Isometry3d pose = orbitTrajectory(orbit, t);
    const Vec3 offset = pose.translation() - orbit.target;
    EXPECT_NEAR(offset.head<2>().norm(), 2.0, 1e-12);
    EXPECT_NEAR(std::atan2(offset.y(), offset.x()), std::remainder(0.4 * t, 2.0 * kPi), 1e-9);
    min_height = std::min(min_height, offset.z());
    max_height = std::max(max_height, offset.z());
    // The optical axis points at the target.
    const Vec3 target_in_sensor = pose.inverse() * orbit.target;
    EXPECT_NEAR(target_in_sensor.x(), 0.0, 1e-12);
    EXPECT_NEAR(target_in_sensor.y(), 0.0, 1e-12);
    EXPECT_NEAR(target_in_sensor.z(), offset.norm(), 1e-12);
  }
  EXPECT_NEAR(min_height, 0.5, 1e-3);
  EXPECT_NEAR(max_height, 1.1, 1e-3);
  // Periodic in angle when there is no climb.
  orbit.height_amplitude = 0.0;
  EXPECT_TRUE(orbitTrajectory(orbit, 1.0).isApprox(orbitTrajectory(orbit, 1.0 + 2.0 * kPi / 0.4), 1e-9));
  orbit.climb_rate = 0.1;
  EXPECT_NEAR(orbitEye(orbit, 10.0).z() - orbitEye(orbit, 0.0).z(), 1.0, 1e-12);
  orbit.radius = 0.0;
  EXPECT_THROW(orbitTrajectory(orbit, 0.0), std::invalid_argument);
}

TEST(SensorTrajectory, OrbitingSensorSeesTheModelInEveryFrame) {
  const TriangleMesh knot = makeModel("torus_knot", 8);
  const TriangleMesh scene = makeModel("torus_knot", 8, true);
  Vec3 lo, hi;
  knot.vertices.bounds(&lo, &hi);
  const MeshRayCaster caster(scene);
  const DepthSensor sensor(smallConfig());
  OrbitParameters orbit;
  for (int frame = 0; frame < 8; ++frame) {
    const Eigen::Isometry3d pose = orbitTrajectory(orbit, 1.5 * frame);
    const SurfelCloud cloud = sensor.capture(caster, pose, frame);
    size_t on_knot = 0, on_ground = 0;
    for (const Vec3& p : cloud.positions) {
      if (!p.allFinite()) continue;
      const Vec3 world = pose * p;
      if (world.z() > lo.z() + 1e-6) {
        ++on_knot;
        EXPECT_TRUE((world.array() <= hi.array() + 1e-9).all()) << frame;
      } else {
        ++on_ground;
        EXPECT_NEAR(world.z(), lo.z(), 0.01) << frame;
      }
    }
    // The knot (about 1.3 m across, seen from 1.6 m) covers a good part of the 60-degree image.
    EXPECT_GT(on_knot, cloud.size() / 8) << frame;
    EXPECT_GT(on_ground, cloud.size() / 8) << frame;
  }
}

}  // namespace
}  // namespace rc
