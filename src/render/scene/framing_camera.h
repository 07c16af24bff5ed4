// A perspective camera that frames an axis-aligned box from a fixed direction (offline tools: rc_render
// --surfels, rc_shell --render).
#pragma once

#include <cmath>
#include <cstdint>

#include "relaxed_connectivity/render/splat/camera.h"

namespace rc {

/// Looks at the centre of [lo, hi] from centre + |hi - lo| * `eye_offset` (world up +z) with the given
/// horizontal field of view. With the default offset (length 1.53 box diagonals) and 40 degrees the box's
/// bounding sphere fits into the image for aspect ratios up to 4:3 (portrait images need a wider view).
/// Throws std::invalid_argument for a non-finite box, a zero size or a zero offset.
Camera framingCamera(const Vec3& lo, const Vec3& hi, uint32_t width, uint32_t height,
                     const Vec3& eye_offset = Vec3(0.8, -1.1, 0.7), double horizontal_fov = 40 * M_PI / 180);

}  // namespace rc
