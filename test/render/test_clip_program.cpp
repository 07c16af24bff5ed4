// ClipProgram: the per-frame compiled fragment test (screen-space affine tests, clip_program.h) against the
// per-fragment double-precision reference CsgClipper::keepFragment (Algorithms 4.2-4.4) on the thesis scenes,
// the row evaluation against the per-pixel one, the plane horizon inside a splat, and the limits that make
// the renderer fall back to the reference.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "relaxed_connectivity/render/csg/clip_inside_patch.h"
#include "relaxed_connectivity/render/csg/clip_program.h"
#include "relaxed_connectivity/render/scene/csg_scene_renderer.h"
#include "scene_test_support.h"

namespace rc {
namespace {

const std::string kSceneDir = sceneDir();

struct Agreement {
  size_t surfels = 0, compiled = 0, pixels = 0, disagree = 0, row_mismatch = 0, beyond_horizon = 0;
};

/// Every clipped surfel of the scene seen by `camera`: compiled test vs keepFragment at every pixel of its
/// box, and keepRow over whole rows vs keep() per pixel.
Agreement compareScene(const std::string& name, int camera_index) {
  const CsgScene scene = loadCsgScene(kSceneDir + name + ".yaml");
  CsgSceneRenderer renderer(scene);
  const Camera camera = resizedCamera(scene.cameras.at(camera_index).camera, 160, 120);
  RenderImages images;
  renderer.render(camera, 0, &images);  // finds the partners for this frame
  const CsgClipper& clipper = *renderer.clipper();
  const SurfelDiscs& discs = clipper.discs();
  const CameraFrame frame(camera);
  Agreement a;
  ClipProgram program;
  for (uint32_t i : clipper.edgeSurfels()) {
    if (!clipper.needsClipping(i)) continue;
    SplatRaster box;
    SplatGeometry geometry;
    const SplatSetup setup = setupEwaSplat(discs.centers[i], discs.normals[i], discs.axes1[i], discs.axes2[i],
                                           frame, EwaParams(), &box, &geometry);
    if (setup != SplatSetup::kDrawn) continue;
    ++a.surfels;
    ClipFrame clip_frame;
    if (!makeClipFrame(geometry, frame, box.x0, box.y0, box.x1, box.y1, &clip_frame)) continue;
    if (!clipper.compileClip(i, clip_frame, &program)) continue;
    ++a.compiled;
    for (int y = box.y0; y <= box.y1; ++y) {
      for (int x0 = box.x0; x0 <= box.x1; x0 += 64) {
        const int count = std::min(64, int(box.x1) - x0 + 1);
        const uint64_t all = count == 64 ? ~uint64_t(0) : (uint64_t(1) << count) - 1;
        const uint64_t row = program.keepRow(y - program.v0(), x0 - program.u0(), all);
        for (int b = 0; b < count; ++b) {
          const int x = x0 + b;
          const bool compiled = program.keep(x - program.u0(), y - program.v0());
          a.row_mismatch += compiled != bool((row >> b) & 1);
          const double d = clip_frame.sign * (clip_frame.d0 + clip_frame.d_u * (x - clip_frame.u0) +
                                              clip_frame.d_v * (y - clip_frame.v0));
          if (!(d > 0)) {  // the ray meets the plane behind the camera: never kept
            ++a.beyond_horizon;
            EXPECT_FALSE(compiled);
            continue;
          }
          const bool reference = clipper.keepFragment(i, fragmentWorldPoint(geometry, frame, x, y));
          ++a.pixels;
          a.disagree += compiled != reference;
        }
      }
    }
  }
  std::printf(
      "%-15s camera %d: %zu clipped surfels, %zu compiled, %zu pixels, %zu disagree, %zu beyond the "
      "horizon\n",
      name.c_str(), camera_index, a.surfels, a.compiled, a.pixels, a.disagree, a.beyond_horizon);
  return a;
}

void expectAgreement(const std::string& name, int camera_index) {
  SCOPED_TRACE(name);
  const Agreement a = compareScene(name, camera_index);
  EXPECT_GT(a.compiled, 0u);
  EXPECT_GE(a.compiled, a.surfels * 9 / 10);  // all but (near) edge-on ones
  EXPECT_GT(a.pixels, 1000u);
  EXPECT_EQ(a.row_mismatch, 0u);                   // row evaluation == per pixel
  EXPECT_LE(double(a.disagree), 1e-4 * a.pixels);  // float vs double: only exactly at decision boundaries
}

TEST(ClipProgram, AgreesWithPerFragmentTestOnSpikes) {
  expectAgreement("spikes", 0);
  expectAgreement("spikes", 1);
}

TEST(ClipProgram, AgreesWithPerFragmentTestOnIcosahedron) {
  expectAgreement("icosahedron", 0);
  expectAgreement("icosahedron", 1);
}

TEST(ClipProgram, AgreesWithPerFragmentTestOnCubeFemurTextureAndOrbit) {
  expectAgreement("cube_densities", 0);
  expectAgreement("femur", 0);
  expectAgreement("texture_square", 0);
  expectAgreement("orbit", 0);
}

/// A unit-square surfel in the plane z = 0 (normal +z) clipped by the half-space x < 0 of one partner.
struct HalfPlaneSetup {
  Vec3 centers[2] = {Vec3(0, 0, 0), Vec3(0, 0, 0)};
  Vec3 normals[2] = {Vec3(0, 0, 1), Vec3(1, 0, 0)};
  SplatGeometry geometry;
  HalfPlaneSetup() {
    geometry.center_world = centers[0];
    geometry.normal_world = normals[0];
    geometry.axis1_world = Vec3(1, 0, 0);
    geometry.axis2_world = Vec3(0, 1, 0);
  }
};

TEST(ClipProgram, HorizonInsideTheSplatIsNeverKept) {
  // Perspective camera 1 above a huge surfel, looking almost along it: the plane's horizon crosses the image.
  Camera camera = Camera::perspective(200, 100, 90 * M_PI / 180);
  camera.lookAt(Vec3(0, -1, 1), Vec3(0, 10, 0.8));
  const CameraFrame frame(camera);
  HalfPlaneSetup setup;
  Vec3 c_cam = frame.camera_R_world * setup.geometry.center_world + frame.camera_t_world;
  setup.geometry.center_u = frame.cx + frame.fx * c_cam.x() / c_cam.z();
  setup.geometry.center_v = frame.cy + frame.fy * c_cam.y() / c_cam.z();
  ClipFrame clip_frame;
  ASSERT_TRUE(makeClipFrame(setup.geometry, frame, 0, 0, 199, 99, &clip_frame));
  EXPECT_TRUE(clip_frame.horizon);
  ClipProgram program;
  program.reset(clip_frame);
  const uint32_t partner = 1;
  ASSERT_EQ(program.addGroup(&partner, 1, setup.centers, setup.normals), 0);
  program.pushGroup(0, /*inverted=*/true);  // A & !B: kept where x is not inside B (x >= 0)
  program.levelIntersection();
  ASSERT_TRUE(program.valid());
  size_t above = 0, kept_left = 0, kept_right = 0;
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 200; ++x) {
      Vec3 origin, direction;
      camera.pixelRay(x, y, &origin, &direction);
      const bool keep = program.keep(x - program.u0(), y - program.v0());
      if (!(direction.z() < 0)) {  // this ray never meets z = 0 in front of the camera
        ++above;
        EXPECT_FALSE(keep) << x << "," << y;
        continue;
      }
      const Vec3 hit = origin + direction * (-origin.z() / direction.z());
      if (std::abs(hit.x()) < 1e-3 * (1 + hit.norm())) continue;  // on the clip line
      EXPECT_EQ(keep, hit.x() >= 0) << x << "," << y;
      (hit.x() >= 0 ? kept_right : kept_left) += keep;
    }
  EXPECT_GT(above, 1000u);
  EXPECT_GT(kept_right, 1000u);
  EXPECT_EQ(kept_left, 0u);
}

TEST(ClipProgram, LimitsMakeTheProgramInvalid) {
  HalfPlaneSetup setup;
  Camera camera = Camera::perspective(64, 64, 60 * M_PI / 180);
  camera.lookAt(Vec3(0, 0, 3), Vec3::Zero());
  const CameraFrame frame(camera);
  setup.geometry.center_u = setup.geometry.center_v = 31.5;
  ClipFrame clip_frame;
  ASSERT_TRUE(makeClipFrame(setup.geometry, frame, 0, 0, 63, 63, &clip_frame));
  EXPECT_FALSE(clip_frame.horizon);
  ClipProgram program;
  // More partners in one patch than the concavity bit rows hold.
  std::vector<Vec3> centers(40, Vec3(0.1, 0, 0)), normals(40, Vec3(1, 0, 0));
  std::vector<uint32_t> ids(40);
  for (uint32_t k = 0; k < 40; ++k) ids[k] = k;
  program.reset(clip_frame);
  EXPECT_EQ(program.addGroup(ids.data(), 40, centers.data(), normals.data()), -1);
  EXPECT_FALSE(program.valid());
  // A non-finite partner.
  centers[0] = Vec3(std::nan(""), 0, 0);
  program.reset(clip_frame);
  EXPECT_EQ(program.addGroup(ids.data(), 1, centers.data(), normals.data()), -1);
  EXPECT_FALSE(program.valid());
  // Unbalanced code.
  program.reset(clip_frame);
  const uint32_t one = 1;
  ASSERT_EQ(program.addGroup(&one, 1, setup.centers, setup.normals), 0);
  program.pushGroup(0, false);
  EXPECT_FALSE(program.valid());  // a value left on the stack
  program.levelUnion();
  EXPECT_TRUE(program.valid());
  // Edge-on surfels have no pixel map.
  SplatGeometry edge_on = setup.geometry;
  edge_on.edge_on = true;
  EXPECT_FALSE(makeClipFrame(edge_on, frame, 0, 0, 63, 63, &clip_frame));
}

TEST(ClipProgram, TwoClosestRuleMatchesInsidePatchFromSurfels) {
  // A surfel in z = 0 seen from above; partner patch of two surfels forming a concave and a convex corner.
  HalfPlaneSetup setup;
  Camera camera = Camera::orthographic(96, 96, 2.4);
  camera.lookAt(Vec3(0, 0, 3), Vec3::Zero());
  const CameraFrame frame(camera);
  setup.geometry.center_u = setup.geometry.center_v = 47.5;
  ClipFrame clip_frame;
  ASSERT_TRUE(makeClipFrame(setup.geometry, frame, 0, 0, 95, 95, &clip_frame));
  for (const bool concave : {true, false}) {
    SCOPED_TRACE(concave ? "concave" : "convex");
    const double s = concave ? 1 : -1;
    // (Off the pixel grid, so that no pixel's point lies exactly on a partner plane.)
    const Vec3 centers[2] = {Vec3(-0.3031, 0.2017, 0), Vec3(0.2983, 0.2011, 0)};
    const Vec3 normals[2] = {Vec3(s, 1, 0).normalized(), Vec3(-s, 1, 0).normalized()};
    ASSERT_EQ(surfelsConcave(centers[0], normals[0], centers[1], normals[1]), concave);
    ClipProgram program;
    program.reset(clip_frame);
    const uint32_t ids[2] = {0, 1};
    ASSERT_EQ(program.addGroup(ids, 2, centers, normals), 0);
    program.pushGroup(0, false);
    program.levelIntersection();  // A & B
    ASSERT_TRUE(program.valid());
    size_t disagree = 0, kept = 0;
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 96; ++x) {
        const Vec3 point = fragmentWorldPoint(setup.geometry, frame, x, y);
        const bool reference = insidePatchFromSurfels(point, ids, 2, centers, normals) == Tri::kTrue;
        const bool compiled = program.keep(x - program.u0(), y - program.v0());
        disagree += reference != compiled;
        kept += compiled;
      }
    EXPECT_EQ(disagree, 0u);
    EXPECT_GT(kept, 1000u);
    EXPECT_LT(kept, 96u * 96u - 1000u);
  }
}

}  // namespace
}  // namespace rc
