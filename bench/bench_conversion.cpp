// Point cloud -> textured mesh (thesis 6, Table 6.1): per-stage times for the bunny, the Igea and the dragon
// (../shared/data) at Table 6.1's triangle counts, median of N runs, next to the thesis' times; texture bytes
// (the colour atlas as raw RGB, as the table counts it) and usage; the geometric error; the colour PSNR of
// the textured mesh against its surfels from four fixed views. Then the speed/accuracy curve of the texture
// threshold on the Igea: texture time and bytes against PSNR (--csv for scripts/plot_conversion_tradeoff.py).
//
// The scanned models carry no colour: they are painted procedurally (cells of two colours with a gradient
// and thin stripes) so that the texture refinement has detail to find, as the thesis' painted models had.
// Normals are estimated (kNN PCA, propagated orientation) and radii estimated before the timed conversion
// (the "preparation" column; the thesis' models came with normals). The dragon here is a 50,000-point
// decimation, not the thesis' 553,619-point scan.
//   bench_conversion [--runs N] [--quick] [--csv PATH] [--model FILE]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "relaxed_connectivity/convert/procedural_paint.h"
#include "relaxed_connectivity/convert/surfel_conversion.h"
#include "relaxed_connectivity/convert/textured_mesh_renderer.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/render/splat/image_io.h"
#include "relaxed_connectivity/render/splat/surfel_renderer.h"
#include "relaxed_connectivity/surface/normal_estimation.h"
#include "relaxed_connectivity/surface/radius_estimation.h"

namespace {

using Clock = std::chrono::steady_clock;
using rc::Vec3;

double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct ViewQuality {
  double worst_psnr = 0, mean_psnr = 0, mismatch = 0;
};

/// The unshaded colour of the surfels and of the textured mesh from four views around the model.
ViewQuality compareViews(const rc::SurfelCloud& surfels, const rc::TexturedMesh& mesh) {
  Vec3 lo, hi;
  surfels.bounds(&lo, &hi);
  const Vec3 centre = 0.5 * (lo + hi);
  const double distance = 0.8 * (hi - lo).norm();  // close-ups: texels and surfels magnified, not aliased
  rc::SplatConfig config;
  config.shading = false;
  config.outputs = rc::kOutputColor | rc::kOutputDepth;
  const rc::SurfelRenderer renderer(config);
  ViewQuality q;
  q.worst_psnr = 1e9;
  const Vec3 dirs[] = {Vec3(0, -1, 0.2), Vec3(1, 0, 0.3), Vec3(-0.7, 0.7, -0.2), Vec3(0, 1, 0.5)};
  for (const Vec3& d : dirs) {
    rc::Camera camera = rc::Camera::perspective(480, 360, 0.6);
    camera.lookAt(centre + distance * d.normalized(), centre, Vec3::UnitZ());
    rc::RenderImages splats;
    renderer.render(surfels, camera, &splats);
    const rc::MeshImage triangles = rc::renderTexturedMesh(mesh, camera);
    const rc::ImageComparison c =
        rc::compareImages(splats.color, splats.depth, triangles.color, triangles.depth);
    if (const char* dump = std::getenv("RC_DUMP_VIEWS")) {  // the views as PNGs, for a look
      static int view = 0;
      rc::writePng(std::string(dump) + "_splats" + std::to_string(view) + ".png", splats.color, 480, 360);
      rc::writePng(std::string(dump) + "_mesh" + std::to_string(view++) + ".png", triangles.color, 480, 360);
    }
    q.worst_psnr = std::min(q.worst_psnr, c.psnr);
    q.mean_psnr += c.psnr / 4;
    q.mismatch = std::max(q.mismatch, c.silhouette_mismatch);
  }
  return q;
}

size_t atlasTexels(const rc::TexturedMesh& mesh) {
  size_t texels = 0;
  for (const rc::TexturePage& page : mesh.pages) texels += size_t(page.width) * page.height;
  return texels;
}

struct Model {
  const char* file;
  const char* name;
  size_t triangles;
  const char* thesis;  // Table 6.1: points, triangles, textures, times
};

}  // namespace

