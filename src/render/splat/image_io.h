// Image files for the renderer's outputs: 8-bit PNG colour, PFM float images (depth, normals, weights) and
// 16-bit PNG patch-id images, with readers for tests and tools. Errors throw std::runtime_error naming the
// file.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

struct RenderImages;

/// Row-major float image, top row first, `channels` (1 or 3) interleaved values per pixel.
struct FloatImage {
  uint32_t width = 0, height = 0;
  int channels = 1;
  std::vector<float> values;
};

/// 8-bit RGBA PNG (rows top to bottom).
void writePng(const std::string& path, const std::vector<Rgba>& pixels, uint32_t width, uint32_t height);
/// The bytes of an 8-bit RGBA PNG file of the image (for containers such as glTF binaries).
std::vector<uint8_t> encodePng(const std::vector<Rgba>& pixels, uint32_t width, uint32_t height);
/// Reads an 8-bit PNG (any channel count) as RGBA.
std::vector<Rgba> readPng(const std::string& path, uint32_t* width, uint32_t* height);

/// Portable float map: "Pf" (1 channel) or "PF" (3 channels), little endian, stored bottom row first as the
/// format requires. Non-finite values (background depth +inf) are written as they are.
void writePfm(const std::string& path, const FloatImage& image);
FloatImage readPfm(const std::string& path);

/// 16-bit greyscale PNG (rows top to bottom; deflated), and its reader (any 8- or 16-bit PNG, as
/// 16-bit grey).
void writeGray16Png(const std::string& path, const std::vector<uint16_t>& values, uint32_t width,
                    uint32_t height);
std::vector<uint16_t> readGray16Png(const std::string& path, uint32_t* width, uint32_t* height);
/// 16-bit greyscale PNG of patch ids shifted by one (background -1 -> 0). Throws for ids outside [-1, 65534].
void writePatchIdPng(const std::string& path, const std::vector<int32_t>& patch_ids, uint32_t width,
                     uint32_t height);
std::vector<int32_t> readPatchIdPng(const std::string& path, uint32_t* width, uint32_t* height);

/// Writes <prefix>_color.png, <prefix>_depth.pfm, <prefix>_normal.pfm, <prefix>_weight.pfm,
/// <prefix>_patch.png.
void writeRenderImages(const std::string& prefix, const RenderImages& images);

}  // namespace rc
