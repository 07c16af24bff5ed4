// Surfels as oriented, radius-scaled discs for a rasterizing viewer (the rviz SurfelCloud display): per
// surfel one quad in its tangent plane, corners at +-r along two tangent axes, texture coordinates that a
// circular alpha mask cuts to the disc, the surfel's colour or a scalar field through a colour map. ROS- and
// Ogre-free so that it is tested and measured alone.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// One quad corner: 36 bytes, the vertex layout the viewer uploads as is.
struct DiscVertex {
  float position[3];
  float normal[3];
  uint8_t colour[4];  ///< r, g, b, a
  float uv[2];        ///< (+-1, +-1): the disc is u^2 + v^2 <= 1
};
static_assert(sizeof(DiscVertex) == 36, "DiscVertex is packed as the viewer expects");

struct DiscQuadOptions {
  double radius_scale = 1.0;
  double default_radius = 0.005;  ///< for clouds without radii (and surfels with radius <= 0) [m]
  /// "rgb" (the surfels' colours; grey without), "radius", "confidence", "curvature", "x", "y", "z", or the
  /// name of a one-component attribute column: mapped by the colour map from [min_value, max_value].
  std::string colour_field = "rgb";
  bool auto_range = true;  ///< min/max of the field over the cloud (else min_value, max_value)
  double min_value = 0, max_value = 1;
  uint8_t alpha = 255;
};

struct DiscQuadStats {
  size_t discs = 0;                     ///< quads written
  size_t skipped = 0;                   ///< non-finite position or normal
  double min_value = 0, max_value = 0;  ///< the range the colour map used
};

/// The scalar fields of `cloud` a viewer can colour by, in DiscQuadOptions::colour_field names.
std::vector<std::string> discColourFields(const SurfelCloud& cloud);

/// Writes four vertices per drawable surfel into `vertices` (resized) and returns what it did; quads are
/// (4k, 4k+1, 4k+2), (4k, 4k+2, 4k+3). Tangent axes come from the cloud where present (elliptical surfels),
/// else from the normal. Throws std::invalid_argument for an unknown colour field or a cloud without
/// normals.
DiscQuadStats buildDiscQuads(const SurfelCloud& cloud, const DiscQuadOptions& options,
                             std::vector<DiscVertex>* vertices);

/// The colour map (viridis: dark blue through green to yellow) at t in [0, 1] (clamped), as r, g, b.
void viridisColour(double t, uint8_t rgb[3]);

}  // namespace rc
