// Rendering of shell frames as rc_shell --render does it: a camera framing the rest bounding box
// (framingCamera), EWA splatting of the simulated surfels and PNG output. The covered pixels of a flat sheet
// match its projected area (bracketed by the splat footprint at the sheet's border), and follow the sheet
// when it moves.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "relaxed_connectivity/render/scene/framing_camera.h"
#include "relaxed_connectivity/render/splat/image_io.h"
#include "relaxed_connectivity/render/splat/surfel_renderer.h"
#include "relaxed_connectivity/shell/shell_scene_reader.h"
#include "relaxed_connectivity/shell/shell_simulation.h"

using namespace rc;

namespace {

constexpr double kHalfSize = 2.0;  // the sheet is [-2, 2]^2 at z = 0
constexpr double kSpacing = 0.1;   // surfel spacing; disc radius 0.75 spacing (the sheet source)
constexpr uint32_t kWidth = 320, kHeight = 240;

const char* kSheet =
    "source:\n"
    "  sheet: {size: [4, 4], spacing: 0.1}\n"
    "nodes: {spacing: 0.5}\n"
    "material: {stretch_stiffness: 100, bending_stiffness: 10}\n"
    "dynamics: {time_step: auto, gravity: [0, 0, 0]}\n"
    "frames: {count: 1, time: 0.1}\n"
    "output: {every: 0}\n";

/// Pixel area and perimeter of the square [-h, h]^2 (z = 0) moved by `offset`, projected by `camera`
/// (a planar quad projects to a quad: shoelace formula).
void projectedSquare(const Camera& camera, double h, const Vec3& offset, double* area, double* perimeter) {
  const std::array<Vec3, 4> corners = {Vec3(-h, -h, 0), Vec3(h, -h, 0), Vec3(h, h, 0), Vec3(-h, h, 0)};
  std::array<Eigen::Vector2d, 4> px;
  for (int i = 0; i < 4; ++i) {
    double u, v;
    EXPECT_TRUE(camera.project(camera.toCamera(corners[i] + offset), &u, &v));
    px[i] = Eigen::Vector2d(u, v);
  }
  *area = *perimeter = 0;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d& a = px[i];
    const Eigen::Vector2d& b = px[(i + 1) % 4];
    *area += 0.5 * (a.x() * b.y() - b.x() * a.y());
    *perimeter += (b - a).norm();
  }
  *area = std::abs(*area);
}

struct Coverage {
  size_t covered = 0;
  size_t background_colored = 0;  ///< covered pixels with the background colour, or uncovered ones without
};

Coverage coverageOf(const RenderImages& images, const Rgba& background) {
  Coverage c;
  for (size_t i = 0; i < images.weight.size(); ++i) {
    const bool covered = images.weight[i] > 0;
    const bool is_background = images.color[i] == background;
    c.covered += covered;
    c.background_colored += covered == is_background;
  }
  return c;
}

/// Covered pixels must lie between the projected sheet shrunk by half a pixel along its border (pixel-centre
/// sampling of the edge) and the sheet grown by the splat reach: discs of radius 0.75 spacing centred half a
/// spacing inside the border reach 0.25 spacing beyond it, and the EWA low-pass (variance 0.25 px^2, 2-sigma
/// cut-off) adds 1 px, plus half a pixel of edge sampling.
void expectSheetCoverage(const Camera& camera, const Vec3& offset, size_t covered, double* expected_area) {
  double area, perimeter, outer_area, outer_perimeter;
  projectedSquare(camera, kHalfSize, offset, &area, &perimeter);
  projectedSquare(camera, kHalfSize + 0.25 * kSpacing, offset, &outer_area, &outer_perimeter);
  const double lower = area - 0.5 * perimeter;
  const double upper = outer_area + 1.5 * outer_perimeter + M_PI * 1.5 * 1.5;
  EXPECT_GE(double(covered), lower) << "projected sheet area " << area << " px";
  EXPECT_LE(double(covered), upper) << "projected sheet area " << area << " px";
  std::printf("covered %zu px, bracket [%.0f, %.0f], projected sheet %.0f px\n", covered, lower, upper, area);
  *expected_area = area;
}

}  // namespace

