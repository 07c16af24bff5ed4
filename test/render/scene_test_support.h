// Shared by the render tests: the scene folder of the source tree and scene cameras resized for fast tests.
#pragma once

#include <cstdint>
#include <string>

#include "relaxed_connectivity/render/splat/camera.h"

namespace rc {

/// config/scenes/ of this checkout (with the trailing slash).
inline std::string sceneDir() {
  const std::string here = __FILE__;
  return here.substr(0, here.rfind("/test/")) + "/config/scenes/";
}

/// `camera` with the same field of view at width x height, principal point at the image centre.
inline Camera resizedCamera(const Camera& camera, uint32_t width, uint32_t height) {
  Camera out = camera;
  const double s = double(width) / camera.width;
  out.width = width;
  out.height = height;
  out.fx *= s;
  out.fy *= s;
  out.ortho_scale *= s;
  out.cx = 0.5 * (width - 1.0);
  out.cy = 0.5 * (height - 1.0);
  return out;
}

}  // namespace rc
