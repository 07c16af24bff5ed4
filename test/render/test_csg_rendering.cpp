// Integration: the thesis scenes (config/scenes) rendered with CSG splatting (4.2) against the analytic CSG
// ray caster. Depth and patch id must agree except next to edges; the icosahedron of one surfel per face must
// be covered completely with edges in place; the texture square must have a sharp colour step over smooth
// normals.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "relaxed_connectivity/render/scene/csg_scene_renderer.h"
#include "scene_test_support.h"

namespace rc {
namespace {

const std::string kSceneDir = sceneDir();
constexpr uint32_t kWidth = 320, kHeight = 240;

Camera smallCamera(const Camera& c) {
  return resizedCamera(c, kWidth, kHeight);
}

/// Pixels within `radius` (Chebyshev) of an analytic edge: a patch-id change (silhouettes included) or a
/// depth jump of more than 5% between 4-neighbours.
std::vector<uint8_t> edgeMask(const AnalyticImages& a, int radius) {
  const int w = int(a.width), h = int(a.height);
  std::vector<uint8_t> edge(size_t(w) * h, 0), near(size_t(w) * h, 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      for (const auto& d : {std::pair<int, int>{1, 0}, {0, 1}}) {
        const int xn = x + d.first, yn = y + d.second;
        if (xn >= w || yn >= h) continue;
        const size_t j = size_t(yn) * w + xn;
        const bool jump = a.patch_id[i] != a.patch_id[j] ||
                          (a.patch_id[i] >= 0 && std::abs(a.depth[i] - a.depth[j]) > 0.05 * a.depth[i]);
        if (jump) edge[i] = edge[j] = 1;
      }
    }
  }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!edge[size_t(y) * w + x]) continue;
      for (int dy = -radius; dy <= radius; ++dy)
        for (int dx = -radius; dx <= radius; ++dx) {
          const int xn = x + dx, yn = y + dy;
          if (xn >= 0 && yn >= 0 && xn < w && yn < h) near[size_t(yn) * w + xn] = 1;
        }
    }
  return near;
}

struct Comparison {
  size_t pixels = 0, mismatches = 0, mismatches_away_from_edges = 0, covered = 0;
  size_t coverage = 0, patch = 0, depth = 0;  ///< mismatch kinds
  size_t displaced = 0;  ///< mismatches that no analytic pixel within 1 px explains (edges off by > 1 px)
};

/// Does the rendered pixel i agree with the analytic image at pixel j?
bool agrees(const RenderImages& r, size_t i, const AnalyticImages& a, size_t j) {
  const bool hit_a = a.patch_id[j] >= 0, hit_r = r.weight[i] > 0;
  if (hit_a != hit_r) return false;
  return !hit_a || (r.patch_id[i] == a.patch_id[j] && std::abs(r.depth[i] - a.depth[j]) <= 0.01 * a.depth[j]);
}

/// A pixel mismatches if coverage or patch id differ or the depth is off by more than 1%.
Comparison compare(const RenderImages& r, const AnalyticImages& a) {
  const std::vector<uint8_t> near = edgeMask(a, 2);
  Comparison c;
  c.pixels = r.depth.size();
  for (size_t i = 0; i < c.pixels; ++i) {
    const bool hit_a = a.patch_id[i] >= 0, hit_r = r.weight[i] > 0;
    c.covered += hit_a;
    bool bad = hit_a != hit_r;
    c.coverage += bad;
    if (!bad && hit_a) {
      const bool patch = r.patch_id[i] != a.patch_id[i];
      const bool depth = std::abs(r.depth[i] - a.depth[i]) > 0.01 * a.depth[i];
      c.patch += patch;
      c.depth += depth && !patch;
      bad = patch || depth;
    }
    c.mismatches += bad;
    c.mismatches_away_from_edges += bad && !near[i];
    if (bad) {
      const int x = int(i % r.width), y = int(i / r.width);
      bool explained = false;
      for (int dy = -1; dy <= 1 && !explained; ++dy)
        for (int dx = -1; dx <= 1 && !explained; ++dx) {
          const int xn = x + dx, yn = y + dy;
          if (xn >= 0 && yn >= 0 && xn < int(r.width) && yn < int(r.height))
            explained = agrees(r, i, a, size_t(yn) * r.width + xn);
        }
      c.displaced += !explained;
    }
  }
  return c;
}

// Issue #3 asks for < 0.5% of pixels mismatching, all next to edges: `displaced` = fraction of pixels not
// explained by an analytic pixel within 1 px, `away` = fraction of mismatches more than 2 px from any
// analytic edge or silhouette.
struct MismatchBounds {
  double displaced = 0.005;
  double away = 0.0005;
};

