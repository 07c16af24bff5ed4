// Sampled analytic surfaces for the brush tests (a plane, a sphere and a convex 90-degree edge) and a flat
// brush.
#pragma once

#include <cmath>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/paint/brush_preset.h"

namespace rc::paint_test {

/// The plane z = height, a square grid of spacing h over [-half, half]^2, normals +z.
inline SurfelCloud planeCloud(double half, double h, double height = 0) {
  SurfelCloud c;
  const int n = int(std::round(half / h));
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      c.positions.push_back(Vec3(i * h, j * h, height));
      c.normals.push_back(Vec3::UnitZ());
    }
  c.radii.assign(c.size(), 0.75 * h);
  return c;
}

/// Fibonacci sampling of a sphere of radius r about `centre`, outward normals.
inline SurfelCloud sphereCloud(const Vec3& centre, double r, size_t count) {
  SurfelCloud c;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count;
    const double s = std::sqrt(1.0 - z * z);
    const Vec3 n(s * std::cos(golden * i), s * std::sin(golden * i), z);
    c.positions.push_back(centre + r * n);
    c.normals.push_back(n);
  }
  c.radii.assign(c.size(), r * std::sqrt(4.0 / count));
  return c;
}

/// A convex 90-degree edge along y: the top face z = 0 for x <= 0 (normal +z) and the side face x = 0 for
/// z <= 0 (normal +x), each a grid of spacing h extending `extent` from the edge and +-extent in y.
inline SurfelCloud edgeCloud(double extent, double h) {
  SurfelCloud c;
  const int n = int(std::round(extent / h));
  for (int j = -n; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      c.positions.push_back(Vec3(-i * h, j * h, 0));
      c.normals.push_back(Vec3::UnitZ());
      if (i == 0) continue;  // the edge line belongs to the top face
      c.positions.push_back(Vec3(0, j * h, -i * h));
      c.normals.push_back(Vec3::UnitX());
    }
  c.radii.assign(c.size(), 0.75 * h);
  return c;
}

/// The flat brush of config/paint/brushes/flat.yaml (four chains across 12 mm).
inline BrushPreset flatPreset() {
  BrushPreset p;
  p.shape = BrushShape::kFlat;
  p.chains = 4;
  p.radius = 0.006;
  p.time_step = 8e-4;
  return p;
}

}  // namespace rc::paint_test
