#include "relaxed_connectivity/render/splat/overlay_compositor.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "relaxed_connectivity/render/splat/ewa_splat.h"

namespace rc {

namespace {

SplatConfig overlayConfig(SplatConfig config, uint32_t outputs) {
  config.outputs = outputs;
  return config;
}

/// Inclusive pixel rectangle.
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  bool empty() const { return x1 < x0 || y1 < y0; }
};

/// The camera showing only `rect` of `camera`'s image.
Camera crop(const Camera& camera, const PixelRect& rect) {
  Camera c = camera;
  c.width = uint32_t(rect.x1 - rect.x0 + 1);
  c.height = uint32_t(rect.y1 - rect.y0 + 1);
  c.cx -= rect.x0;
  c.cy -= rect.y0;
  return c;
}

/// Grows `rect` by the pixel at (u, v) widened by `pad` pixels.
void include(PixelRect* rect, bool* any, double u, double v, double pad) {
  const int x0 = int(std::floor(u - pad)), x1 = int(std::ceil(u + pad));
  const int y0 = int(std::floor(v - pad)), y1 = int(std::ceil(v + pad));
  if (!*any) {
    *rect = {x0, y0, x1, y1};
    *any = true;
    return;
  }
  rect->x0 = std::min(rect->x0, x0);
  rect->y0 = std::min(rect->y0, y0);
  rect->x1 = std::max(rect->x1, x1);
  rect->y1 = std::max(rect->y1, y1);
}

PixelRect clampToImage(PixelRect rect, const Camera& camera) {
  rect.x0 = std::max(rect.x0, 0);
  rect.y0 = std::max(rect.y0, 0);
  rect.x1 = std::min(rect.x1, int(camera.width) - 1);
  rect.y1 = std::min(rect.y1, int(camera.height) - 1);
  return rect;
}

/// Pixels per metre at camera depth z.
double pixelsPerMetre(const Camera& camera, double z) {
  return camera.projection == Camera::Projection::kPerspective ? std::max(camera.fx, camera.fy) / z
                                                               : camera.ortho_scale;
}

/// The screen rectangle of the overlay's splats, clamped to the image; the whole image if a splat reaches
/// behind the near plane; empty if no surfel is finite.
PixelRect screenRect(const SurfelCloud& overlay, const Camera& camera, double cutoff) {
  PixelRect rect;
  bool any = false;
  const Eigen::Isometry3d camera_T_world = camera.world_T_camera.inverse();
  for (size_t i = 0; i < overlay.size(); ++i) {
    const Vec3 p = camera_T_world * overlay.positions[i];
    if (!p.allFinite()) continue;
    const double radius = overlay.hasRadii() ? overlay.radii[i] : 0.0;
    double u, v;
    if (!camera.project(p, &u, &v)) {
      if (p.z() + cutoff * radius >= camera.near_clip)
        return clampToImage({0, 0, int(camera.width) - 1, int(camera.height) - 1}, camera);
      continue;
    }
    include(&rect, &any, u, v, cutoff * radius * pixelsPerMetre(camera, p.z()) + 3);
  }
  return any ? clampToImage(rect, camera) : PixelRect();
}

using Clock = std::chrono::steady_clock;

}  // namespace

void OverlayOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("OverlayOptions: " + what); };
  if (!light_direction.allFinite() || !(light_direction.norm() > 0)) fail("light_direction must be non-zero");
  if (!(shadow_length >= 0) || !std::isfinite(shadow_length)) fail("shadow_length must be >= 0");
  if (!(shadow_strength >= 0 && shadow_strength <= 1)) fail("shadow_strength must lie in [0, 1]");
  if (!(shadow_texel >= 0) || !std::isfinite(shadow_texel)) fail("shadow_texel must be >= 0");
  if (max_shadow_map_size < 8 || max_shadow_map_size > 4096)
    fail("max_shadow_map_size must lie in [8, 4096]");
}

OverlayCompositor::OverlayCompositor(const OverlayOptions& options)
    : options_(options),
      renderer_(overlayConfig(options.splat, kOutputColor | kOutputDepth)),
      shadow_renderer_(overlayConfig(options.splat, kOutputDepth)) {
  options_.validate();
}

void OverlayCompositor::composite(const SurfelCloud& overlay, const Camera& camera, const RenderImages& base,
                                  std::vector<Rgba>* color, OverlayStats* stats) const {
  const Clock::time_point start = Clock::now();
  const size_t pixels = size_t(camera.width) * camera.height;
  if (base.width != camera.width || base.height != camera.height || base.color.size() != pixels ||
      base.depth.size() != pixels)
    throw std::invalid_argument(
        "OverlayCompositor: the base images need colour and depth of the camera's size");
  *color = base.color;
  OverlayStats local;
  if (!overlay.empty()) {
    if (!overlay.hasAxes() && !(overlay.hasNormals() && overlay.hasRadii()))
      throw std::invalid_argument("OverlayCompositor: the overlay needs normals and radii, or tangent axes");
    const PixelRect rect = screenRect(overlay, camera, options_.splat.cutoff_radius);
    std::vector<uint8_t> covered(pixels, 0);
    if (!rect.empty()) {
      const Camera cropped = crop(camera, rect);
      RenderImages images;
      renderer_.render(overlay, cropped, &images);
      for (uint32_t y = 0; y < cropped.height; ++y)
        for (uint32_t x = 0; x < cropped.width; ++x) {
          const size_t o = size_t(y) * cropped.width + x;
          const size_t p = size_t(y + rect.y0) * camera.width + (x + rect.x0);
          if (!(images.depth[o] < base.depth[p])) continue;  // (background: +inf on both)
          (*color)[p] = images.color[o];
          covered[p] = 1;
          ++local.overlay_pixels;
        }
    }
    if (options_.shadow && options_.shadow_strength > 0)
      castShadow(overlay, camera, base, covered, color, &local);
  }
  local.ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  if (stats) *stats = local;
}