int main(int argc, char** argv) {
  int runs = 3;
  bool quick = false;
  const char* csv_path = nullptr;
  std::string only;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--model") && a + 1 < argc) only = argv[++a];
    if (!std::strcmp(argv[a], "--runs") && a + 1 < argc) runs = std::max(1, std::atoi(argv[++a]));
    if (!std::strcmp(argv[a], "--quick")) quick = true, runs = 1;
    if (!std::strcmp(argv[a], "--csv") && a + 1 < argc) csv_path = argv[++a];
  }
  if (!rc::meshGenerationAvailable()) {
    std::printf("bench_conversion: this build has no CGAL (libcgal-dev); nothing to measure\n");
    return 0;
  }
  const std::string data = RC_SHARED_DATA_DIR;
  const Model models[] = {
      {"bunny.ply", "bunny", 10000, "349,989 pts, 10,000 tris, 3.8 MB / 86 %, 511 + 28 + 104 s"},
      {"igea.ply", "Igea", 11340, "134,345 pts, 11,340 tris, 2.3 MB / 93 %, 258 + 15 + 35 s"},
      {"dragon_50k.obj", "dragon (50k)", 30000, "553,619 pts, 30,000 tris, 12.1 MB / 89 %, 907 + 37 + 444 s"},
  };
  std::printf(
      "Conversion (thesis 6, Table 6.1), median of %d run(s) per stage, 2 threads for the textures; "
      "colour threshold %.3g, normal threshold %.3g, border 1\n\n",
      runs, rc::TextureOptions().color_error, rc::TextureOptions().normal_error);
  std::printf("%-13s %8s %6s %6s | %7s %7s %7s %7s %7s | %7s | %8s %6s %6s | %9s %7s %6s\n", "model",
              "points", "tris", "prep s", "recon", "simpl", "error", "texture", "pack", "total s", "RGB MB",
              "use %", "+bord", "Hausdorff", "PSNR dB", "worst");
  rc::SurfelCloud igea;
  rc::TriangleMesh igea_mesh;
  for (const Model& m : models) {
    if (!only.empty() && only != m.file) continue;
    const std::string path = data + "/" + m.file;
    if (!std::filesystem::exists(path)) {
      std::printf("%-13s skipped: needs ../shared/data/%s\n", m.name, m.file);
      continue;
    }
    const auto p0 = Clock::now();
    rc::SurfelCloud surfels = rc::readCloud(path);
    surfels.removeNonFinite();
    surfels.normals.clear();
    rc::estimateNormals(surfels, rc::NormalEstimationConfig());
    rc::estimateRadii(surfels, rc::RadiusEstimationConfig());
    rc::paintCells(surfels);
    const double prep = since(p0);
    rc::ConversionOptions options;
    options.simplification.max_error = 0;
    options.simplification.target_triangles = m.triangles;
    std::vector<double> stage[5], totals;
    rc::ConversionResult last;
    for (int r = 0; r < runs; ++r) {
      last = rc::convertSurfels(surfels, options);
      for (int s = 0; s < 5; ++s) stage[s].push_back(last.seconds[s]);
      totals.push_back(last.totalSeconds());
    }
    const ViewQuality q = compareViews(surfels, last.textured);
    std::printf(
        "%-13s %8zu %6zu %6.1f | %7.2f %7.2f %7.2f %7.2f %7.2f | %7.2f | %8.2f %6.1f %6.1f | %9.2e %7.1f "
        "%6.1f\n",
        m.name, surfels.size(), last.textured.mesh.triangles.size(), prep, median(stage[0]), median(stage[1]),
        median(stage[2]), median(stage[3]), median(stage[4]), median(totals),
        3.0 * double(atlasTexels(last.textured)) / 1e6, 100 * last.textured.layout.usage,
        100 * last.textured.layout.usage_with_borders, last.geometric_error.hausdorff, q.mean_psnr,
        q.worst_psnr);
    {  // the packing's knob: without the gap fill (one run)
      rc::ConversionOptions rows_only = options;
      rows_only.atlas.fill_gaps = false;
      const rc::ConversionResult r = rc::convertSurfels(surfels, rows_only);
      std::printf("%-13s no gap fill: pack %.2f s, %.2f MB, use %.1f %% (%.1f %% with borders)\n", "",
                  r.seconds[4], 3.0 * double(atlasTexels(r.textured)) / 1e6, 100 * r.textured.layout.usage,
                  100 * r.textured.layout.usage_with_borders);
    }
    std::printf("%-13s thesis: %s\n", "", m.thesis);
    std::fflush(stdout);
    if (std::string(m.name) == "Igea") {
      igea = surfels;
      rc::SimplificationOptions simplification = options.simplification;
      igea_mesh = rc::simplifyMesh(rc::reconstructSurface(surfels), simplification);
    }
  }
  std::printf(
      "\nColumns: recon = reconstruction (CGAL advancing front), simpl = Garland-Heckbert to the triangle "
      "count, "
      "error = the geometric error measurement (not in the thesis' times), texture = patches with "
      "refinement, "
      "pack = Algorithm 6.1 and page assembly; thesis columns: triangulation / simplification / texture "
      "generation. RGB MB = colour atlas texels x 3 bytes; use %% = texels inside triangles / atlas area, "
      "+bord "
      "= texels the patches claim (triangles and their 1-texel borders) / atlas area. PSNR: unshaded colour "
      "of "
      "the textured mesh vs. the EWA-splatted surfels, 480x360, four views (mean, worst), pixels both "
      "show.\n");
  if (igea.empty()) return 0;

  // The texture threshold's speed/accuracy curve on the Igea (mesh fixed).
  std::printf("\nTexture threshold (Igea, %zu triangles): texture time (median of %d), colour atlas, PSNR\n",
              igea_mesh.triangles.size(), runs);
  std::printf("%10s | %9s %9s | %10s %8s %6s %6s | %8s %8s | %9s %9s\n", "threshold", "texture s", "pack s",
              "texels", "RGB MB", "use %", "+bord", "PSNR", "worst", "mean err", "at limit");
  FILE* csv = csv_path ? std::fopen(csv_path, "w") : nullptr;
  if (csv)
    std::fprintf(csv,
                 "threshold,texture_s,pack_s,texels,rgb_bytes,usage,usage_with_borders,psnr_mean,psnr_worst,"
                 "color_error_mean,at_limit\n");
  std::vector<double> thresholds = {0.2, 0.1, 0.06, 0.04, 0.03, 0.02, 0.015, 0.01};
  if (quick) thresholds = {0.1, 0.03, 0.01};
  for (double threshold : thresholds) {
    rc::TextureOptions texture;
    texture.color_error = threshold;
    texture.normal_texture = false;
    std::vector<double> texture_s, pack_s;
    rc::TexturedMesh mesh;
    rc::TextureStats stats;
    double mean_error = 0;
    for (int r = 0; r < runs; ++r) {
      const auto t0 = Clock::now();
      const std::vector<rc::TrianglePatches> patches =
          rc::computeTexturePatches(igea_mesh, igea, texture, &stats);
      texture_s.push_back(since(t0));
      const auto t1 = Clock::now();
      mesh = rc::buildTexturedMesh(igea_mesh, patches);
      pack_s.push_back(since(t1));
      double area = 0;
      mean_error = 0;
      for (const rc::TrianglePatches& p : patches) {
        const double a = 0.5 * p.frame.base * p.frame.height;
        mean_error += a * p.color.error, area += a;
      }
      mean_error /= area;
    }
    const ViewQuality q = compareViews(igea, mesh);
    if (const char* dump = std::getenv("RC_DUMP_VIEWS"))  // the first page, for a look at the packing
      rc::writePng(std::string(dump) + "_atlas" + std::to_string(threshold) + ".png", mesh.pages[0].color,
                   mesh.pages[0].width, mesh.pages[0].height);
    const size_t texels = atlasTexels(mesh);
    std::printf("%10.3f | %9.2f %9.2f | %10zu %8.2f %6.1f %6.1f | %8.2f %8.2f | %9.4f %9zu\n", threshold,
                median(texture_s), median(pack_s), texels, 3e-6 * double(texels), 100 * mesh.layout.usage,
                100 * mesh.layout.usage_with_borders, q.mean_psnr, q.worst_psnr, mean_error,
                stats.at_resolution_limit);
    std::fflush(stdout);
    if (csv)
      std::fprintf(csv, "%g,%.4f,%.4f,%zu,%zu,%.4f,%.4f,%.3f,%.3f,%.5f,%zu\n", threshold, median(texture_s),
                   median(pack_s), texels, 3 * texels, mesh.layout.usage, mesh.layout.usage_with_borders,
                   q.mean_psnr, q.worst_psnr, mean_error, stats.at_resolution_limit);
  }
  if (csv) std::fclose(csv);
  std::printf("(colour textures only; the mean error is (6.1) per area, area-weighted over the triangles)\n");
  return 0;
}
