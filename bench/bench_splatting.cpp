// Software EWA splatting throughput (thesis 3.2): splats per second for a sampled sphere at 1280x720,
// 1 and 2 threads, median of 5 frames (after a warm-up frame: scratch memory is reused), per-pass breakdown
// (visibility, accumulation and shading run per tile: thread-summed time / threads), next to the four-wide
// SSE2 passes (the peer; the default uses AVX2 where the CPU has it); cost of the EWA filter
// and of the depth tolerance against quality (holes inside the analytic silhouette, seam angle between
// neighbouring pixels).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "render/surfel_renderer.h"

namespace {

using rc::Vec3;

rc::SurfelCloud sampleSphere(double radius, int count) {
  rc::SurfelCloud cloud;
  cloud.positions.reserve(count);
  cloud.normals.reserve(count);
  cloud.radii.assign(count, 1.5 * radius * std::sqrt(4.0 / count));
  cloud.colors.assign(count, rc::Rgba{200, 120, 60, 255});
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1 - 2 * (i + 0.5) / count, r = std::sqrt(1 - z * z), phi = golden * i;
    const Vec3 normal(r * std::cos(phi), r * std::sin(phi), z);
    cloud.normals.push_back(normal);
    cloud.positions.push_back(radius * normal);
  }
  return cloud;
}

struct Timing {
  double total, setup, bin, visibility, accumulate, shade;
};

Timing medianOf5(const rc::SurfelRenderer& renderer, const rc::SurfelCloud& cloud, const rc::Camera& camera,
                 rc::RenderImages* images) {
  std::vector<rc::RenderStats> runs(5);
  renderer.render(cloud, camera, images);  // warm-up
  for (auto& stats : runs) renderer.render(cloud, camera, images, nullptr, &stats);
  std::sort(runs.begin(), runs.end(), [](auto& a, auto& b) { return a.total_ms < b.total_ms; });
  const rc::RenderStats& m = runs[2];
  return {m.total_ms, m.setup_ms, m.bin_ms, m.visibility_ms, m.accumulate_ms, m.shade_ms};
}

/// Pixels inside the analytic silhouette (shrunk by 2 px) without weight, and the largest angle between
/// the normals of neighbouring pixels facing the camera (seams).
void quality(const rc::RenderImages& images, const rc::Camera& camera, double silhouette_px, size_t* holes,
             double* seam) {
  *holes = 0;
  *seam = 0;
  for (uint32_t v = 1; v < images.height; ++v)
    for (uint32_t u = 1; u < images.width; ++u) {
      const size_t p = size_t(v) * images.width + u;
      if (std::hypot(u - camera.cx, v - camera.cy) < silhouette_px - 2 && !(images.weight[p] > 0)) ++*holes;
      for (size_t q : {p - 1, p - images.width}) {
        if (!(images.weight[p] > 0 && images.weight[q] > 0)) continue;
        if (images.normal[p].x() < 0.7f || images.normal[q].x() < 0.7f) continue;  // camera on +x
        *seam = std::max(*seam, double(std::acos(std::min(1.0f, images.normal[p].dot(images.normal[q])))));
      }
    }
}

}  // namespace

int main(int argc, char** argv) {
  rc::Camera camera = rc::Camera::perspective(1280, 720, 60.0 * M_PI / 180);
  const double distance = 3.0;
  camera.lookAt(Vec3(distance, 0, 0), Vec3::Zero());
  const double silhouette_px = camera.fx / std::sqrt(distance * distance - 1);
  std::printf("EWA splatting, sphere at 1280x720 (silhouette radius %.0f px), median of 5 frames\n\n",
              silhouette_px);
  std::printf(
      "| surfels | threads | EWA | outputs | faces | SIMD | total ms | set-up ms | bin ms | visibility ms | "
      "accumulate ms | shade ms | Msplats/s | fragments/splat | speed-up vs SSE2 |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  struct Variant {
    bool ewa;
    uint32_t outputs;
    bool cull;
  };
  const Variant variants[] = {{true, rc::kOutputAll, false},
                              {false, rc::kOutputAll, false},
                              {true, rc::kOutputColor | rc::kOutputDepth, false},
                              {true, rc::kOutputColor | rc::kOutputDepth, true}};
  for (int count : {100000, 1000000}) {
    const rc::SurfelCloud cloud = sampleSphere(1.0, count);
    for (int threads : {1, 2})
      for (const Variant& v : variants) {
        rc::SplatConfig config;
        config.threads = threads;
        config.ewa_filter = v.ewa;
        config.outputs = v.outputs;
        config.backface_culling = v.cull;
        rc::SurfelRenderer renderer(config);
        rc::RenderImages images;
        const Timing t = medianOf5(renderer, cloud, camera, &images);
        rc::RenderStats stats;
        renderer.render(cloud, camera, &images, nullptr, &stats);
        // The peer: the same frame with the four-wide SSE2 passes and scalar set-up (bitwise the same image).
        rc::SplatConfig peer_config = config;
        peer_config.wide_simd = false;
        rc::SurfelRenderer peer(peer_config);
        const Timing p = medianOf5(peer, cloud, camera, &images);
        std::printf(
            "| %d | %d | %s | %s | %s | %d-wide | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | "
            "%.2f |\n",
            count, threads, v.ewa ? "on" : "off", v.outputs == rc::kOutputAll ? "all" : "colour+depth",
            v.cull ? "front" : "both", stats.simd_width, t.total, t.setup, t.bin, t.visibility, t.accumulate,
            t.shade, count / (t.total * 1e3), double(stats.fragments) / stats.splats, p.total / t.total);
      }
  }

  std::printf(
      "\nDepth tolerance vs quality (100k surfels, 2 threads; holes inside the silhouette, largest "
      "normal angle between neighbouring pixels facing the camera)\n\n");
  std::printf(
      "| depth_tolerance_scale | EWA | total ms | holes | seam angle [rad] |\n|---|---|---|---|---|\n");
  const rc::SurfelCloud cloud = sampleSphere(1.0, 100000);
  for (double scale : {0.0, 0.25, 1.0, 4.0})
    for (bool ewa : {true, false}) {
      rc::SplatConfig config;
      config.threads = 2;
      config.depth_tolerance_scale = scale;
      config.ewa_filter = ewa;
      rc::RenderImages images;
      const Timing t = medianOf5(rc::SurfelRenderer(config), cloud, camera, &images);
      size_t holes;
      double seam;
      quality(images, camera, silhouette_px, &holes, &seam);
      std::printf("| %.2f | %s | %.1f | %zu | %.4f |\n", scale, ewa ? "on" : "off", t.total, holes, seam);
    }
  return 0;
}
