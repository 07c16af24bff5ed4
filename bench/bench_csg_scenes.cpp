// CSG splatting performance on the thesis scenes (Table 4.1) at 1280x720: surfels, edge surfels, edge pixels,
// frames per second and edge pixels per second, median of 5 frames, next to the thesis numbers (Pentium 4,
// 3 GHz + GeForce FX5900, hardware/software renderer). Target: 30 fps.
//   bench_csg_scenes [SCENE_DIR] [--spatial]
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

}  // namespace

int main(int argc, char** argv) {
  const std::string here = __FILE__;
  std::string dir = here.substr(0, here.rfind("/bench/")) + "/config/scenes";
  bool spatial = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--spatial") == 0) {
      spatial = true;
    } else {
      dir = argv[i];
    }
  }
  std::printf("CSG scenes at 1280x720, median of 5 frames, partners: %s\n",
              spatial ? "spatial index" : "clip buffer");
  std::printf("%-6s %-15s %-6s %8s %8s %8s %9s %9s %8s %8s %12s  %s\n", "fig", "scene", "camera", "surfels",
              "edge_sf", "edge_px", "partn_ms", "splat_ms", "total_ms", "fps", "edge_px/s",
              "thesis (Table 4.1)");
  for (const ThesisRow& row : kThesis) {
    const rc::Scene scene = rc::loadScene(dir + "/" + row.scene + ".yaml");
    rc::SceneRenderOptions options;
    options.clipper.method = spatial ? rc::PartnerMethod::kSpatialIndex : rc::PartnerMethod::kClipBuffer;
    rc::SceneRenderer renderer(scene, options);
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
      rc::RenderImages images;
      std::vector<double> total, partners, splat;
      rc::SceneFrameStats stats;
      renderer.render(camera, 0, &images, &stats);  // warm-up
      for (int f = 0; f < 5; ++f) {
        renderer.render(camera, scene.isDynamic() ? (f + 1) / 30.0 : 0.0, &images, &stats);
        total.push_back(stats.total_ms);
        partners.push_back(stats.partners_ms + stats.classify_ms);
        splat.push_back(stats.visibility_ms + stats.accumulate_ms + stats.shade_ms);
      }
      const double ms = median(total);
      std::printf("%-6s %-15s %-6s %8zu %8zu %8zu %9.2f %9.2f %8.2f %8.1f %12.3g  %s\n", row.figure,
                  row.scene, sc.name.c_str(), stats.surfels, stats.edge_surfels, stats.edge_pixels,
                  median(partners), median(splat), ms, 1000.0 / ms, stats.edge_pixels * 1000.0 / ms,
                  row.numbers);
    }
  }
  std::printf("target: 30 fps\n");
  return 0;
}
