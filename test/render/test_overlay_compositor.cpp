#include "relaxed_connectivity/render/splat/overlay_compositor.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rc {
namespace {

/// Surfels of colour `color` on the square [-half, half]^2 at height z (normals +z), spacing h.
SurfelCloud square(double half, double h, double z, Rgba color) {
  SurfelCloud c;
  const int n = int(std::round(half / h));
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      c.positions.push_back(Vec3(i * h, j * h, z));
      c.normals.push_back(Vec3::UnitZ());
      c.radii.push_back(0.8 * h);
      c.colors.push_back(color);
    }
  return c;
}

/// Looking straight down at the board z = 0 from 1 m.
Camera topCamera() {
  Camera camera = Camera::perspective(200, 200, 40 * M_PI / 180);
  camera.lookAt(Vec3(0, 0, 1), Vec3::Zero(), Vec3::UnitY());
  return camera;
}

size_t pixelAt(const Camera& camera, const Vec3& world) {
  double u, v;
  EXPECT_TRUE(camera.project(camera.toCamera(world), &u, &v));
  return size_t(std::lround(v)) * camera.width + size_t(std::lround(u));
}

struct Scene {
  Scene() : camera(topCamera()) {
    SplatConfig config;
    config.outputs = kOutputColor | kOutputDepth;
    config.shading = false;
    SurfelRenderer(config).render(square(0.3, 0.005, 0, Rgba{200, 200, 200, 255}), camera, &base);
  }
  Camera camera;
  RenderImages base;
};

OverlayOptions unshaded() {
  OverlayOptions options;
  options.splat.shading = false;
  return options;
}

TEST(OverlayCompositor, OverlayInFrontIsDrawnBehindIsHidden) {
  Scene s;
  OverlayOptions options = unshaded();
  options.shadow = false;
  const OverlayCompositor compositor(options);
  std::vector<Rgba> color;
  OverlayStats stats;
  const SurfelCloud above = square(0.02, 0.002, 0.05, Rgba{255, 0, 0, 255});
  compositor.composite(above, s.camera, s.base, &color, &stats);
  EXPECT_EQ(color[pixelAt(s.camera, Vec3(0, 0, 0.05))], (Rgba{255, 0, 0, 255}));
  EXPECT_EQ(color[pixelAt(s.camera, Vec3(0.1, 0.1, 0))], s.base.color[pixelAt(s.camera, Vec3(0.1, 0.1, 0))]);
  // The patch covers about (0.044 m * fx / 0.95 m)^2 = 163 pixels (fx = 100 px / tan 20 deg), plus its rim.
  EXPECT_GT(stats.overlay_pixels, 140u);
  EXPECT_LT(stats.overlay_pixels, 260u);

  const SurfelCloud below = square(0.02, 0.002, -0.05, Rgba{255, 0, 0, 255});
  compositor.composite(below, s.camera, s.base, &color, &stats);
  EXPECT_EQ(color, s.base.color);
  EXPECT_EQ(stats.overlay_pixels, 0u);

  compositor.composite(SurfelCloud(), s.camera, s.base, &color, &stats);
  EXPECT_EQ(color, s.base.color);
}

// The shadow falls along the light: straight down below the overlay (hidden by it from this camera, so the
// light comes in at 45 degrees here) and is darkened by shadow_strength.
TEST(OverlayCompositor, ShadowFallsAlongTheLight) {
  Scene s;
  OverlayOptions options = unshaded();
  options.light_direction = Vec3(1, 0, -1);  // travels +x and down: the shadow lies 5 cm towards +x
  options.shadow_length = 0.2;
  const OverlayCompositor compositor(options);
  std::vector<Rgba> color;
  OverlayStats stats;
  compositor.composite(square(0.02, 0.002, 0.05, Rgba{255, 0, 0, 255}), s.camera, s.base, &color, &stats);
  const size_t shadow = pixelAt(s.camera, Vec3(0.05, 0, 0)), lit = pixelAt(s.camera, Vec3(-0.05, 0, 0));
  EXPECT_EQ(color[lit], s.base.color[lit]);
  EXPECT_NEAR(color[shadow][0], (1 - options.shadow_strength) * s.base.color[shadow][0], 1.0);
  EXPECT_GT(stats.shadow_pixels, 110u);  // (0.044 m * fx / 1 m)^2 = 146 pixels
  EXPECT_LT(stats.shadow_pixels, 220u);

  options.shadow_length = 0.02;  // the board lies farther below the overlay than shadows reach
  const OverlayCompositor short_shadow(options);
  short_shadow.composite(square(0.02, 0.002, 0.05, Rgba{255, 0, 0, 255}), s.camera, s.base, &color, &stats);
  EXPECT_EQ(stats.shadow_pixels, 0u);
}

// An overlay partly outside the image, one crossing the near plane, and bad input.
TEST(OverlayCompositor, EdgesOfTheImageAndBadInput) {
  Scene s;
  const OverlayCompositor compositor(unshaded());
  std::vector<Rgba> color;
  OverlayStats stats;
  SurfelCloud off_edge = square(0.1, 0.004, 0.05, Rgba{0, 0, 255, 255});
  for (Vec3& p : off_edge.positions) p.x() += 0.4;  // mostly off the right edge
  compositor.composite(off_edge, s.camera, s.base, &color, &stats);
  EXPECT_GT(stats.overlay_pixels, 100u);
  EXPECT_EQ(color[size_t(100) * s.camera.width + s.camera.width - 1], (Rgba{0, 0, 255, 255}));
  SurfelCloud at_the_eye =
      square(0.01, 0.002, 0.999, Rgba{0, 255, 0, 255});  // beside and behind the near plane
  EXPECT_NO_THROW(compositor.composite(at_the_eye, s.camera, s.base, &color, &stats));
  SurfelCloud no_radii = square(0.01, 0.002, 0.05, Rgba{0, 255, 0, 255});
  no_radii.radii.clear();
  EXPECT_THROW(compositor.composite(no_radii, s.camera, s.base, &color, &stats), std::invalid_argument);
  RenderImages no_depth = s.base;
  no_depth.depth.clear();
  EXPECT_THROW(compositor.composite(SurfelCloud(), s.camera, no_depth, &color, &stats),
               std::invalid_argument);
  OverlayOptions bad;
  bad.shadow_strength = 2;
  EXPECT_THROW(OverlayCompositor{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace rc
