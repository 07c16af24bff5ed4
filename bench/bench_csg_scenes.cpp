// CSG splatting performance on the scenes of thesis chapter 4 (Table 4.1) at 1280x720, next to the thesis
// numbers (Pentium 4, 3 GHz + GeForce FX5900, hardware/software renderer). Target: 30 fps.
//
// Table 1 ("static"): surfels, edge surfels, two edge-pixel counts (defined below), frame times (median, min
// and max of the timed frames) with the clipping partners searched once (static geometry), and the same frame
// with Algorithms 4.2-4.4 evaluated in double per fragment (the peer of the compiled clip tests).
// Table 2 ("partners in every frame"): the thesis' dynamic case, where the clipping partners are recomputed
// in every timed frame: (a) the edge surfels' partners by the clip buffer (Algorithm 4.1, the thesis'
// per-frame method), classification kept; (b) classification of all surfels (4.1.2) plus the edge surfels'
// partners (spatial index) in every frame, which is what moving patches need. The orbit scene really moves in
// (b).
//
// Each scene is marked as the thesis' model (same construction and surfel count) or as a procedural stand-in,
// with its surfel count next to the thesis' count. Edge pixels: Table 4.1 counts "visible edge pixels" ("the
// number of viewport pixels covered by edge surfels", 4.4) without saying how a pixel is attributed or at
// which resolution; both counts printed here are visible pixels of our 1280x720 images, so they are not the
// thesis' numbers and no ratio to them is formed.
//   bench_csg_scenes [SCENE_DIR] [--clip-buffer] [--frames N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "relaxed_connectivity/render/scene/csg_scene_renderer.h"