void expectMatchesAnalytic(const std::string& scene_name, double t = 0, MismatchBounds bounds = {},
                           bool backface_culling = false) {
  SCOPED_TRACE(scene_name + (backface_culling ? " (back faces culled)" : ""));
  const CsgScene scene = loadCsgScene(kSceneDir + scene_name + ".yaml");
  CsgSceneRenderOptions options;
  options.splat.shading = false;
  options.splat.backface_culling = backface_culling;
  CsgSceneRenderer renderer(scene, options);
  const Camera camera = smallCamera(scene.cameras[0].camera);
  RenderImages images;
  CsgSceneFrameStats stats;
  renderer.render(camera, t, &images, &stats);
  const AnalyticImages reference = castImage(scene.analyticCaster(t), camera);
  const Comparison c = compare(images, reference);
  std::printf(
      "%-16s t=%.2f covered %6zu mismatches %5zu (%.3f%%; coverage %zu, patch %zu, depth %zu), more than "
      "1 px off %zu (%.3f%%), more than 2 px from an edge %zu, edge surfels %zu\n",
      scene_name.c_str(), t, c.covered, c.mismatches, 100.0 * c.mismatches / c.pixels, c.coverage, c.patch,
      c.depth, c.displaced, 100.0 * c.displaced / c.pixels, c.mismatches_away_from_edges, stats.edge_surfels);
  EXPECT_GT(c.covered, c.pixels / 10);
  // Edge pixels may go to either side (the rendered patch id is that of the largest weight): a pixel that an
  // analytic pixel within 1 px explains is an edge placed within 1 px. The rest stays below 0.5%...
  EXPECT_LT(double(c.displaced), bounds.displaced * c.pixels);
  // ... and every mismatch lies within 2 px of an analytic edge or silhouette, up to a few silhouette pixels.
  EXPECT_LE(double(c.mismatches_away_from_edges), bounds.away * c.pixels);
}

TEST(CsgRendering, CubeWithOneTwentyFiveAndNineHundredSurfelFaces) {
  // At the target since the fuzzy depth test takes eps_z from both the front and the incoming surfel and
  // faces of other patches behind do not blend (0 px more than 1 px off measured).
  expectMatchesAnalytic("cube_densities");
}

TEST(CsgRendering, ThinSpikesOfASphereMinusSpheres) {
  // 0.009% more than 1 px off with exact silhouettes (0.12% with the filtered footprint, whose low-pass
  // filter dilated silhouettes by up to 1 px; 0.63% with a low-pass variance of 1 px^2).
  expectMatchesAnalytic("spikes", 0, {0.0005, 0.0005});
}

TEST(CsgRendering, EllipsoidMinusTwoSpheres) {
  // 0.014% more than 1 px off with exact silhouettes (0.15% with the filtered footprint; 1.17% with the 2 px
  // wider splats of a 1 px^2 low-pass: a dilated silhouette, and tangent planes of grazing surfels
  // extrapolated in front of the surface).
  expectMatchesAnalytic("femur", 0, {0.0005, 0.0005});
}

// Back-face culling is correct for intersections and unions (all surfaces face out) and refused for
// differences: the walls of a subtracted solid are complemented patches, and culling them by their reversed
// normal still left the rims wrong (measured before the refusal: 5.5 % of the pixels of spikes more than 1 px
// off, 1.3 % of femur's, against 0.12 % and 0.15 % two-sided, then with the filtered footprint).
TEST(CsgRendering, BackFaceCullingWorksForIntersectionsAndIsRefusedForDifferences) {
  expectMatchesAnalytic("cube_densities", 0, {}, true);
  for (const char* name : {"spikes", "femur", "orbit"}) {
    const CsgScene scene = loadCsgScene(kSceneDir + name + ".yaml");
    EXPECT_TRUE(scene.csgTree().hasComplementedPatches()) << name;
    CsgSceneRenderOptions options;
    options.splat.backface_culling = true;
    CsgSceneRenderer renderer(scene, options);
    RenderImages images;
    try {
      renderer.render(smallCamera(scene.cameras[0].camera), 0, &images, nullptr);
      ADD_FAILURE() << name << ": rendered with back-face culling";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("backface_culling with complemented CSG patches"),
                std::string::npos)
          << e.what();
    }
  }
  EXPECT_FALSE(loadCsgScene(kSceneDir + "cube_densities.yaml").csgTree().hasComplementedPatches());
}

TEST(CsgRendering, OrbitingSphereThroughABoxEveryFrame) {
  for (double t : {0.0, 0.7, 1.5}) expectMatchesAnalytic("orbit", t);
}

