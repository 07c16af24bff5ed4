// rc_convert: a point cloud to a textured mesh (thesis chapter 6).
//   rc_convert IN OUT [OUT...]    OUT: .obj (with .mtl and PNG pages beside it) and/or .glb
// Normals are estimated where the input has none (towards --viewpoint, else propagated), radii where it has
// none. A progress line per stage goes to stderr, a JSON summary to stdout (or --json FILE).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "relaxed_connectivity/convert/procedural_paint.h"
#include "relaxed_connectivity/convert/surfel_conversion.h"
#include "relaxed_connectivity/convert/textured_mesh_io.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/surface/normal_estimation.h"

namespace {

using Clock = std::chrono::steady_clock;

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "rc_convert: point cloud -> simplified mesh with colour and normal texture atlases (thesis ch. 6)"};
  std::string input, json_path;
  std::vector<std::string> outputs;
  rc::ConversionOptions options;
  std::vector<double> viewpoint;
  bool quiet = false, no_normal_texture = false;
  double paint_cells = 0;
  std::string method = "advancing_front";
  app.add_option("input", input,
                 "point file (ply, pcd, off, obj, xyz); normals and radii are used if present")
      ->required();
  app.add_option("outputs", outputs, "one or more of OUT.obj (with OUT.mtl and PNG pages beside it), OUT.glb")
      ->required();
  app.add_option(
         "--simplify-error", options.simplification.max_error,
         "simplification bound: largest quadric error, a fraction of the bounding box diagonal (0: none)")
      ->capture_default_str();
  app.add_option("--triangles", options.simplification.target_triangles,
                 "simplify to this many triangles (0: none)")
      ->capture_default_str();
  app.add_option("--color-error", options.texture.color_error,
                 "texture threshold: area-weighted mean RGB error (6.1), channels in [0, 1]")
      ->capture_default_str();
  app.add_option("--normal-error", options.texture.normal_error,
                 "normal texture threshold: mean 1 - N.N (6.2)")
      ->capture_default_str();
  app.add_flag("--no-normal-texture", no_normal_texture, "colour textures only");
  app.add_flag("--depth-texture", options.texture.depth_texture,
               "also a depth (displacement) texture: the surface's height above each triangle (OBJ output)");
  app.add_option("--depth-error", options.texture.depth_error,
                 "depth texture threshold: mean |h_s - h_t| over the median surfel radius")
      ->capture_default_str();
  app.add_option("--border", options.atlas.border, "texels around each patch")->capture_default_str();
  app.add_option("--mip-levels", options.atlas.mip_levels,
                 "also write this many mip levels of each page in the atlas' pattern (OBJ output)")
      ->capture_default_str();
  app.add_flag(
      "--no-gap-fill", [&](int64_t) { options.atlas.fill_gaps = false; },
      "pack rows and their ends only (faster; gaps between patches stay empty)");
  app.add_option("--max-page-size", options.atlas.max_page_size, "largest texture page (a power of two)")
      ->capture_default_str();
  app.add_option("--projection-depth", options.texture.projection_depth,
                 "surfels farther than this from a triangle are not drawn into it [m] (0: automatic)")
      ->capture_default_str();
  app.add_option("--method", method, "reconstruction: advancing_front | scale_space (noisy scans) | poisson")
      ->capture_default_str();
  app.add_flag(
      "--non-manifold", [&](int64_t) { options.reconstruction.require_manifold = false; },
      "keep going when the reconstruction is not a manifold");
  app.add_option("--viewpoint", viewpoint, "orient estimated normals towards x y z (a scanner)")->expected(3);
  app.add_option("--threads", options.texture.threads, "texture threads (0: all cores)")
      ->capture_default_str();
  app.add_option(
      "--paint-cells", paint_cells,
      "paint the input procedurally first (cells per bounding box diagonal; for uncoloured scans)");
  app.add_option("--json", json_path, "write the summary here instead of stdout");
  app.add_flag("--quiet", quiet, "no progress line");
  CLI11_PARSE(app, argc, argv);
  options.texture.normal_texture = !no_normal_texture;
  try {
    options.reconstruction.method = rc::reconstructionMethodFromName(method);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rc_convert: %s\n", e.what());
    return 2;
  }
  for (const std::string& out : outputs)
    if (!endsWith(out, ".obj") && !endsWith(out, ".glb")) {
      std::fprintf(stderr, "rc_convert: %s: outputs end in .obj or .glb\n", out.c_str());
      return 2;
    }
  try {
    const auto t0 = Clock::now();
    rc::SurfelCloud surfels = rc::readCloud(input);
    const size_t read_points = surfels.size();
    const size_t dropped = surfels.removeNonFinite();
    bool normals_estimated = false;
    if (!surfels.hasNormals()) {
      rc::NormalEstimationConfig config;
      if (viewpoint.size() == 3) config.viewpoint = rc::Vec3(viewpoint[0], viewpoint[1], viewpoint[2]);
      if (!quiet) std::fprintf(stderr, "normals: estimating for %zu points\n", surfels.size());
      rc::estimateNormals(surfels, config);
      normals_estimated = true;
    }
    if (paint_cells > 0) rc::paintCells(surfels, paint_cells);
    const double read_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    int last_percent = -1;
    rc::ConversionStage last_stage = rc::ConversionStage::kReconstruction;
    auto progress = [&](rc::ConversionStage stage, double fraction) {
      const int percent = int(100 * fraction);
      if (stage == last_stage && percent == last_percent) return true;  // one line update per percent
      last_stage = stage, last_percent = percent;
      if (!quiet) {
        std::fprintf(stderr, "\r%-16s %3d%%  %.1f s", rc::stageName(stage), int(100 * fraction),
                     std::chrono::duration<double>(Clock::now() - t0).count());
        if (fraction >= 1) std::fprintf(stderr, "\n");
      }
      return true;
    };
    const rc::ConversionResult r = rc::convertSurfels(surfels, options, progress);
    std::vector<std::string> files;
    const auto w0 = Clock::now();
    for (const std::string& out : outputs) {
      if (endsWith(out, ".obj")) {
        for (const std::string& f : rc::writeTexturedObj(out, r.textured)) files.push_back(f);
      } else {
        rc::writeGlb(out, r.textured);
        files.push_back(out);
      }
    }
    const double write_seconds = std::chrono::duration<double>(Clock::now() - w0).count();
    size_t texels = 0, file_bytes = 0;
    for (const rc::TexturePage& page : r.textured.pages) texels += size_t(page.width) * page.height;
    for (const std::string& f : files) file_bytes += std::filesystem::file_size(f);
    std::ostringstream j;
    j.precision(6);
    j << "{\n  \"input\": " << jsonString(input) << ",\n  \"points_read\": " << read_points
      << ", \"non_finite_dropped\": " << dropped << ", \"surfels\": " << surfels.size()
      << ", \"normals_estimated\": " << (normals_estimated ? "true" : "false")
      << ", \"radii_estimated\": " << r.radii_estimated << ",\n  \"reconstruction\": {\"method\": \""
      << rc::reconstructionMethodName(options.reconstruction.method)
      << "\", \"triangles\": " << r.reconstruction.triangles
      << ", \"components\": " << r.reconstruction.components
      << ", \"unused_surfels\": " << r.reconstruction.unused_surfels
      << ", \"boundary_edges\": " << r.reconstruction.boundary_edges
      << "},\n  \"triangles\": " << r.textured.mesh.triangles.size()
      << ", \"vertices\": " << r.textured.mesh.vertices.size()
      << ",\n  \"geometric_error\": {\"hausdorff\": " << r.geometric_error.hausdorff
      << ", \"rms\": " << r.geometric_error.rms << ", \"diagonal\": " << r.geometric_error.diagonal
      << "},\n  \"texture_error\": {\"color_max\": " << r.color_error_max
      << ", \"color_mean\": " << r.color_error_mean << ", \"normal_max\": " << r.normal_error_max
      << ", \"normal_mean\": " << r.normal_error_mean << ", \"depth_max\": " << r.depth_error_max
      << ", \"depth_mean\": " << r.depth_error_mean
      << ", \"patches_at_resolution_limit\": " << r.texture.at_resolution_limit
      << ", \"empty_patches\": " << r.texture.empty_patches
      << "},\n  \"atlas\": {\"pages\": " << r.textured.layout.pages
      << ", \"page_size\": " << r.textured.layout.page_size
      << ", \"last_page_height\": " << r.textured.layout.last_page_height << ", \"texels\": " << texels
      << ", \"rgb_bytes\": " << 3 * texels << ", \"usage\": " << r.textured.layout.usage
      << ", \"usage_with_borders\": " << r.textured.layout.usage_with_borders
      << ", \"color_refined_texels\": " << r.texture.color_refined_texels
      << ", \"normal_refined_texels\": " << r.texture.normal_refined_texels
      << ", \"depth_refined_texels\": " << r.texture.depth_refined_texels << ", \"depth_range\": ["
      << r.textured.depth_min << ", " << r.textured.depth_max << "]"
      << "},\n  \"seconds\": {\"read\": " << read_seconds;
    for (int s = 0; s < 5; ++s)
      j << ", " << jsonString(rc::stageName(rc::ConversionStage(s))) << ": " << r.seconds[s];
    j << ", \"write\": " << write_seconds << ", \"conversion\": " << r.totalSeconds() << "},\n  \"files\": [";
    for (size_t i = 0; i < files.size(); ++i) j << (i ? ", " : "") << jsonString(files[i]);
    j << "], \"file_bytes\": " << file_bytes << "\n}\n";
    if (json_path.empty()) {
      std::fputs(j.str().c_str(), stdout);
    } else {
      std::ofstream(json_path) << j.str();
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\nrc_convert: %s\n", e.what());
    return 1;
  }
  return 0;
}