namespace {

using Clock = std::chrono::steady_clock;

struct SceneInfo {
  const char* figure;
  const char* scene;
  const char* model;          // thesis model or procedural stand-in, and how it differs
  size_t thesis_surfels;      // Table 4.1 (0: not in the table)
  const char* thesis_counts;  // Table 4.1: # surfels, # edge surfels (or why there are none)
  const char* thesis_frames;  // Table 4.1: # edge pixels and FPS at the two zoom levels
};

// Table 4.1 of the thesis, quoted; the model column says what our scene file is.
const SceneInfo kScenes[] = {
    {"4.9", "spikes",
     "procedural stand-in: the Fig. 4.9(d) construction (unit sphere minus six spheres), our own sampling",
     1871, "1,871 surfels, 972 edge surfels", "7,189 edge px 9.09 fps; 33,404 edge px 2.63 fps"},
    {"4.10", "icosahedron", "thesis model: 20 half-spaces, one surfel per face", 20,
     "20 surfels, 20 edge surfels", "8,763 edge px 8.3 fps; 47,469 edge px 2.27 fps"},
    {"4.8", "femur", "procedural stand-in: an ellipsoid for the scanned femoral neck, minus two spheres",
     116650, "116,650 surfels, 2,272 edge surfels", "12,234 edge px 5.55 fps; 69,450 edge px 2.0 fps"},
    {"4.7", "cube_densities", "thesis construction: cube faces with 1, 25 and 900 surfels", 0,
     "not in Table 4.1", "-"},
    {"4.6", "texture_square", "thesis construction: a square painted on a sphere (texture discontinuities)",
     0, "not in Table 4.1", "-"},
    {"-", "orbit", "not in the thesis: box minus a sphere orbiting through it (moving patch)", 0, "-", "-"},
};

struct Spread {
  double median = 0, min = 0, max = 0;
};

Spread spreadOf(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return {v[v.size() / 2], v.front(), v.back()};
}

/// Frame times of one scene camera over `frames` timed frames (after a warm-up frame).
struct FrameTimes {
  Spread total;
  double classify = 0, partners = 0, setup = 0, splat = 0;  // medians
  rc::CsgSceneFrameStats stats;                             // of the last frame
};

struct Series {
  std::vector<double> total, classify, partners, setup, splat;
  FrameTimes finish(const rc::CsgSceneFrameStats& stats) const {
    FrameTimes t;
    t.total = spreadOf(total);
    t.classify = spreadOf(classify).median;
    t.partners = spreadOf(partners).median;
    t.setup = spreadOf(setup).median;
    t.splat = spreadOf(splat).median;
    t.stats = stats;
    return t;
  }
  void add(const rc::CsgSceneFrameStats& s) {
    total.push_back(s.total_ms);
    classify.push_back(s.classify_ms);
    partners.push_back(s.partners_ms);
    setup.push_back(s.render.setup_ms + s.render.bin_ms);
    splat.push_back(s.visibility_ms + s.accumulate_ms + s.shade_ms);
  }
};

/// Through CsgSceneRenderer. moving = false renders the scene at t = 0 in every frame (static geometry: the
/// spatial partners are searched once and kept; the clip buffer method searches in every frame); moving =
/// true advances a dynamic scene by 1/30 s per frame (motion, classification and partners in every frame).
FrameTimes measureScene(const rc::CsgScene& scene, const rc::Camera& camera,
                        const rc::CsgSceneRenderOptions& options, int frames, bool moving,
                        rc::RenderImages* images, std::unique_ptr<rc::CsgSceneRenderer>* keep = nullptr) {
  auto renderer = std::make_unique<rc::CsgSceneRenderer>(scene, options);
  Series series;
  rc::CsgSceneFrameStats stats;
  renderer->render(camera, 0, images, &stats);  // warm-up (and the one partner search of a static scene)
  for (int f = 0; f < frames; ++f) {
    renderer->render(camera, moving ? (f + 1) / 30.0 : 0.0, images, &stats);
    series.add(stats);
  }
  if (keep) *keep = std::move(renderer);
  return series.finish(stats);
}

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// Static geometry, but the classification of all surfels (4.1.2, partners of all surfels) and the edge
/// surfels' partners (4.2.1) recomputed in every frame, as CsgSceneRenderer does after a motion.
FrameTimes measureReclassify(const rc::CsgScene& scene, const rc::Camera& camera,
                             const rc::CsgSceneRenderOptions& options, int frames, rc::RenderImages* images) {
  rc::CsgClipper clipper(scene.surfels, scene.csgTree(), options.clipper);
  rc::SurfelRenderer renderer(options.splat);
  Series series;
  rc::CsgSceneFrameStats s;
  for (int f = -1; f < frames; ++f) {  // frame -1: warm-up
    s = rc::CsgSceneFrameStats();
    const auto t0 = Clock::now();
    clipper.classify();
    s.classify_ms = msSince(t0);
    const auto tp = Clock::now();
    clipper.update(camera);
    s.partners_ms = msSince(tp);
    renderer.render(scene.surfels, camera, images, &clipper, &s.render);
    s.total_ms = msSince(t0);
    s.visibility_ms = s.render.visibility_ms;
    s.accumulate_ms = s.render.accumulate_ms;
    s.shade_ms = s.render.shade_ms;
    s.surfels = scene.surfels.size();
    s.edge_surfels = clipper.edgeSurfels().size();
    if (f >= 0) series.add(s);
  }
  return series.finish(s);
}

/// Visible pixels showing a kept fragment of an edge surfel: pixels inside the surfel's disc (ray-plane
/// intersection, exact elliptical footprint, no filter) where the clipper keeps the fragment (Algorithm 4.2
/// in double) and the rendered depth is within the surfel radius of the fragment's depth. A subset of
/// countEdgePixels (footprint circle, clipped-away parts included).
size_t countShownEdgePixels(const rc::SurfelCloud& cloud, const rc::CsgClipper& clipper,
                            const rc::Camera& camera, const rc::RenderImages& images) {
  std::vector<uint8_t> mark(size_t(images.width) * images.height, 0);
  const Eigen::Isometry3d camera_T_world = camera.world_T_camera.inverse();
  const rc::SurfelDiscs& discs = clipper.discs();
  for (uint32_t i : clipper.edgeSurfels()) {
    if (!clipper.needsClipping(i) || !clipper.isVisible(i)) continue;
    const rc::Vec3 p = camera_T_world * cloud.positions[i];
    double u, v;
    if (!camera.project(p, &u, &v)) continue;
    const double r = discs.radii[i];
    const double r_px = camera.projection == rc::Camera::Projection::kPerspective ? r * camera.fx / p.z()
                                                                                  : r * camera.ortho_scale;
    const rc::Vec3 &c = discs.centers[i], &n = discs.normals[i], &t1 = discs.axes1[i], &t2 = discs.axes2[i];
    const int x0 = std::max(0, int(std::floor(u - r_px))),
              x1 = std::min(int(images.width) - 1, int(std::ceil(u + r_px)));
    const int y0 = std::max(0, int(std::floor(v - r_px))),
              y1 = std::min(int(images.height) - 1, int(std::ceil(v + r_px)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const size_t k = size_t(y) * images.width + x;
        if (mark[k] || !std::isfinite(images.depth[k])) continue;
        rc::Vec3 origin, dir;
        camera.pixelRay(x, y, &origin, &dir);
        const double denom = n.dot(dir);
        if (std::abs(denom) < 1e-12) continue;
        const rc::Vec3 xw = origin + (n.dot(c - origin) / denom) * dir;
        const rc::Vec3 d = xw - c;
        const double a = d.dot(t1) / t1.squaredNorm(), b = d.dot(t2) / t2.squaredNorm();
        if (a * a + b * b > 1) continue;
        if (std::abs(double(images.depth[k]) - (camera_T_world * xw).z()) > r) continue;
        if (clipper.keepFragment(i, xw)) mark[k] = 1;
      }
  }
  size_t count = 0;
  for (uint8_t m : mark) count += m;
  return count;
}

rc::Camera at1280x720(rc::Camera camera) {
  const double s = 1280.0 / camera.width;
  camera.width = 1280;
  camera.height = 720;
  camera.fx *= s;
  camera.fy *= s;
  camera.ortho_scale *= s;
  camera.cx = 639.5;
  camera.cy = 359.5;
  return camera;
}

std::string loadAverage() {
  std::FILE* f = std::fopen("/proc/loadavg", "r");
  if (!f) return "?";
  char buf[64] = {0};
  const size_t n = std::fread(buf, 1, sizeof(buf) - 1, f);
  std::fclose(f);
  std::string s(buf, n);
  // first three fields
  size_t pos = 0;
  for (int i = 0; i < 3 && pos != std::string::npos; ++i) pos = s.find(' ', pos + 1);
  return s.substr(0, pos);
}

std::string withCommas(size_t v) {
  std::string s = std::to_string(v);
  for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(size_t(i), ",");
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string here = __FILE__;
  std::string dir = here.substr(0, here.rfind("/bench/")) + "/config/scenes";
  bool clip_buffer = false;
  int frames = 9;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--clip-buffer") == 0) {
      clip_buffer = true;
    } else if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
      frames = std::max(1, std::atoi(argv[++i]));
    } else {
      dir = argv[i];
    }
  }
  const int reference_frames = std::max(1, std::min(frames, 3));
  std::printf("CSG scenes at 1280x720, %u hardware threads, load average at start %s\n",
              std::thread::hardware_concurrency(), loadAverage().c_str());

  std::printf("\nScenes (our scene files against the thesis' models; Table 4.1 quoted):\n\n");
  std::printf(
      "| fig | scene | model | surfels | thesis (Table 4.1) | ours / thesis surfels |\n"
      "|---|---|---|---|---|---|\n");
  std::vector<rc::CsgScene> scenes;
  for (const SceneInfo& info : kScenes) {
    scenes.push_back(rc::loadCsgScene(dir + "/" + info.scene + ".yaml"));
    const size_t ours = scenes.back().surfels.size();
    char ratio[32] = "-";
    if (info.thesis_surfels) std::snprintf(ratio, sizeof(ratio), "%.3g", double(ours) / info.thesis_surfels);
    std::printf("| %s | %s | %s | %s | %s | %s |\n", info.figure, info.scene, info.model,
                withCommas(ours).c_str(), info.thesis_counts, ratio);
  }

  std::printf(
      "\nTable 1, static geometry. Partners: %s\n"
      "(bench_clip_partners times one search). Images: colour, depth, weight, patch id (what csg_renderer\n"
      "publishes). total ms: median (min-max) of %d frames after a warm-up frame; set-up ms: surfel set-up,\n"
      "clip programs and tile binning; splat ms: visibility, accumulation and shading passes (per thread).\n"
      "per-fragment: the same frame with Algorithms 4.2-4.4 in double per fragment (compiled_clipping =\n"
      "false), median of %d.\n"
      "Edge px, footprint: visible pixels inside the bounding circle of a clipped edge surfel's projected\n"
      "disc, at the rendered depth (the pixels the clip test runs on, clipped-away parts included;\n"
      "SceneFrameStats::edge_pixels). Edge px, shown: visible pixels where a kept fragment of a clipped "
      "edge\n"
      "surfel lies (exact disc; Algorithm 4.2 keeps it). Table 4.1 counts \"visible edge pixels\" of its "
      "own\n"
      "images at an unstated resolution: compare the counts side by side, form no ratio of rates.\n\n",
      clip_buffer ? "clip buffer (4.2.1), searched in every frame (it depends on the camera)"
                  : "spatial index, searched once (static geometry: SceneRenderer keeps them)",
      frames, reference_frames);
  std::printf(
      "| fig | scene | camera | surfels | edge surfels | edge px footprint | edge px shown | set-up ms | "
      "splat ms "
      "| total ms | fps | per-fragment ms | speed-up | thesis (Table 4.1) |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  struct Dyn {
    const char *scene, *camera;
    double static_ms;
    FrameTimes clip_buffer, reclassify;
    bool moving;
  };
  std::vector<Dyn> dynamic_rows;
  for (size_t s = 0; s < scenes.size(); ++s) {
    const SceneInfo& info = kScenes[s];
    const rc::CsgScene& scene = scenes[s];
    rc::CsgSceneRenderOptions options;
    options.clipper.method = clip_buffer ? rc::PartnerMethod::kClipBuffer : rc::PartnerMethod::kSpatialIndex;
    options.splat.outputs = rc::kOutputColor | rc::kOutputDepth | rc::kOutputWeight | rc::kOutputPatchId;
    rc::CsgSceneRenderOptions per_fragment = options;
    per_fragment.clipper.compiled_clipping = false;
    for (const rc::CsgSceneCamera& sc : scene.cameras) {
      const rc::Camera camera = at1280x720(sc.camera);
      rc::RenderImages images;
      std::unique_ptr<rc::CsgSceneRenderer> renderer;
      const FrameTimes compiled = measureScene(scene, camera, options, frames, false, &images, &renderer);
      const size_t shown = countShownEdgePixels(renderer->surfels(), *renderer->clipper(), camera, images);
      const FrameTimes reference =
          measureScene(scene, camera, per_fragment, reference_frames, false, &images);
      const rc::CsgSceneFrameStats& stats = compiled.stats;
      std::printf(
          "| %s | %s | %s | %s | %s | %s | %s | %.1f | %.1f | %.1f (%.1f-%.1f) | %.1f | %.1f | %.1f | %s |\n",
          info.figure, info.scene, sc.name.c_str(), withCommas(stats.surfels).c_str(),
          withCommas(stats.edge_surfels).c_str(), withCommas(stats.edge_pixels).c_str(),
          withCommas(shown).c_str(), compiled.setup, compiled.splat, compiled.total.median,
          compiled.total.min, compiled.total.max, 1000.0 / compiled.total.median, reference.total.median,
          reference.total.median / compiled.total.median, info.thesis_frames);
      std::fflush(stdout);

      if (clip_buffer)
        continue;  // Table 1 already searches in every frame; Table 2 comes with the default run
      // The dynamic case: partners in every frame.
      Dyn d{info.scene, sc.name.c_str(), compiled.total.median, {}, {}, scene.isDynamic()};
      rc::CsgSceneRenderOptions per_frame_buffer = options;
      per_frame_buffer.clipper.method = rc::PartnerMethod::kClipBuffer;
      d.clip_buffer = measureScene(scene, camera, per_frame_buffer, frames, false, &images);
      rc::CsgSceneRenderOptions spatial = options;
      spatial.clipper.method = rc::PartnerMethod::kSpatialIndex;
      d.reclassify = scene.isDynamic() ? measureScene(scene, camera, spatial, frames, true, &images)
                                       : measureReclassify(scene, camera, spatial, frames, &images);
      dynamic_rows.push_back(d);
    }
  }

  if (clip_buffer) {
    std::printf("\n(Table 2, partners in every frame: see the run without --clip-buffer)\n");
  } else {
    std::printf(
        "\nTable 2, partners in every timed frame (the thesis' dynamic case, 4.2.1 and 4.4): median of\n"
        "%d frames, total (min-max). (a) clip buffer: the edge surfels' partners by Algorithm 4.1 in\n"
        "every frame, classification kept, geometry unchanged (orbit frozen at t = 0). (b) re-classified:\n"
        "the classification of all surfels (4.1.2: partners of all surfels by the spatial index, then\n"
        "surface / edge / outside) plus the edge surfels' partners (spatial index) in every frame, as\n"
        "moving patches need it; the orbit scene moves by 1/30 s per frame here (its Table 1 row is the\n"
        "scene frozen at t = 0), the others re-classify unchanged geometry. static: Table 1's total.\n\n",
        frames);
    std::printf(
        "| scene | camera | static ms | (a) partners ms | (a) total ms | (a) fps | (b) classify ms "
        "| (b) partners ms | (b) total ms | (b) fps | edge surfels |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const Dyn& d : dynamic_rows)
      std::printf(
          "| %s%s | %s | %.1f | %.1f | %.1f (%.1f-%.1f) | %.1f | %.1f | %.1f | %.1f (%.1f-%.1f) | %.1f | %s "
          "|\n",
          d.scene, d.moving ? " (moving)" : "", d.camera, d.static_ms, d.clip_buffer.partners,
          d.clip_buffer.total.median, d.clip_buffer.total.min, d.clip_buffer.total.max,
          1000.0 / d.clip_buffer.total.median, d.reclassify.classify, d.reclassify.partners,
          d.reclassify.total.median, d.reclassify.total.min, d.reclassify.total.max,
          1000.0 / d.reclassify.total.median, withCommas(d.reclassify.stats.edge_surfels).c_str());
  }
  std::printf("\ntarget: 30 fps; load average at end %s\n", loadAverage().c_str());
  return 0;
}