TEST(CsgRendering, IcosahedronFromTwentySurfels) {
  const CsgScene scene = loadCsgScene(kSceneDir + "icosahedron.yaml");
  CsgSceneRenderOptions options;
  options.splat.shading = false;
  CsgSceneRenderer renderer(scene, options);
  for (const CsgSceneCamera& sc : scene.cameras) {
    SCOPED_TRACE(sc.name);
    const Camera camera = smallCamera(sc.camera);
    RenderImages images;
    renderer.render(camera, 0, &images);
    const AnalyticImages reference = castImage(scene.analyticCaster(), camera);
    const std::vector<uint8_t> near_analytic_edge = edgeMask(reference, 1);
    size_t silhouette_pixels = 0, uncovered = 0, rendered_edge = 0, misplaced_edge = 0, outside = 0;
    const int w = kWidth, h = kHeight;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        if (reference.patch_id[i] >= 0) {
          ++silhouette_pixels;
          uncovered += !(images.weight[i] > 0);
        } else {
          outside += images.weight[i] > 0 && !near_analytic_edge[i];
        }
        if (x + 1 < w && images.patch_id[i] != images.patch_id[i + 1]) {
          ++rendered_edge;
          misplaced_edge += !near_analytic_edge[i];
        }
        if (y + 1 < h && images.patch_id[i] != images.patch_id[i + w]) {
          ++rendered_edge;
          misplaced_edge += !near_analytic_edge[i];
        }
      }
    }
    std::printf(
        "icosahedron %-6s: %zu analytic pixels, %zu uncovered, %zu rendered edge pixels, %zu misplaced, "
        "%zu outside\n",
        sc.name.c_str(), silhouette_pixels, uncovered, rendered_edge, misplaced_edge, outside);
    EXPECT_GT(silhouette_pixels, 10000u);
    EXPECT_EQ(uncovered, 0u);
    EXPECT_GT(rendered_edge, 500u);
    // No edge pixel more than 1 px from an analytic edge (edge-on faces at the silhouette are clipped at
    // the ray/plane point, see fragmentWorldPoint).
    EXPECT_EQ(misplaced_edge, 0u);
    EXPECT_EQ(outside, 0u);
  }
}

TEST(CsgRendering, TextureSquareSharpColourSmoothNormals) {
  const CsgScene scene = loadCsgScene(kSceneDir + "texture_square.yaml");
  const TextureSquare& square = scene.texture_squares.at(0);
  const Camera camera = smallCamera(scene.cameras[0].camera);
  const AnalyticImages reference = castImage(scene.analyticGeometryCaster(), camera);
  // Analytic colour class per pixel (1 inside the square) and the pixels next to its border.
  const int w = kWidth, h = kHeight;
  std::vector<int> inside(size_t(w) * h, -1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (reference.patch_id[i] < 0) continue;
      Vec3 origin, dir;
      camera.pixelRay(x, y, &origin, &dir);
      const Vec3 forward = camera.world_T_camera.linear().col(2);
      const double z0 = (origin - camera.world_T_camera.translation()).dot(forward);
      inside[i] = square.contains(origin + dir * ((reference.depth[i] - z0) / dir.dot(forward)));
    }
  // Is a pixel with a different class within r pixels? silhouette: background / image border counts too.
  auto within = [&](int x, int y, int r, bool silhouette) {
    const int c = inside[size_t(y) * w + x];
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        const int xn = x + dx, yn = y + dy;
        const int cn = (xn < 0 || yn < 0 || xn >= w || yn >= h) ? -1 : inside[size_t(yn) * w + xn];
        if (silhouette ? cn < 0 : (cn >= 0 && cn != c)) return true;
      }
    return false;
  };
  auto colourStats = [&](bool csg, size_t* mixed, size_t* wrong_away, double* max_normal_deg_border,
                         size_t* border_pixels) {
    CsgSceneRenderOptions options;
    options.csg = csg;
    options.splat.shading = false;
    CsgSceneRenderer renderer(scene, options);
    RenderImages images;
    renderer.render(camera, 0, &images);
    *mixed = *wrong_away = *border_pixels = 0;
    *max_normal_deg_border = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        if (inside[i] < 0 || !(images.weight[i] > 0)) continue;
        const int green = images.color[i][1];  // square 40, ball 235
        const bool is_mixed = green > 60 && green < 215;
        const int rendered = green <= 60 ? 1 : (green >= 215 ? 0 : -1);
        *mixed += is_mixed;
        if (rendered != inside[i] && !within(x, y, 1, false) && !within(x, y, 2, true)) ++*wrong_away;
        if (within(x, y, 2, false) && !within(x, y, 3, true)) {
          // Near the square's border (away from the silhouette): the normal is the sphere's.
          const Eigen::Vector3f n = images.normal[i];
          const double cosine = double(n.normalized().dot(reference.normal[i]));
          *max_normal_deg_border =
              std::max(*max_normal_deg_border, std::acos(std::min(1.0, cosine)) * 180 / M_PI);
          ++*border_pixels;
        }
      }
  };
  size_t mixed, wrong_away, border_pixels;
  double max_normal_deg;
  colourStats(true, &mixed, &wrong_away, &max_normal_deg, &border_pixels);
  size_t blurred_mixed, blurred_wrong, blurred_border;
  double blurred_normal_deg;
  colourStats(false, &blurred_mixed, &blurred_wrong, &blurred_normal_deg, &blurred_border);
  std::printf(
      "texture square: mixed-colour pixels %zu (plain splatting %zu), wrong class >1 px from the border %zu "
      "(plain %zu), max normal error near the border %.2f deg over %zu px\n",
      mixed, blurred_mixed, wrong_away, blurred_wrong, max_normal_deg, border_pixels);
  EXPECT_EQ(wrong_away, 0u);
  EXPECT_LT(mixed * 10, blurred_mixed);  // the step is sharp where plain splatting blurs it
  EXPECT_GT(border_pixels, 200u);
  EXPECT_LT(max_normal_deg, 3.0);
}

}  // namespace
}  // namespace rc
