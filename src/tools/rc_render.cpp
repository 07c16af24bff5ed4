// rc_render: renders CSG scenes with sharp edges from surfels (thesis chapter 4).
//   rc_render SCENE.yaml [--camera i] [--width W --height H] [--frames N --dt S] [--out DIR] [--no-csg]
//             [--clip-method clipbuffer|spatial]
//   rc_render --surfels a.ply b.ply --csg "0 - 1" [...]      patch id = file index; camera fitted to the
//   bounds
// Writes DIR/<scene>_<camera>[_fNNN]_color.png, _depth.pfm, _normal.pfm, _weight.pfm, _patch.png (16 bit) and
// prints a timing table.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>

#include "relaxed_connectivity/core/surfel_attributes.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/render/scene/csg_scene_renderer.h"
#include "relaxed_connectivity/render/scene/framing_camera.h"
#include "relaxed_connectivity/render/splat/image_io.h"

namespace {

using rc::Vec3;

/// A scene made of surfel files: patch i = file i, expression over indices.
rc::CsgScene sceneFromSurfelFiles(const std::vector<std::string>& files, const std::string& csg) {
  rc::CsgScene scene;
  scene.name = std::filesystem::path(files.front()).stem().string();
  for (size_t k = 0; k < files.size(); ++k) {
    rc::SurfelCloud cloud = rc::readCloud(files[k]);
    if (!cloud.hasNormals() || !(cloud.hasRadii() || cloud.hasAxes()))
      throw std::runtime_error(files[k] + ": needs normals and radii (run rc_surface estimate first)");
    cloud.attributes = rc::AttributeSet();
    cloud.attributes.add(rc::kPatchIdAttribute, rc::ScalarType::kInt32, 1, cloud.size());
    cloud.attributes.add(rc::kSurfelRoleAttribute, rc::ScalarType::kInt32, 1, cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) cloud.attributes.find(rc::kPatchIdAttribute)->set(i, double(k));
    if (!cloud.hasColors()) cloud.colors.assign(cloud.size(), rc::Rgba{200, 200, 200, 255});
    if (!cloud.hasRadii()) {
      cloud.radii.resize(cloud.size());
      for (size_t i = 0; i < cloud.size(); ++i)
        cloud.radii[i] = std::max(cloud.axes1[i].norm(), cloud.axes2[i].norm());
    }
    rc::CsgScenePatch patch;
    patch.name = "p" + std::to_string(k);
    patch.first_surfel = scene.surfels.size();
    patch.surfel_count = cloud.size();
    scene.patches.push_back(patch);
    if (k == 0) {
      scene.surfels = cloud;
    } else {
      scene.surfels.append(cloud);
    }
  }
  scene.csg_expression = scene.geometry_expression = csg;
  Vec3 lo, hi;
  scene.surfels.bounds(&lo, &hi);
  scene.cameras.push_back(rc::CsgSceneCamera{"fit", rc::framingCamera(lo, hi, 640, 480)});
  return scene;
}

/// The camera resized to W x H with the same field of view / view width.
rc::Camera resized(const rc::Camera& c, uint32_t width, uint32_t height) {
  rc::Camera out = c;
  const double s = double(width) / c.width;
  out.width = width;
  out.height = height;
  out.fx = c.fx * s;
  out.fy = c.fy * s;
  out.ortho_scale = c.ortho_scale * s;
  out.cx = 0.5 * (width - 1.0);
  out.cy = 0.5 * (height - 1.0);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rc_render: CSG splatting with sharp edges and corners (thesis ch. 4)"};
  std::string scene_path, out_dir = ".", clip_method = "spatial", csg;
  std::vector<std::string> surfel_files;
  int camera_index = -1, frames = 1;
  uint32_t width = 0, height = 0;
  double dt = 1.0 / 30;
  bool no_csg = false;
  app.add_option("scene", scene_path, "scene file (config/scenes/*.yaml)");
  app.add_option("--surfels", surfel_files, "surfel files (patch id = index) instead of a scene file");
  app.add_option("--csg", csg, "CSG expression over file indices, e.g. \"0 - 1\" (with --surfels)");
  app.add_option("--camera", camera_index, "camera index (default: all)");
  app.add_option("--width", width, "image width (keeps the field of view)");
  app.add_option("--height", height, "image height");
  app.add_option("--frames", frames, "frames to render (dynamic scenes move by --dt per frame)")
      ->check(CLI::PositiveNumber);
  app.add_option("--dt", dt, "seconds per frame");
  app.add_option("--out", out_dir, "output folder");
  app.add_flag("--no-csg", no_csg, "plain splatting without clipping");
  app.add_option("--clip-method", clip_method, "clipping partner search (default spatial)")
      ->check(CLI::IsMember({"clipbuffer", "spatial"}));
  CLI11_PARSE(app, argc, argv);

  try {
    rc::CsgScene scene;
    if (!surfel_files.empty()) {
      if (!scene_path.empty()) throw std::runtime_error("give either a scene file or --surfels, not both");
      if (csg.empty()) throw std::runtime_error("--surfels needs --csg");
      scene = sceneFromSurfelFiles(surfel_files, csg);
    } else {
      if (scene_path.empty()) throw std::runtime_error("no scene file (or --surfels) given");
      scene = rc::loadCsgScene(scene_path);
    }
    if (camera_index >= int(scene.cameras.size()))
      throw std::runtime_error("--camera " + std::to_string(camera_index) + ": the scene has " +
                               std::to_string(scene.cameras.size()) + " cameras");
    std::filesystem::create_directories(out_dir);
    rc::CsgSceneRenderOptions options;
    options.csg = !no_csg;
    options.clipper.method =
        clip_method == "spatial" ? rc::PartnerMethod::kSpatialIndex : rc::PartnerMethod::kClipBuffer;
    rc::CsgSceneRenderer renderer(scene, options);
    std::printf("%-24s %8s %8s %8s %8s %8s %8s %8s %8s %8s\n", "frame", "surfels", "edge_sf", "edge_px",
                "partn_ms", "visib_ms", "accum_ms", "shade_ms", "total_ms", "fps");
    for (size_t c = 0; c < scene.cameras.size(); ++c) {
      if (camera_index >= 0 && int(c) != camera_index) continue;
      rc::Camera camera = scene.cameras[c].camera;
      if (width || height)
        camera = resized(camera, width ? width : camera.width,
                         height ? height
                                : uint32_t(std::lround(double(camera.height) *
                                                       (width ? width : camera.width) / camera.width)));
      for (int f = 0; f < frames; ++f) {
        rc::RenderImages images;
        rc::CsgSceneFrameStats stats;
        renderer.render(camera, f * dt, &images, &stats);
        std::string prefix = out_dir + "/" + scene.name + "_" + scene.cameras[c].name;
        if (frames > 1) {
          char suffix[16];
          std::snprintf(suffix, sizeof(suffix), "_f%03d", f);
          prefix += suffix;
        }
        rc::writeRenderImages(prefix, images);
        std::printf("%-24s %8zu %8zu %8zu %8.2f %8.2f %8.2f %8.2f %8.2f %8.1f\n",
                    (scene.cameras[c].name + (frames > 1 ? "/" + std::to_string(f) : "")).c_str(),
                    stats.surfels, stats.edge_surfels, stats.edge_pixels,
                    stats.partners_ms + stats.classify_ms, stats.visibility_ms, stats.accumulate_ms,
                    stats.shade_ms, stats.total_ms, 1000.0 / stats.total_ms);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rc_render: %s\n", e.what());
    return 1;
  }
  return 0;
}