TEST(ShellRender, FramedSheetCoversItsProjectedAreaAndFollowsTheMotion) {
  ShellScene scene = parseShellScene(kSheet, "sheet.yaml");
  scene.initial_velocity = Vec3(0, 0, 10);  // rigid lift (no gravity, no forces)
  ShellSimulation sim(scene);
  Vec3 lo, hi;
  ASSERT_TRUE(scene.surfels.bounds(&lo, &hi));
  const Camera camera = framingCamera(lo, hi, kWidth, kHeight);

  SplatConfig config;
  config.outputs = kOutputColor | kOutputWeight;
  const SurfelRenderer renderer(config);
  RenderImages images;
  renderer.render(sim.surfels(), camera, &images);

  // The written PNG has the requested size.
  const std::filesystem::path png =
      std::filesystem::temp_directory_path() / ("test_shell_render_" + std::to_string(::getpid()) + ".png");
  writePng(png.string(), images.color, images.width, images.height);
  uint32_t width = 0, height = 0;
  const std::vector<Rgba> read = readPng(png.string(), &width, &height);
  std::filesystem::remove(png);
  EXPECT_EQ(width, kWidth);
  EXPECT_EQ(height, kHeight);
  ASSERT_EQ(read.size(), size_t(kWidth) * kHeight);

  const Coverage rest = coverageOf(images, config.background);
  double rest_area = 0;
  expectSheetCoverage(camera, Vec3::Zero(), rest.covered, &rest_area);
  EXPECT_EQ(rest.background_colored, 0u);
  // The framed sheet fills a sizeable part of the image but lies inside it.
  EXPECT_GT(rest_area, 0.2 * kWidth * kHeight);
  EXPECT_LT(rest_area, 0.8 * kWidth * kHeight);

  // One frame: the sheet rises rigidly; the coverage follows the moved sheet.
  sim.advanceFrame();
  Vec3 offset = Vec3::Zero();
  for (size_t i = 0; i < scene.surfels.size(); ++i)
    offset += sim.surfels().positions[i] - scene.surfels.positions[i];
  offset /= double(scene.surfels.size());
  double rigid_error = 0;
  for (size_t i = 0; i < scene.surfels.size(); ++i)
    rigid_error =
        std::max(rigid_error, (sim.surfels().positions[i] - scene.surfels.positions[i] - offset).norm());
  ASSERT_LT(rigid_error, 1e-6);
  EXPECT_NEAR(offset.z(), 10 * sim.solver().time(), 1e-6);
  ASSERT_GT(offset.z(), 0.5);

  renderer.render(sim.surfels(), camera, &images);
  const Coverage moved = coverageOf(images, config.background);
  double moved_area = 0;
  expectSheetCoverage(camera, offset, moved.covered, &moved_area);
  EXPECT_EQ(moved.background_colored, 0u);
  // Lifted towards the camera's height, the sheet is seen more obliquely: it shrinks on screen more than
  // the coverage brackets are wide.
  EXPECT_LT(moved_area, 0.9 * rest_area);
  EXPECT_LT(double(moved.covered), 0.9 * double(rest.covered));
  std::printf("sheet coverage: rest %zu px (projected %.0f px), moved up %.3f: %zu px (projected %.0f px)\n",
              rest.covered, rest_area, offset.z(), moved.covered, moved_area);
}

TEST(ShellRender, FramingCameraRejectsAnEmptyBox) {
  EXPECT_THROW(framingCamera(Vec3::Zero(), Vec3::Zero(), 64, 48), std::invalid_argument);
  EXPECT_THROW(framingCamera(Vec3::Zero(), Vec3::Ones(), 64, 48, Vec3::Zero()), std::invalid_argument);
}
