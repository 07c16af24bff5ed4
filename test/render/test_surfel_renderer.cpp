#include "relaxed_connectivity/render/splat/surfel_renderer.h"

#include <gtest/gtest.h>

#include <thread>

#include <cmath>
#include <cstring>

namespace rc {
namespace {

/// Camera at the origin looking along +z (image x right, y down), square image.
Camera frontCamera(uint32_t size = 201, double focal = 200) {
  Camera camera;
  camera.width = camera.height = size;
  camera.fx = camera.fy = focal;
  camera.cx = camera.cy = 0.5 * (size - 1);
  return camera;
}

void addSurfel(SurfelCloud& cloud, const Vec3& position, const Vec3& normal, double radius, Rgba color) {
  cloud.positions.push_back(position);
  cloud.normals.push_back(normal.normalized());
  cloud.radii.push_back(radius);
  cloud.colors.push_back(color);
}

/// Grid of surfels on the plane z = z0 + slope * x over [-half, half]^2, normals towards the camera.
SurfelCloud samplePlane(double z0, double slope, double half, double spacing, double radius_factor,
                        Rgba color) {
  SurfelCloud cloud;
  const Vec3 normal = Vec3(slope, 0, -1).normalized();
  const int steps = int(std::round(2 * half / spacing));
  for (int i = 0; i <= steps; ++i)
    for (int j = 0; j <= steps; ++j) {
      const double x = -half + i * spacing, y = -half + j * spacing;
      addSurfel(cloud, Vec3(x, y, z0 + slope * x), normal,
                radius_factor * spacing * std::sqrt(1 + slope * slope), color);
    }
  return cloud;
}

SurfelCloud sampleSphere(const Vec3& center, double radius, int count, Rgba color) {
  SurfelCloud cloud;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  const double surfel_radius = 1.5 * radius * std::sqrt(4.0 / count);  // covers the Fibonacci spacing
  for (int i = 0; i < count; ++i) {
    const double z = 1 - 2 * (i + 0.5) / count, r = std::sqrt(1 - z * z), phi = golden * i;
    const Vec3 normal(r * std::cos(phi), r * std::sin(phi), z);
    addSurfel(cloud, center + radius * normal, normal, surfel_radius, color);
  }
  return cloud;
}

size_t coveredPixels(const RenderImages& images) {
  size_t covered = 0;
  for (float w : images.weight) covered += w > 0;
  return covered;
}

bool allFinite(const RenderImages& images) {
  for (size_t p = 0; p < images.weight.size(); ++p) {
    if (!std::isfinite(images.weight[p]) || !images.normal[p].allFinite()) return false;
    if (images.weight[p] > 0 && !std::isfinite(images.depth[p])) return false;
  }
  return true;
}

SplatConfig unshaded() {
  SplatConfig config;
  config.shading = false;
  return config;
}

TEST(SurfelRenderer, SingleSurfelDiscRadiusAndCentre) {
  const Camera camera = frontCamera();
  SurfelCloud cloud;
  addSurfel(cloud, Vec3(0, 0, 5), Vec3(0, 0, -1), 0.5, {255, 0, 0, 255});
  for (bool ewa : {false, true}) {
    SplatConfig config = unshaded();
    config.ewa_filter = ewa;
    RenderImages images;
    RenderStats stats;
    SurfelRenderer(config).render(cloud, camera, &images, nullptr, &stats);
    EXPECT_EQ(stats.splats, 1u);
    // Expected footprint radius: r fx / z = 20 px, widened by the low-pass filter: cutoff * sqrt(sigma^2 +
    // V).
    const double sigma = 0.5 * 0.5 * camera.fx / 5;
    const double expected = ewa ? 2 * std::sqrt(sigma * sigma + config.lowpass_variance) : 20.0;
    double sum_u = 0, sum_v = 0, max_distance = 0;
    size_t covered = 0;
    for (uint32_t v = 0; v < camera.height; ++v)
      for (uint32_t u = 0; u < camera.width; ++u) {
        if (!(images.weight[v * camera.width + u] > 0)) continue;
        ++covered;
        sum_u += u;
        sum_v += v;
        max_distance = std::max(max_distance, std::hypot(u - camera.cx, v - camera.cy));
        EXPECT_EQ(images.color[v * camera.width + u], (Rgba{255, 0, 0, 255}));
      }
    EXPECT_NEAR(max_distance, expected, 1.0) << "ewa " << ewa;
    EXPECT_NEAR(std::sqrt(covered / M_PI), expected, 1.0);
    EXPECT_NEAR(sum_u / covered, camera.cx, 0.1);
    EXPECT_NEAR(sum_v / covered, camera.cy, 0.1);
    EXPECT_NEAR(images.depth[100 * camera.width + 100], 5.0, 1e-5);
    EXPECT_EQ(images.patch_id[100 * camera.width + 100], 0);
    EXPECT_EQ(images.patch_id[0], -1);
  }
}

TEST(SurfelRenderer, OrthographicDiscRadius) {
  Camera camera = Camera::orthographic(101, 101, 2.0);  // 50 px per metre
  camera.lookAt(Vec3(0, 0, 3), Vec3::Zero(), Vec3::UnitY());
  SurfelCloud cloud;
  addSurfel(cloud, Vec3(0, 0, 0), Vec3(0, 0, 1), 0.4, {0, 255, 0, 255});
  SplatConfig config = unshaded();
  config.ewa_filter = false;
  RenderImages images;
  SurfelRenderer(config).render(cloud, camera, &images);
  EXPECT_NEAR(std::sqrt(coveredPixels(images) / M_PI), 20.0, 1.0);
  EXPECT_NEAR(images.depth[50 * 101 + 50], 3.0, 1e-5);
}

TEST(SurfelRenderer, DensePlaneIsHoleFreeWithAnalyticDepthAndNormal) {
  const Camera camera = frontCamera();
  const double z0 = 4, slope = 0.4;
  const SurfelCloud cloud = samplePlane(z0, slope, 1.0, 0.02, 1.0, {100, 150, 200, 255});
  RenderImages images;
  RenderStats stats;
  SurfelRenderer(unshaded()).render(cloud, camera, &images, nullptr, &stats);
  const Eigen::Vector3f plane_normal = Vec3(slope, 0, -1).normalized().cast<float>();
  size_t inside = 0, holes = 0;
  double max_depth_error = 0, max_normal_error = 0;
  for (uint32_t v = 0; v < camera.height; ++v)
    for (uint32_t u = 0; u < camera.width; ++u) {
      // Ray (xn, yn, 1) t meets z = z0 + slope x at t = z0 / (1 - slope xn).
      const double xn = (u - camera.cx) / camera.fx, yn = (v - camera.cy) / camera.fy;
      const double t = z0 / (1 - slope * xn);
      if (std::abs(xn * t) > 0.95 || std::abs(yn * t) > 0.95) continue;
      ++inside;
      const size_t p = v * camera.width + u;
      if (!(images.weight[p] > 0)) {
        ++holes;
        continue;
      }
      max_depth_error = std::max(max_depth_error, std::abs(images.depth[p] - t));
      max_normal_error = std::max(max_normal_error, double((images.normal[p] - plane_normal).norm()));
    }
  EXPECT_GT(inside, 8000u);
  EXPECT_EQ(holes, 0u);
  EXPECT_LT(max_depth_error, 1e-4 * z0);
  EXPECT_LT(max_normal_error, 1e-5);
  EXPECT_EQ(stats.edge_on_surfels, 0u);
}

TEST(SurfelRenderer, FuzzyDepthTestSeparatesOverlappingPlanes) {
  const Camera camera = frontCamera();
  SurfelCloud cloud = samplePlane(3.0, 0, 0.6, 0.02, 1.0, {255, 0, 0, 255});
  cloud.append(samplePlane(3.3, 0, 0.6, 0.02, 1.0, {0, 0, 255, 255}));
  auto countMixed = [&](double tolerance_scale, size_t* pure_front) {
    SplatConfig config = unshaded();
    config.depth_tolerance_scale = tolerance_scale;
    RenderImages images;
    SurfelRenderer(config).render(cloud, camera, &images);
    size_t mixed = 0;
    *pure_front = 0;
    for (uint32_t v = 60; v <= 140; ++v)  // well inside the front plane (|x|, |y| < 0.6 at z = 3: 40 px)
      for (uint32_t u = 60; u <= 140; ++u) {
        const Rgba c = images.color[v * camera.width + u];
        if (c == Rgba{255, 0, 0, 255} && std::abs(images.depth[v * camera.width + u] - 3.0f) < 1e-4f)
          ++*pure_front;
        else
          ++mixed;
      }
    return mixed;
  };
  size_t pure = 0;
  EXPECT_EQ(countMixed(1.0, &pure), 0u);
  EXPECT_EQ(pure, 81u * 81u);
  // A tolerance larger than the gap between the sheets blends them: the test above can fail.
  EXPECT_GT(countMixed(200.0, &pure), 1000u);
}

/// Largest angle between the normals of 4-neighbour pixels on the part of the sphere facing the camera.
double maxNeighbourNormalAngle(const RenderImages& images, const Camera& camera) {
  double max_angle = 0;
  for (uint32_t v = 1; v < camera.height; ++v)
    for (uint32_t u = 1; u < camera.width; ++u) {
      const size_t p = v * camera.width + u;
      for (size_t q : {p - 1, p - camera.width}) {
        if (!(images.weight[p] > 0 && images.weight[q] > 0)) continue;
        if (images.normal[p].z() > -0.7f || images.normal[q].z() > -0.7f) continue;  // away from silhouette
        max_angle =
            std::max(max_angle, double(std::acos(std::min(1.0f, images.normal[p].dot(images.normal[q])))));
      }
    }
  return max_angle;
}

TEST(SurfelRenderer, SphereBlendsWithoutSeams) {
  const Camera camera = frontCamera(201, 300);
  const SurfelCloud sphere = sampleSphere(Vec3(0, 0, 4), 1.0, 20000, {10, 200, 120, 255});
  for (bool exact_silhouettes : {true, false}) {
    SplatConfig config = unshaded();
    config.exact_silhouettes = exact_silhouettes;
    RenderImages images;
    RenderStats stats;
    SurfelRenderer(config).render(sphere, camera, &images, nullptr, &stats);
    size_t covered = 0;
    for (size_t p = 0; p < images.weight.size(); ++p) {
      if (!(images.weight[p] > 0)) continue;
      ++covered;
      ASSERT_EQ(images.color[p], (Rgba{10, 200, 120, 255})) << p;
    }
    // Disc of radius fx * R / sqrt(d^2 - R^2) = 77.5 px (silhouette of the sphere).
    EXPECT_NEAR(std::sqrt(covered / M_PI), 300 / std::sqrt(15.0), exact_silhouettes ? 0.25 : 3.0);
    const double blended = maxNeighbourNormalAngle(images, camera);
    config.depth_tolerance_scale = 0;  // no blending across surfels: piecewise constant normals (seams)
    SurfelRenderer(config).render(sphere, camera, &images);
    const double unblended = maxNeighbourNormalAngle(images, camera);
    // Measured: blended 0.0230 in both; unblended 0.0569 (exact silhouettes: the nearest covering surfel
    // shows) and 0.0710 (the nearest of the dilated ones, tangent planes extrapolated beyond their discs).
    std::printf(
        "exact_silhouettes %d: covered radius %.2f px (silhouette 77.46), max neighbour normal angle: "
        "blended %.4f, unblended %.4f\n",
        int(exact_silhouettes), std::sqrt(covered / M_PI), blended, unblended);
    EXPECT_LT(blended, 0.03);
    EXPECT_GT(unblended, 2 * blended);
  }
}

TEST(SurfelRenderer, ExactSilhouettesShowTheSurfaceBehind) {
  // A sphere (silhouette radius 77.46 px) in front of a plane: just outside its silhouette the plane shows,
  // not a ring of the sphere's dilated splats (filtered coverage) and not the background (a dilated
  // fragment in front must not hide the plane's covering ones).
  const Camera camera = frontCamera(201, 300);
  const Rgba green{10, 200, 120, 255}, red{220, 20, 20, 255};
  SurfelCloud scene = sampleSphere(Vec3(0, 0, 4), 1.0, 20000, green);
  scene.append(samplePlane(6.0, 0, 3.0, 0.02, 0.75, red));
  const double silhouette = 300 / std::sqrt(15.0);
  for (bool exact_silhouettes : {true, false}) {
    SplatConfig config = unshaded();
    config.exact_silhouettes = exact_silhouettes;
    RenderImages images;
    SurfelRenderer(config).render(scene, camera, &images);
    size_t ring = 0, sphere_in_ring = 0, plane_in_ring = 0, background = 0, wrong_inside = 0;
    for (uint32_t v = 0; v < camera.height; ++v)
      for (uint32_t u = 0; u < camera.width; ++u) {
        const size_t p = size_t(v) * camera.width + u;
        const double r = std::hypot(u - camera.cx, v - camera.cy);
        background += !(images.weight[p] > 0);
        if (r < silhouette - 1.5) wrong_inside += images.color[p] != green;
        if (r < silhouette + 0.25 || r > silhouette + 1.0) continue;  // the pixel ring outside
        ++ring;
        sphere_in_ring += images.color[p] == green;
        plane_in_ring += images.color[p] == red;
      }
    std::printf(
        "exact_silhouettes %d: ring of %zu px outside the silhouette: %zu sphere, %zu plane; %zu "
        "background px\n",
        int(exact_silhouettes), ring, sphere_in_ring, plane_in_ring, background);
    EXPECT_EQ(background, 0u);
    EXPECT_EQ(wrong_inside, 0u);
    if (exact_silhouettes) {
      EXPECT_EQ(sphere_in_ring, 0u);
      EXPECT_EQ(plane_in_ring, ring);
    } else {
      EXPECT_GT(sphere_in_ring, ring / 2);  // the dilation (up to 1 px)
    }
  }
}

TEST(SurfelRenderer, EdgeOnSurfelsAreDrawnWithoutNaN) {
  for (bool ortho : {false, true}) {
    Camera camera = ortho ? Camera::orthographic(201, 201, 2.0) : frontCamera();
    SurfelCloud cloud;
    for (int i = 0; i < 50; ++i) {  // normals exactly perpendicular to the view ray through the centre
      const Vec3 position(-0.5 + 0.02 * i, 0.3 * std::sin(i), 5);
      const Vec3 view = ortho ? Vec3::UnitZ() : position.normalized();
      addSurfel(cloud, position, view.cross(Vec3(std::cos(i), std::sin(i), 0)), 0.05, {0, 0, 0, 255});
    }
    addSurfel(cloud, Vec3(0, 0, 5), Vec3(1, 0, 1e-9), 0.05, {0, 0, 0, 255});  // almost edge-on
    for (int variant = 0; variant < 3; ++variant) {
      SplatConfig config;
      config.ewa_filter = variant != 0;
      config.exact_silhouettes = variant == 2;
      RenderImages images;
      RenderStats stats;
      SurfelRenderer(config).render(cloud, camera, &images, nullptr, &stats);
      EXPECT_EQ(stats.edge_on_surfels, 51u);
      EXPECT_EQ(stats.splats, 51u);
      EXPECT_TRUE(allFinite(images));
      if (config.exact_silhouettes) {  // a disc seen exactly edge-on has no area: (almost) nothing covered
        EXPECT_LT(coveredPixels(images), 51u);
      } else {
        EXPECT_GT(coveredPixels(images), 51u * 3);  // each is a line several pixels long (4.2.3)
      }
      for (size_t p = 0; p < images.depth.size(); ++p) {
        if (images.weight[p] > 0) {
          EXPECT_NEAR(images.depth[p], 5.0, 0.06);
        }
      }
    }
  }
}

TEST(SurfelRenderer, InvalidSurfelsAreCountedAndBadInputThrows) {
  SurfelCloud cloud;
  addSurfel(cloud, Vec3(0, 0, 5), Vec3(0, 0, -1), 0.5, {1, 2, 3, 255});
  addSurfel(cloud, Vec3(NAN, 0, 5), Vec3(0, 0, -1), 0.5, {1, 2, 3, 255});
  addSurfel(cloud, Vec3(0, 0, 5), Vec3(0, 0, -1), 0.0, {1, 2, 3, 255});
  addSurfel(cloud, Vec3(0, 0, -5), Vec3(0, 0, -1), 0.5, {1, 2, 3, 255});  // behind the camera
  RenderImages images;
  RenderStats stats;
  SurfelRenderer().render(cloud, frontCamera(), &images, nullptr, &stats);
  EXPECT_EQ(stats.splats, 1u);
  EXPECT_EQ(stats.invalid_surfels, 2u);
  EXPECT_EQ(stats.culled_surfels, 1u);
  EXPECT_TRUE(allFinite(images));
  cloud.radii.clear();
  try {
    SurfelRenderer().render(cloud, frontCamera(), &images);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("radii"), std::string::npos);
  }
  SplatConfig bad;
  bad.lowpass_variance = 0;
  EXPECT_THROW(SurfelRenderer{bad}, std::invalid_argument);
}

TEST(SurfelRenderer, DeterministicForAnyThreadCount) {
  const Camera camera = frontCamera(257, 300);
  SurfelCloud cloud = sampleSphere(Vec3(0.1, -0.05, 4), 1.0, 30000, {200, 50, 50, 255});
  cloud.append(samplePlane(4.5, 0.2, 1.5, 0.03, 1.0, {50, 50, 200, 255}));
  RenderImages images[2];
  for (int k = 0; k < 2; ++k) {
    SplatConfig config;
    config.threads = k + 1;
    SurfelRenderer(config).render(cloud, camera, &images[k]);
  }
  const size_t n = images[0].weight.size();
  EXPECT_EQ(0, std::memcmp(images[0].color.data(), images[1].color.data(), n * sizeof(Rgba)));
  EXPECT_EQ(0, std::memcmp(images[0].depth.data(), images[1].depth.data(), n * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(images[0].weight.data(), images[1].weight.data(), n * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(images[0].normal.data(), images[1].normal.data(), n * sizeof(Eigen::Vector3f)));
  EXPECT_EQ(images[0].patch_id, images[1].patch_id);
}

// The eight-wide (AVX2) tile passes give bitwise the images of the four-wide (SSE2) ones: perspective and
// orthographic cameras, circular and elliptical surfels, two-sided and culled, every output subset.
TEST(SurfelRenderer, WideTilePassesGiveBitwiseTheSameImages) {
  SurfelCloud circular = sampleSphere(Vec3(0.1, -0.05, 4), 1.0, 20000, {200, 50, 50, 255});
  circular.append(samplePlane(4.5, 0.2, 1.5, 0.03, 1.0, {50, 50, 200, 255}));
  for (size_t i = 0; i < circular.size(); ++i)
    circular.colors[i] = {uint8_t(i * 37 % 256), uint8_t(i * 91 % 256), uint8_t(i * 13 % 256), 255};
  SurfelCloud elliptical = samplePlane(4.2, -0.4, 1.2, 0.04, 1.0, {90, 200, 60, 255});
  for (size_t i = 0; i < elliptical.size(); ++i) {  // stretched along a direction that turns over the plane
    Vec3 axis1, axis2;
    const double angle = 0.01 * double(i);
    const Vec3 n = elliptical.normals[i];
    const Vec3 t = n.unitOrthogonal(), b = n.cross(t);
    axis1 = 1.8 * elliptical.radii[i] * (std::cos(angle) * t + std::sin(angle) * b);
    axis2 = 0.7 * elliptical.radii[i] * (-std::sin(angle) * t + std::cos(angle) * b);
    elliptical.axes1.push_back(axis1);
    elliptical.axes2.push_back(axis2);
  }
  Camera orthographic = Camera::orthographic(203, 157, 3.5);
  orthographic.lookAt(Vec3(0.3, -2, -1), Vec3(0, 0, 4));
  const Camera cameras[] = {frontCamera(257, 300), orthographic};
  const SurfelCloud* clouds[] = {&circular, &elliptical};
  int wide_runs = 0;
  for (const Camera& camera : cameras)
    for (const SurfelCloud* cloud : clouds)
      for (const bool cull : {false, true})
        for (const uint32_t outputs : {uint32_t(kOutputAll), uint32_t(kOutputColor | kOutputDepth)}) {
          RenderImages images[2];
          RenderStats stats[2];
          for (int wide = 0; wide < 2; ++wide) {
            SplatConfig config;
            config.threads = 2;
            config.backface_culling = cull;
            config.outputs = outputs;
            config.wide_simd = wide == 1;
            SurfelRenderer(config).render(*cloud, camera, &images[wide], nullptr, &stats[wide]);
          }
          wide_runs += stats[1].simd_width == 8;
          EXPECT_NE(stats[0].simd_width, 8);
          EXPECT_EQ(stats[0].fragments, stats[1].fragments);
          EXPECT_EQ(stats[0].splats, stats[1].splats);
          EXPECT_EQ(stats[0].culled_surfels, stats[1].culled_surfels);
          EXPECT_EQ(stats[0].invalid_surfels, stats[1].invalid_surfels);
          EXPECT_GT(stats[1].fragments, 1000u);
          const size_t n = size_t(camera.width) * camera.height;
          EXPECT_EQ(0, std::memcmp(images[0].color.data(), images[1].color.data(), n * sizeof(Rgba)));
          EXPECT_EQ(0, std::memcmp(images[0].depth.data(), images[1].depth.data(), n * sizeof(float)));
          EXPECT_EQ(images[0].weight, images[1].weight);
          EXPECT_TRUE(images[0].normal == images[1].normal);
          EXPECT_EQ(images[0].patch_id, images[1].patch_id);
        }
  if (wide_runs == 0) std::printf("[ note ] this CPU has no AVX2: only the four-wide passes ran\n");
}

// The renderer keeps scratch memory between frames: a second frame of another scene, a copied renderer and
// two threads rendering with one renderer at the same time all give the images of a fresh renderer.
TEST(SurfelRenderer, ReusedCopiedAndConcurrentRenderersGiveFreshResults) {
  const Camera camera = frontCamera(129, 150);
  const SurfelCloud sphere = sampleSphere(Vec3(0, 0, 4), 1.0, 8000, {200, 50, 50, 255});
  const SurfelCloud plane = samplePlane(4.5, 0.2, 1.5, 0.05, 1.0, {50, 50, 200, 255});
  RenderImages fresh_sphere, fresh_plane;
  SurfelRenderer().render(sphere, camera, &fresh_sphere);
  SurfelRenderer().render(plane, camera, &fresh_plane);
  auto same = [](const RenderImages& a, const RenderImages& b) {
    return a.depth.size() == b.depth.size() &&
           std::memcmp(a.depth.data(), b.depth.data(), a.depth.size() * sizeof(float)) == 0 &&
           std::memcmp(a.color.data(), b.color.data(), a.color.size() * sizeof(Rgba)) == 0 &&
           a.patch_id == b.patch_id;
  };
  SurfelRenderer reused;
  RenderImages images;
  reused.render(sphere, camera, &images);
  reused.render(plane, camera, &images);
  EXPECT_TRUE(same(images, fresh_plane));
  const SurfelRenderer copy = reused;
  copy.render(sphere, camera, &images);
  EXPECT_TRUE(same(images, fresh_sphere));
  RenderImages concurrent[2];
  std::thread other([&] { reused.render(plane, camera, &concurrent[1]); });
  reused.render(sphere, camera, &concurrent[0]);
  other.join();
  EXPECT_TRUE(same(concurrent[0], fresh_sphere));
  EXPECT_TRUE(same(concurrent[1], fresh_plane));
}

TEST(SurfelRenderer, OnlyTheRequestedOutputsAreFilledAndTheyAreUnchanged) {
  const Camera camera = frontCamera(129, 150);
  const SurfelCloud sphere = sampleSphere(Vec3(0, 0, 4), 1.0, 8000, {200, 50, 50, 255});
  RenderImages all, some;
  SurfelRenderer().render(sphere, camera, &all);
  for (const uint32_t outputs : {uint32_t(kOutputColor | kOutputDepth), uint32_t(kOutputNormal),
                                 uint32_t(kOutputWeight | kOutputPatchId)}) {
    SplatConfig config;
    config.outputs = outputs;
    SurfelRenderer(config).render(sphere, camera, &some);
    const size_t pixels = size_t(camera.width) * camera.height;
    EXPECT_EQ(some.color.size(), (outputs & kOutputColor) ? pixels : 0u);
    EXPECT_EQ(some.depth.size(), (outputs & kOutputDepth) ? pixels : 0u);
    EXPECT_EQ(some.normal.size(), (outputs & kOutputNormal) ? pixels : 0u);
    EXPECT_EQ(some.weight.size(), (outputs & kOutputWeight) ? pixels : 0u);
    EXPECT_EQ(some.patch_id.size(), (outputs & kOutputPatchId) ? pixels : 0u);
    if (outputs & kOutputColor) {
      EXPECT_EQ(std::memcmp(some.color.data(), all.color.data(), pixels * sizeof(Rgba)), 0);
    }
    if (outputs & kOutputDepth) {
      EXPECT_EQ(std::memcmp(some.depth.data(), all.depth.data(), pixels * sizeof(float)), 0);
    }
    if (outputs & kOutputNormal) {
      EXPECT_TRUE(some.normal == all.normal);
    }
    if (outputs & kOutputWeight) {
      EXPECT_TRUE(some.weight == all.weight);
    }
    if (outputs & kOutputPatchId) {
      EXPECT_TRUE(some.patch_id == all.patch_id);
    }
  }
  SplatConfig bad;
  bad.outputs = 64;
  EXPECT_THROW(SurfelRenderer{bad}, std::invalid_argument);
}

/// Keeps fragments with world x < 0 of surfel 0.
class HalfSpaceClipper : public FragmentClipper {
 public:
  explicit HalfSpaceClipper(bool color_only) : color_only_(color_only) {}
  bool needsClipping(uint32_t surfel) const override { return surfel == 0; }
  bool keepFragment(uint32_t surfel, const Vec3& x) const override { return x.x() < 0; }
  bool clipsColorOnly(uint32_t surfel) const override { return color_only_; }

 private:
  bool color_only_;
};

TEST(SurfelRenderer, ClipperHalvesDiscAndClippedFragmentsDoNotOcclude) {
  const Camera camera = frontCamera();
  SurfelCloud cloud;
  addSurfel(cloud, Vec3(0, 0, 5), Vec3(0, 0, -1), 0.5, {255, 0, 0, 255});  // red, clipped at x = 0
  addSurfel(cloud, Vec3(0, 0, 6), Vec3(0, 0, -1), 1.0, {0, 0, 255, 255});  // blue, behind
  const HalfSpaceClipper clipper(false);
  RenderImages images;
  RenderStats stats;
  SurfelRenderer(unshaded()).render(cloud, camera, &images, &clipper, &stats);
  int max_red_column = -1, min_red_column = 1000;
  size_t red = 0;
  for (uint32_t v = 0; v < camera.height; ++v)
    for (uint32_t u = 0; u < camera.width; ++u) {
      const size_t p = v * camera.width + u;
      const bool is_red = images.color[p] == Rgba{255, 0, 0, 255};
      if (is_red) {
        ++red;
        max_red_column = std::max(max_red_column, int(u));
        min_red_column = std::min(min_red_column, int(u));
      }
      // Right of x = 0 within the red disc, the blue surfel behind is visible.
      if (u > camera.cx && std::hypot(u - camera.cx, v - camera.cy) < 15) {
        EXPECT_EQ(images.color[p], (Rgba{0, 0, 255, 255})) << u << " " << v;
        EXPECT_NEAR(images.depth[p], 6.0, 1e-4);
      }
    }
  EXPECT_NEAR(max_red_column, camera.cx, 1.0);
  // Footprint radius: 2 sigma of the kernel (10 px); the low-pass filter covers no more (exact silhouettes).
  const double radius = 20;
  EXPECT_LE(camera.cx - min_red_column, radius);
  EXPECT_GT(camera.cx - min_red_column, radius - 1.001);
  EXPECT_NEAR(double(red), 0.5 * M_PI * radius * radius - radius,
              0.05 * red);  // left half, centre column cut
  EXPECT_GT(stats.clipped_fragments, red / 2);
}

TEST(SurfelRenderer, ColorOnlyClippingKeepsWeightsAndRemovesColor) {
  const Camera camera = frontCamera();
  SurfelCloud cloud;
  addSurfel(cloud, Vec3(0, 0, 5), Vec3(0, 0, -1), 0.5, {255, 0, 0, 255});
  SplatConfig config = unshaded();
  RenderImages reference, clipped;
  SurfelRenderer(config).render(cloud, camera, &reference);
  const HalfSpaceClipper clipper(true);
  RenderStats stats;
  SurfelRenderer(config).render(cloud, camera, &clipped, &clipper, &stats);
  EXPECT_EQ(reference.weight, clipped.weight);
  EXPECT_EQ(reference.depth, clipped.depth);
  EXPECT_GT(stats.clipped_fragments, 0u);
  for (uint32_t v = 0; v < camera.height; ++v)
    for (uint32_t u = 0; u < camera.width; ++u) {
      const size_t p = v * camera.width + u;
      if (!(clipped.weight[p] > 0)) continue;
      const Rgba expected = u < camera.cx ? Rgba{255, 0, 0, 255} : config.default_color;
      EXPECT_EQ(clipped.color[p], expected) << u << " " << v;
    }
}

TEST(SurfelRenderer, EwaFilterKeepsMinifiedSurfelsHoleFree) {
  // (without exact_silhouettes) Far-away plane: 0.8 px between samples, disc radius 0.4 of the spacing
  // (sub-pixel gaps). Point sampling the unfiltered kernels misses pixels; the low-pass filter band-limits
  // them into a closed surface.
  const Camera camera = frontCamera(201, 200);
  const double z = 50, spacing = 0.8 * z / camera.fx;
  const SurfelCloud cloud = samplePlane(z, 0, 0.5 * 100 * spacing, spacing, 0.4, {90, 90, 90, 255});
  auto holesInside = [&](bool ewa, bool exact_silhouettes = false, const SurfelCloud* other = nullptr) {
    SplatConfig config = unshaded();
    config.ewa_filter = ewa;
    config.exact_silhouettes = exact_silhouettes;
    RenderImages images;
    SurfelRenderer(config).render(other ? *other : cloud, camera, &images);
    size_t holes = 0;
    for (uint32_t v = 70; v <= 130; ++v)
      for (uint32_t u = 70; u <= 130; ++u) holes += !(images.weight[v * camera.width + u] > 0);
    return holes;
  };
  EXPECT_EQ(holesInside(true), 0u);
  EXPECT_GT(holesInside(false), 61u * 61u / 4);
  // Exact silhouettes count only the discs themselves as covering: the gaps between them stay open (the
  // trade stated at SplatConfig::exact_silhouettes; clouds whose discs overlap have none).
  EXPECT_GT(holesInside(true, true), 61u * 61u / 4);
  const SurfelCloud overlapping = samplePlane(z, 0, 0.5 * 100 * spacing, spacing, 0.75, {90, 90, 90, 255});
  EXPECT_EQ(holesInside(true, true, &overlapping), 0u);
}

TEST(SurfelRenderer, BackfaceCullingAndPatchIds) {
  const Camera camera = frontCamera();
  SurfelCloud cloud;
  addSurfel(cloud, Vec3(-0.3, 0, 5), Vec3(0, 0, -1), 0.2, {255, 0, 0, 255});  // facing the camera
  addSurfel(cloud, Vec3(0.3, 0, 5), Vec3(0, 0, 1), 0.2, {0, 255, 0, 255});    // facing away
  Attribute& patch = cloud.attributes.add("patch_id", ScalarType::kInt32, 1, 2);
  patch.set(0, 7);
  patch.set(1, 9);
  RenderImages images;
  RenderStats stats;
  SurfelRenderer().render(cloud, camera, &images, nullptr, &stats);
  EXPECT_EQ(stats.splats, 2u);
  const size_t left = 100 * camera.width + 88, right = 100 * camera.width + 112;
  EXPECT_EQ(images.patch_id[left], 7);
  EXPECT_EQ(images.patch_id[right], 9);
  // Two-sided shading: the back face is lit like the front face (up to the specular term, whose view
  // direction differs between the two mirrored pixels), and the diffuse light reaches both.
  EXPECT_NEAR(int(images.color[right][1]), int(images.color[left][0]), 3);
  EXPECT_GT(int(images.color[left][0]), int(0.5 * 255));
  SplatConfig config;
  config.backface_culling = true;
  SurfelRenderer(config).render(cloud, camera, &images, nullptr, &stats);
  EXPECT_EQ(stats.splats, 1u);
  EXPECT_EQ(images.patch_id[right], -1);
}

/// Clips nothing; reverses the shading normal of the surfels at or after `first_flipped`.
class FlippingClipper : public FragmentClipper {
 public:
  explicit FlippingClipper(uint32_t first_flipped) : first_flipped_(first_flipped) {}
  bool needsClipping(uint32_t) const override { return false; }
  bool keepFragment(uint32_t, const Vec3&) const override { return true; }
  bool flipsNormal(uint32_t surfel) const override { return surfel >= first_flipped_; }

 private:
  uint32_t first_flipped_;
};

TEST(SurfelRenderer, FlippedNormalsOfComplementedPatchesShadeOnly) {
  // Left half: a plane with normals towards the camera; right half: its continuation whose stored normals
  // point away (a cavity wall of a complemented patch). Flipping makes the blended normal continuous.
  const Camera camera = frontCamera();
  SurfelCloud cloud = samplePlane(3.0, 0, 0.6, 0.02, 1.0, {200, 200, 200, 255});
  std::vector<size_t> left, right;
  for (size_t i = 0; i < cloud.size(); ++i) (cloud.positions[i].x() < 0 ? left : right).push_back(i);
  SurfelCloud right_cloud = cloud, left_cloud = cloud;
  left_cloud.select(left);
  right_cloud.select(right);
  for (Vec3& n : right_cloud.normals) n = -n;
  const uint32_t first_flipped = uint32_t(left_cloud.size());
  left_cloud.append(right_cloud);
  const FlippingClipper flipping(first_flipped), none(uint32_t(left_cloud.size()));
  RenderImages flipped, plain;
  SurfelRenderer renderer(unshaded());
  renderer.render(left_cloud, camera, &flipped, &flipping);
  renderer.render(left_cloud, camera, &plain, &none);
  size_t towards_camera = 0, cancelled = 0, checked = 0;
  for (uint32_t v = 70; v <= 130; ++v)
    for (uint32_t u = 60; u <= 140; ++u) {
      const size_t p = v * camera.width + u;
      ++checked;
      towards_camera += flipped.normal[p].z() < -0.999f;
      // Without flipping, the two halves' normals cancel at the seam (or point away on the right).
      cancelled += !(plain.normal[p].z() < -0.999f);
      EXPECT_FLOAT_EQ(flipped.depth[p], plain.depth[p]);  // geometry is unchanged
    }
  EXPECT_EQ(towards_camera, checked);
  EXPECT_GT(cancelled, checked / 3);
}

TEST(SurfelRenderer, LargeFrontSurfelDoesNotPullInSmallSurfelsBehind) {
  // One large surfel (tolerance 0.1 r = 0.1) in front of a dense plane 0.03 behind (tolerance 0.001) of
  // another patch at the same orientation: the plane lies within the big surfel's tolerance but not within
  // its own, so it must not blend (eps_z from both surfels, 3.2.1).
  const Camera camera = frontCamera();
  SurfelCloud cloud;
  addSurfel(cloud, Vec3(0, 0, 3.0), Vec3(0, 0, -1), 1.0, {255, 0, 0, 255});
  cloud.append(samplePlane(3.03, 0, 0.3, 0.01, 1.0, {0, 0, 255, 255}));
  RenderImages images;
  SurfelRenderer(unshaded()).render(cloud, camera, &images);
  size_t pure_front = 0, checked = 0;
  for (uint32_t v = 80; v <= 120; ++v)
    for (uint32_t u = 80; u <= 120; ++u) {
      const size_t p = v * camera.width + u;
      ++checked;
      pure_front += images.color[p] == Rgba{255, 0, 0, 255} && std::abs(images.depth[p] - 3.0f) < 1e-4f;
    }
  EXPECT_EQ(pure_front, checked);
}

}  // namespace
}  // namespace rc
