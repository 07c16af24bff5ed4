// Environment maps for reflective paint (thesis 5.7, Fig. 5.10 c): "reflectivity is evaluated per surfel
// using a cube map, the resulting colors are blended normally". A surfel of reflectivity r shows (1 - r) C +
// r E(reflect(v, n)), v the view direction to the surfel, n its normal, E the environment's radiance in that
// direction. The environment is a procedural studio (sky, horizon, floor and a soft light) or a
// latitude-longitude image (z up); the reflected colour depends on the camera, so a camera move is a full
// update.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// The per-surfel attribute the renderers read the reflectivity from (float32, 0..1).
constexpr const char* kReflectivityAttribute = "reflectivity";

class EnvironmentMap {
 public:
  /// A procedural studio: a blue-grey sky brightening towards the horizon, a darker floor, a soft key light
  /// from above and behind the default camera.
  static EnvironmentMap studio();
  /// A latitude-longitude (equirectangular) 8-bit PNG, z up: column u is the azimuth atan2(y, x) from -pi
  /// (left) to pi, row v the polar angle from 0 (top, +z) to pi. Throws std::runtime_error naming the file.
  static EnvironmentMap fromEquirectangularPng(const std::string& path);

  /// Radiance (linear RGB, 0..1) seen along the unit `direction` (world frame).
  Vec3 radiance(const Vec3& direction) const;

 private:
  std::vector<Rgba> pixels_;  ///< empty: the procedural studio
  uint32_t width_ = 0, height_ = 0;
};

/// (1 - r) color + r E(reflect(v, n)) for a surfel at `position` with `normal` seen from `eye`; r is clamped
/// to [0, 1], non-finite r or geometry leave the colour unchanged.
Rgba reflectedColor(const Rgba& color, double reflectivity, const Vec3& position, const Vec3& normal,
                    const Vec3& eye, const EnvironmentMap& environment);

}  // namespace rc
