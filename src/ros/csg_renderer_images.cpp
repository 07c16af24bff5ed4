#include "relaxed_connectivity/ros/csg_renderer_images.h"

#include <sensor_msgs/image_encodings.h>
#include <boost/make_shared.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace rc {
namespace {

void checkSizes(const RenderImages& images) {
  const size_t n = static_cast<size_t>(images.width) * images.height;
  if (images.color.size() != n || images.depth.size() != n || images.weight.size() != n)
    throw std::invalid_argument(
        "render images: colour/depth/weight buffers hold " + std::to_string(images.color.size()) + "/" +
        std::to_string(images.depth.size()) + "/" + std::to_string(images.weight.size()) +
        " pixels, expected " + std::to_string(images.width) + " x " + std::to_string(images.height));
}

}  // namespace

size_t countForegroundPixels(const RenderImages& images) {
  checkSizes(images);
  size_t count = 0;
  for (size_t i = 0; i < images.depth.size(); ++i) count += !isBackgroundPixel(images, i);
  return count;
}

sensor_msgs::ImagePtr toColorImage(const RenderImages& images, const std_msgs::Header& header) {
  checkSizes(images);
  return toColorImage(images.color, images.width, images.height, header);
}

sensor_msgs::ImagePtr toColorImage(const std::vector<Rgba>& color, uint32_t width, uint32_t height,
                                   const std_msgs::Header& header) {
  if (color.size() != static_cast<size_t>(width) * height)
    throw std::invalid_argument("colour image: " + std::to_string(color.size()) + " pixels, expected " +
                                std::to_string(width) + " x " + std::to_string(height));
  auto msg = boost::make_shared<sensor_msgs::Image>();
  msg->header = header;
  msg->width = width;
  msg->height = height;
  msg->encoding = sensor_msgs::image_encodings::RGB8;
  msg->is_bigendian = 0;
  msg->step = 3 * width;
  msg->data.resize(static_cast<size_t>(msg->step) * height);
  uint8_t* out = msg->data.data();
  for (const Rgba& c : color) {
    *out++ = c[0];
    *out++ = c[1];
    *out++ = c[2];
  }
  return msg;
}

sensor_msgs::ImagePtr toDepthImage(const RenderImages& images, const std_msgs::Header& header) {
  checkSizes(images);
  auto msg = boost::make_shared<sensor_msgs::Image>();
  msg->header = header;
  msg->width = images.width;
  msg->height = images.height;
  msg->encoding = sensor_msgs::image_encodings::TYPE_32FC1;
  msg->is_bigendian = 0;
  msg->step = 4 * images.width;
  msg->data.resize(static_cast<size_t>(msg->step) * images.height);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  float* out = reinterpret_cast<float*>(msg->data.data());
  for (size_t i = 0; i < images.depth.size(); ++i)
    out[i] = isBackgroundPixel(images, i) ? nan : images.depth[i];
  return msg;
}

sensor_msgs::ImagePtr toPatchIdImage(const RenderImages& images, const std_msgs::Header& header) {
  checkSizes(images);
  if (images.patch_id.size() != images.depth.size())
    throw std::invalid_argument("render images: patch id buffer holds " +
                                std::to_string(images.patch_id.size()) + " pixels, expected " +
                                std::to_string(images.depth.size()));
  auto msg = boost::make_shared<sensor_msgs::Image>();
  msg->header = header;
  msg->width = images.width;
  msg->height = images.height;
  msg->encoding = sensor_msgs::image_encodings::TYPE_32SC1;
  msg->is_bigendian = 0;
  msg->step = 4 * images.width;
  msg->data.resize(static_cast<size_t>(msg->step) * images.height);
  int32_t* out = reinterpret_cast<int32_t*>(msg->data.data());
  for (size_t i = 0; i < images.depth.size(); ++i)
    out[i] = isBackgroundPixel(images, i) ? -1 : images.patch_id[i];
  return msg;
}

sensor_msgs::CameraInfoPtr toCameraInfo(const Camera& camera, const std_msgs::Header& header) {
  auto msg = boost::make_shared<sensor_msgs::CameraInfo>();
  msg->header = header;
  msg->width = camera.width;
  msg->height = camera.height;
  const bool ortho = camera.projection == Camera::Projection::kOrthographic;
  const double fx = ortho ? camera.ortho_scale : camera.fx;
  const double fy = ortho ? camera.ortho_scale : camera.fy;
  msg->distortion_model = ortho ? "orthographic" : "plumb_bob";
  msg->D.assign(ortho ? 0 : 5, 0.0);
  msg->K = {fx, 0, camera.cx, 0, fy, camera.cy, 0, 0, 1};
  msg->R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  msg->P = {fx, 0, camera.cx, 0, 0, fy, camera.cy, 0, 0, 0, 1, 0};
  return msg;
}

}  // namespace rc