void OverlayCompositor::castShadow(const SurfelCloud& overlay, const Camera& camera, const RenderImages& base,
                                   const std::vector<uint8_t>& covered, std::vector<Rgba>* color,
                                   OverlayStats* stats) const {
  // The light's frame: z along the light, looking at the overlay from behind it.
  Camera light;
  light.lookAt(Vec3::Zero(), options_.light_direction.normalized(),
               std::abs(options_.light_direction.normalized().z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitX());
  const Eigen::Isometry3d light_T_world = light.world_T_camera.inverse();
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double radius_sum = 0, max_radius = 0;
  size_t finite = 0;
  for (size_t i = 0; i < overlay.size(); ++i) {
    const Vec3 q = light_T_world * overlay.positions[i];
    if (!q.allFinite()) continue;
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
    const double r = overlay.hasRadii() ? overlay.radii[i] : overlay.axes1[i].norm();
    radius_sum += r;
    max_radius = std::max(max_radius, r);
    ++finite;
  }
  if (finite == 0) return;
  const double margin = options_.splat.cutoff_radius * max_radius;
  lo.head<2>() -= Vec3::Constant(margin).head<2>();
  hi.head<2>() += Vec3::Constant(margin).head<2>();
  double texel = options_.shadow_texel > 0 ? options_.shadow_texel : radius_sum / double(finite);
  const double extent = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  if (!(texel > 0)) texel = extent / 64;
  texel = std::max(texel, extent / options_.max_shadow_map_size);
  const uint32_t w = uint32_t(std::ceil((hi.x() - lo.x()) / texel)) + 1;
  const uint32_t h = uint32_t(std::ceil((hi.y() - lo.y()) / texel)) + 1;
  Camera map_camera = Camera::orthographic(w, h, w * texel);
  map_camera.cx = -lo.x() / texel;
  map_camera.cy = -lo.y() / texel;
  map_camera.near_clip = lo.z() - margin - 1.0;
  map_camera.far_clip = hi.z() + margin + 1.0;
  map_camera.world_T_camera = light.world_T_camera;
  RenderImages map;
  shadow_renderer_.render(overlay, map_camera, &map);

  // The screen rectangle where the shadow can fall: the box from the overlay to shadow_length below it.
  PixelRect rect;
  bool any = false;
  const Eigen::Isometry3d camera_T_world = camera.world_T_camera.inverse();
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 q((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                 (corner & 4) ? hi.z() + options_.shadow_length : lo.z());
    const Vec3 p = camera_T_world * (light.world_T_camera * q);
    double u, v;
    if (!camera.project(p, &u, &v)) {
      rect = {0, 0, int(camera.width) - 1, int(camera.height) - 1};
      any = true;
      break;
    }
    include(&rect, &any, u, v, 1);
  }
  rect = clampToImage(rect, camera);
  const double bias = 2 * texel;
  const float keep = float(1.0 - options_.shadow_strength);
  const bool perspective = camera.projection == Camera::Projection::kPerspective;
  for (int y = rect.y0; y <= rect.y1; ++y)
    for (int x = rect.x0; x <= rect.x1; ++x) {
      const size_t p = size_t(y) * camera.width + x;
      const float z = base.depth[p];
      if (covered[p] || !std::isfinite(z)) continue;
      const Vec3 p_camera =
          perspective ? Vec3((x - camera.cx) / camera.fx * z, (y - camera.cy) / camera.fy * z, z)
                      : Vec3((x - camera.cx) / camera.ortho_scale, (y - camera.cy) / camera.ortho_scale, z);
      const Vec3 q = light_T_world * (camera.world_T_camera * p_camera);
      const double mu = map_camera.cx + q.x() / texel, mv = map_camera.cy + q.y() / texel;
      const int mx = int(std::lround(mu)), my = int(std::lround(mv));
      if (mx < 0 || my < 0 || mx >= int(w) || my >= int(h)) continue;
      const float occluder = map.depth[size_t(my) * w + mx];
      if (!(occluder + bias < q.z()) || q.z() - occluder > options_.shadow_length) continue;
      Rgba& c = (*color)[p];
      for (int k = 0; k < 3; ++k) c[k] = uint8_t(std::lround(keep * c[k]));
      ++stats->shadow_pixels;
    }
}

}  // namespace rc
