#include "relaxed_connectivity/render/display/disc_quads.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

#include "relaxed_connectivity/render/splat/ewa_splat.h"

namespace rc {
namespace {

/// The scalar of surfel i for a field name (a null function for "rgb").
std::function<double(size_t)> fieldReader(const SurfelCloud& cloud, const std::string& field) {
  if (field == "rgb") return nullptr;
  if (field == "x" || field == "y" || field == "z") {
    const int axis = field[0] - 'x';
    return [&cloud, axis](size_t i) { return cloud.positions[i][axis]; };
  }
  if (field == "radius" && cloud.hasRadii()) return [&cloud](size_t i) { return cloud.radii[i]; };
  if (field == "confidence" && cloud.hasConfidence())
    return [&cloud](size_t i) { return double(cloud.confidence[i]); };
  if (field == "curvature" && !cloud.curvature.empty())
    return [&cloud](size_t i) { return double(cloud.curvature[i]); };
  if (const Attribute* a = cloud.attributes.find(field); a && a->count == 1)
    return [a](size_t i) { return a->get(i); };
  throw std::invalid_argument("disc quads: no scalar field '" + field + "' in the cloud");
}

}  // namespace

std::vector<std::string> discColourFields(const SurfelCloud& cloud) {
  std::vector<std::string> fields;
  if (cloud.hasColors()) fields.push_back("rgb");
  if (cloud.hasRadii()) fields.push_back("radius");
  if (cloud.hasConfidence()) fields.push_back("confidence");
  if (!cloud.curvature.empty()) fields.push_back("curvature");
  for (const char* axis : {"x", "y", "z"}) fields.push_back(axis);
  for (const Attribute& a : cloud.attributes.columns())
    if (a.count == 1) fields.push_back(a.name);
  return fields;
}

void viridisColour(double t, uint8_t rgb[3]) {
  // Viridis at t = 0, 1/8, ..., 1 (matplotlib's table), linearly interpolated.
  static const double kTable[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},
                                      {44, 113, 142}, {33, 144, 141}, {39, 173, 129},
                                      {92, 200, 99},  {170, 220, 50}, {253, 231, 37}};
  t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
  const double s = t * 8;
  const int k = std::min(7, int(s));
  const double f = s - k;
  for (int c = 0; c < 3; ++c)
    rgb[c] = uint8_t(std::lround(kTable[k][c] + f * (kTable[k + 1][c] - kTable[k][c])));
}

DiscQuadStats buildDiscQuads(const SurfelCloud& cloud, const DiscQuadOptions& options,
                             std::vector<DiscVertex>* vertices) {
  if (!cloud.hasNormals() && !cloud.hasAxes())
    throw std::invalid_argument("disc quads: the cloud has neither normals nor tangent axes");
  const auto scalar = fieldReader(cloud, options.colour_field);
  const size_t n = cloud.size();
  DiscQuadStats stats;
  stats.min_value = options.min_value;
  stats.max_value = options.max_value;
  if (scalar && options.auto_range) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (size_t i = 0; i < n; ++i) {
      const double v = scalar(i);
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    }
    stats.min_value = std::isfinite(lo) ? lo : 0.0;
    stats.max_value = std::isfinite(hi) ? hi : 1.0;
  }
  const double span = stats.max_value - stats.min_value;
  const double inverse_span = span > 0 ? 1.0 / span : 0.0;
  vertices->resize(4 * n);
  static const float kCorner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  DiscVertex* out = vertices->data();
  for (size_t i = 0; i < n; ++i) {
    Vec3 normal, axis1, axis2;
    if (cloud.hasAxes()) {
      axis1 = cloud.axes1[i];
      axis2 = cloud.axes2[i];
      normal = cloud.hasNormals() ? cloud.normals[i] : axis1.cross(axis2);
    } else {
      normal = cloud.normals[i];
      const double r = cloud.hasRadii() && cloud.radii[i] > 0 ? cloud.radii[i] : options.default_radius;
      tangentAxes(normal.normalized(), r, &axis1, &axis2);
    }
    const Vec3& p = cloud.positions[i];
    const double length = normal.norm();
    if (!p.allFinite() || !(length > 0) || !std::isfinite(length) || !axis1.allFinite() ||
        !axis2.allFinite()) {
      ++stats.skipped;
      continue;
    }
    normal /= length;
    axis1 *= options.radius_scale;
    axis2 *= options.radius_scale;
    uint8_t colour[4] = {200, 200, 200, options.alpha};
    if (scalar) {
      viridisColour((scalar(i) - stats.min_value) * inverse_span, colour);
    } else if (cloud.hasColors()) {
      for (int c = 0; c < 3; ++c) colour[c] = cloud.colors[i][c];
    }
    for (int k = 0; k < 4; ++k) {
      DiscVertex& v = *out++;
      const Vec3 corner = p + kCorner[k][0] * axis1 + kCorner[k][1] * axis2;
      for (int c = 0; c < 3; ++c) {
        v.position[c] = float(corner[c]);
        v.normal[c] = float(normal[c]);
      }
      std::copy_n(colour, 4, v.colour);
      v.uv[0] = kCorner[k][0];
      v.uv[1] = kCorner[k][1];
    }
    ++stats.discs;
  }
  vertices->resize(4 * stats.discs);
  return stats;
}

}  // namespace rc
