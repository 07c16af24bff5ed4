#include "relaxed_connectivity/render/splat/environment_map.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "relaxed_connectivity/render/splat/image_io.h"

namespace rc {

EnvironmentMap EnvironmentMap::studio() {
  return EnvironmentMap();
}

EnvironmentMap EnvironmentMap::fromEquirectangularPng(const std::string& path) {
  EnvironmentMap map;
  map.pixels_ = readPng(path, &map.width_, &map.height_);
  if (map.width_ < 2 || map.height_ < 2)
    throw std::runtime_error(path + ": an environment map needs at least 2 x 2 pixels");
  return map;
}

Vec3 EnvironmentMap::radiance(const Vec3& d) const {
  if (pixels_.empty()) {
    const double z = std::clamp(d.z(), -1.0, 1.0);
    Vec3 c = z >= 0
                 ? Vec3(0.55, 0.62, 0.72) + (1 - z) * (1 - z) * Vec3(0.35, 0.30, 0.22)   // sky to horizon
                 : Vec3(0.22, 0.20, 0.18) + (1 + z) * (1 + z) * Vec3(0.18, 0.16, 0.14);  // floor to horizon
    const Vec3 key = Vec3(-0.3, 0.5, 0.8).normalized();                                  // a soft light box
    c += 0.6 * std::pow(std::max(0.0, d.dot(key)), 24.0) * Vec3::Ones();
    return c.cwiseMin(1.0);
  }
  const double u = (std::atan2(d.y(), d.x()) + M_PI) / (2 * M_PI) * width_;
  const double v = std::acos(std::clamp(d.z(), -1.0, 1.0)) / M_PI * height_;
  const uint32_t x = std::min(width_ - 1, uint32_t(std::max(0.0, u)));
  const uint32_t y = std::min(height_ - 1, uint32_t(std::max(0.0, v)));
  const Rgba& p = pixels_[size_t(y) * width_ + x];
  return Vec3(p[0], p[1], p[2]) / 255.0;
}

Rgba reflectedColor(const Rgba& color, double reflectivity, const Vec3& position, const Vec3& normal,
                    const Vec3& eye, const EnvironmentMap& environment) {
  if (!(reflectivity > 0) || !std::isfinite(reflectivity)) return color;
  const double r = std::min(reflectivity, 1.0);
  const Vec3 view = position - eye;
  const double n_length = normal.norm(), v_length = view.norm();
  if (!(n_length > 0) || !(v_length > 0) || !std::isfinite(n_length) || !std::isfinite(v_length))
    return color;
  Vec3 n = normal / n_length;
  const Vec3 v = view / v_length;
  if (n.dot(v) > 0) n = -n;  // two-sided: the side facing the viewer reflects
  const Vec3 e = 255.0 * environment.radiance(v - 2 * v.dot(n) * n);
  Rgba out = color;
  for (int k = 0; k < 3; ++k)
    out[k] = uint8_t(std::lround(std::clamp((1 - r) * color[k] + r * e[k], 0.0, 255.0)));
  return out;
}

}  // namespace rc
