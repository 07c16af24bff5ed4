// Conversions of the splatting renderer's output (rc::RenderImages, rc::Camera) to the messages csg_renderer
// publishes: an rgb8 colour image, a 32FC1 depth image (metres along the optical axis, NaN background), a
// 32SC1 patch id image and the matching sensor_msgs/CameraInfo.
#pragma once

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Header.h>

#include <cmath>
#include <vector>

#include "relaxed_connectivity/render/splat/camera.h"
#include "relaxed_connectivity/render/splat/surfel_renderer.h"

namespace rc {

/// True if pixel i of `images` shows no surface (no accumulated weight or no finite depth).
inline bool isBackgroundPixel(const RenderImages& images, size_t i) {
  return !(images.weight[i] > 0.0f) || !std::isfinite(images.depth[i]);
}

/// Number of pixels that show a surface.
size_t countForegroundPixels(const RenderImages& images);

/// rgb8 image of the shaded colour (alpha dropped). Throws std::invalid_argument if the buffers disagree in
/// size.
sensor_msgs::ImagePtr toColorImage(const RenderImages& images, const std_msgs::Header& header);
/// The same from a colour buffer of width * height pixels (throws std::invalid_argument otherwise).
sensor_msgs::ImagePtr toColorImage(const std::vector<Rgba>& color, uint32_t width, uint32_t height,
                                   const std_msgs::Header& header);

/// 32FC1 depth image: camera-frame z in metres (REP 118), NaN where isBackgroundPixel.
sensor_msgs::ImagePtr toDepthImage(const RenderImages& images, const std_msgs::Header& header);

/// 32SC1 image of the patch id of the dominant surfel per pixel, -1 where isBackgroundPixel.
sensor_msgs::ImagePtr toPatchIdImage(const RenderImages& images, const std_msgs::Header& header);

/// CameraInfo of `camera` (no distortion). An orthographic camera has no pinhole model: K and P then hold the
/// orthographic scale (pixels per metre) in place of fx, fy, and distortion_model says "orthographic".
sensor_msgs::CameraInfoPtr toCameraInfo(const Camera& camera, const std_msgs::Header& header);

}  // namespace rc
