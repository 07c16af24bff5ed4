// CSG splatting performance on the thesis scenes (Table 4.1) at 1280x720: surfels, edge surfels, edge pixels,
// frames per second and edge pixels per second, median of 5 frames, next to the thesis numbers (Pentium 4,
// 3 GHz + GeForce FX5900, hardware/software renderer). Target: 30 fps.
//   bench_csg_scenes [SCENE_DIR] [--clip-buffer]
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "render/scene_renderer.h"

namespace {

struct ThesisRow {
  const char* figure;
  const char* scene;
  const char* numbers;  // Table 4.1: # surfels, # edge surfels, # edge pixels, FPS (two zoom levels)
};

// Table 4.1 of the thesis, quoted.
const ThesisRow kThesis[] = {
    {"4.9", "spikes", "1871 surfels, 972 edge surfels: 7189 edge px 9.09 fps; 33404 edge px 2.63 fps"},
    {"4.10", "icosahedron", "20 surfels, 20 edge surfels: 8763 edge px 8.3 fps; 47469 edge px 2.27 fps"},
    {"4.8", "femur", "116650 surfels, 2272 edge surfels: 12234 edge px 5.55 fps; 69450 edge px 2.0 fps"},
    {"4.7", "cube_densities", "(not in Table 4.1)"},
    {"4.6", "texture_square", "(not in Table 4.1)"},
    {"-", "orbit", "(dynamic; not in the thesis)"},
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// Median frame statistics over `frames` frames (after a warm-up frame) of one scene camera.
struct FrameTimes {
  double total, partners, splat;
  rc::SceneFrameStats stats;
};

FrameTimes measure(const rc::Scene& scene, const rc::Camera& camera, const rc::SceneRenderOptions& options,
                   int frames) {
  rc::SceneRenderer renderer(scene, options);
  rc::RenderImages images;
  std::vector<double> total, partners, splat;
  FrameTimes t;
  renderer.render(camera, 0, &images, &t.stats);  // warm-up
  for (int f = 0; f < frames; ++f) {
    renderer.render(camera, scene.isDynamic() ? (f + 1) / 30.0 : 0.0, &images, &t.stats);
    total.push_back(t.stats.total_ms);
    partners.push_back(t.stats.partners_ms + t.stats.classify_ms);
    splat.push_back(t.stats.visibility_ms + t.stats.accumulate_ms + t.stats.shade_ms);
  }
  t.total = median(total);
  t.partners = median(partners);
  t.splat = median(splat);
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string here = __FILE__;
  std::string dir = here.substr(0, here.rfind("/bench/")) + "/config/scenes";
  bool clip_buffer = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--clip-buffer") == 0) {
      clip_buffer = true;
    } else {
      dir = argv[i];
    }
  }
  std::printf(
      "CSG scenes at 1280x720, median of 5 frames, partners: %s (static scenes search once, see "
      "bench_clip_partners for the per-search cost); images: colour, depth, weight, patch id (what "
      "csg_renderer "
      "publishes). per-fragment: the same frame with Algorithms 4.2-4.4 evaluated in double per fragment "
      "(compiled_clipping = false), median of 3.\n",
      clip_buffer ? "clip buffer (4.2.1)" : "spatial index");
  std::printf("%-6s %-15s %-6s %8s %8s %8s %9s %9s %8s %8s %12s %12s %8s  %s\n", "fig", "scene", "camera",
              "surfels", "edge_sf", "edge_px", "partn_ms", "splat_ms", "total_ms", "fps", "edge_px/s",
              "per-frag_ms", "speed-up", "thesis (Table 4.1)");
  for (const ThesisRow& row : kThesis) {
    const rc::Scene scene = rc::loadScene(dir + "/" + row.scene + ".yaml");
    rc::SceneRenderOptions options;
    options.clipper.method = clip_buffer ? rc::PartnerMethod::kClipBuffer : rc::PartnerMethod::kSpatialIndex;
    options.splat.outputs = rc::kOutputColor | rc::kOutputDepth | rc::kOutputWeight | rc::kOutputPatchId;
    rc::SceneRenderOptions per_fragment = options;
    per_fragment.clipper.compiled_clipping = false;
    for (const rc::SceneCamera& sc : scene.cameras) {
      rc::Camera camera = sc.camera;
      const double s = 1280.0 / camera.width;
      camera.width = 1280;
      camera.height = 720;
      camera.fx *= s;
      camera.fy *= s;
      camera.ortho_scale *= s;
      camera.cx = 639.5;
      camera.cy = 359.5;
      const FrameTimes compiled = measure(scene, camera, options, 5);
      const FrameTimes reference = measure(scene, camera, per_fragment, 3);
      const rc::SceneFrameStats& stats = compiled.stats;
      std::printf("%-6s %-15s %-6s %8zu %8zu %8zu %9.2f %9.2f %8.2f %8.1f %12.3g %12.2f %8.1f  %s\n",
                  row.figure, row.scene, sc.name.c_str(), stats.surfels, stats.edge_surfels,
                  stats.edge_pixels, compiled.partners, compiled.splat, compiled.total,
                  1000.0 / compiled.total, stats.edge_pixels * 1000.0 / compiled.total, reference.total,
                  reference.total / compiled.total, row.numbers);
    }
  }
  std::printf("target: 30 fps\n");
  return 0;
}
