#include "relaxed_connectivity/render/scene/csg_scene_renderer.h"

#include <chrono>
#include <cmath>

namespace rc {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace

CsgSceneRenderer::CsgSceneRenderer(const CsgScene& scene, const CsgSceneRenderOptions& options)
    : scene_(scene), options_(options), moved_(scene.surfels), renderer_(options.splat) {
  if (options_.csg) {
    clipper_ = std::make_unique<CsgClipper>(moved_, scene_.csgTree(), options_.clipper);
  } else {
    std::vector<size_t> keep;
    const Attribute* role = scene.surfels.attributes.find(kSurfelRoleAttribute);
    for (size_t i = 0; i < scene.surfels.size(); ++i)
      if (!role || role->get(i) == surfelRoleValue(SurfelRole::kSurface)) keep.push_back(i);
    visible_ = scene.surfels;
    visible_.select(keep);
  }
}

CsgSceneRenderer::~CsgSceneRenderer() = default;

void CsgSceneRenderer::render(const Camera& camera, double t, RenderImages* out, CsgSceneFrameStats* stats) {
  const auto t0 = Clock::now();
  CsgSceneFrameStats s;
  const bool moved = scene_.isDynamic() && t != time_;
  if (moved) {
    scene_.moveTo(t, &moved_);
    time_ = t;
  }
  if (!clipper_) {
    if (moved) {
      visible_ = moved_;
      std::vector<size_t> keep;
      const Attribute* role = moved_.attributes.find(kSurfelRoleAttribute);
      for (size_t i = 0; i < moved_.size(); ++i)
        if (!role || role->get(i) == surfelRoleValue(SurfelRole::kSurface)) keep.push_back(i);
      visible_.select(keep);
    }
    renderer_.render(visible_, camera, out, nullptr, &s.render);
  } else {
    if (moved) {
      const auto tc = Clock::now();
      clipper_->classify();  // surface / edge / outside change when patches move (4.1.2)
      s.classify_ms = msSince(tc);
    }
    const auto tp = Clock::now();
    clipper_->update(camera);
    s.partners_ms = msSince(tp);
    renderer_.render(moved_, camera, out, clipper_.get(), &s.render);
    s.edge_surfels = clipper_->edgeSurfels().size();
  }
  s.total_ms = msSince(t0);
  s.surfels = scene_.surfels.size();
  s.visibility_ms = s.render.visibility_ms;
  s.accumulate_ms = s.render.accumulate_ms;
  s.shade_ms = s.render.shade_ms;
  if (clipper_ && stats && !out->depth.empty())
    s.edge_pixels = countEdgePixels(moved_, *clipper_, camera, *out);
  if (stats) *stats = s;
}

size_t countEdgePixels(const SurfelCloud& cloud, const CsgClipper& clipper, const Camera& camera,
                       const RenderImages& images) {
  std::vector<uint8_t> mark(size_t(images.width) * images.height, 0);
  const Eigen::Isometry3d camera_T_world = camera.world_T_camera.inverse();
  for (uint32_t i : clipper.edgeSurfels()) {
    if (!clipper.needsClipping(i) || !clipper.isVisible(i)) continue;
    const Vec3 p = camera_T_world * cloud.positions[i];
    double u, v;
    if (!camera.project(p, &u, &v)) continue;
    const double r = cloud.radii[i];
    const double r_px = camera.projection == Camera::Projection::kPerspective ? r * camera.fx / p.z()
                                                                              : r * camera.ortho_scale;
    const int x0 = std::max(0, int(std::floor(u - r_px))),
              x1 = std::min(int(images.width) - 1, int(std::ceil(u + r_px)));
    const int y0 = std::max(0, int(std::floor(v - r_px))),
              y1 = std::min(int(images.height) - 1, int(std::ceil(v + r_px)));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        if ((x - u) * (x - u) + (y - v) * (y - v) > r_px * r_px) continue;
        const size_t k = size_t(y) * images.width + x;
        if (std::abs(double(images.depth[k]) - p.z()) <= r) mark[k] = 1;
      }
    }
  }
  size_t count = 0;
  for (uint8_t m : mark) count += m;
  return count;
}

}  // namespace rc
