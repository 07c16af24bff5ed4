#include "relaxed_connectivity/render/splat/image_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "relaxed_connectivity/render/splat/surfel_renderer.h"

namespace rc {
namespace {

std::string tempPath(const std::string& name) {
  return "/tmp/rc_test_image_io_" + std::to_string(::getpid()) + "_" + name;
}

TEST(ImageIo, PfmRoundTripOneAndThreeChannels) {
  for (int channels : {1, 3}) {
    FloatImage image{7, 5, channels, {}};
    for (size_t i = 0; i < size_t(7 * 5 * channels); ++i) image.values.push_back(0.25f * float(i) - 3.0f);
    image.values[3] = std::numeric_limits<float>::infinity();
    const std::string path = tempPath("image.pfm");
    writePfm(path, image);
    const FloatImage back = readPfm(path);
    EXPECT_EQ(back.width, 7u);
    EXPECT_EQ(back.height, 5u);
    EXPECT_EQ(back.channels, channels);
    ASSERT_EQ(back.values.size(), image.values.size());
    for (size_t i = 0; i < image.values.size(); ++i) EXPECT_EQ(back.values[i], image.values[i]) << i;
    std::remove(path.c_str());
  }
}

TEST(ImageIo, PngAndPatchIdRoundTrip) {
  const uint32_t width = 300, height = 200;  // raw 16-bit data > 65535 bytes
  std::vector<Rgba> colors(width * height);
  std::vector<int32_t> ids(width * height);
  for (size_t i = 0; i < ids.size(); ++i) {
    colors[i] = {uint8_t(i), uint8_t(i / 7), uint8_t(255 - i % 256), 255};
    ids[i] = int32_t(i % 65536) - 1;  // -1 .. 65534
  }
  const std::string png = tempPath("color.png"), patch = tempPath("patch.png");
  writePng(png, colors, width, height);
  writePatchIdPng(patch, ids, width, height);
  uint32_t w = 0, h = 0;
  EXPECT_EQ(readPng(png, &w, &h), colors);
  EXPECT_EQ(w, width);
  EXPECT_EQ(h, height);
  EXPECT_EQ(readPatchIdPng(patch, &w, &h), ids);
  std::remove(png.c_str());
  std::remove(patch.c_str());
}

TEST(ImageIo, PatchIdPngsAreDeflated) {
  // A 1280 x 720 patch-id image of a few regions (as rendered scenes give): raw 16-bit rows are 1.8 MB;
  // deflated they are a few kB, and read back exactly.
  const uint32_t width = 1280, height = 720;
  std::vector<int32_t> ids(size_t(width) * height, -1);
  for (uint32_t y = 0; y < height; ++y)
    for (uint32_t x = 0; x < width; ++x) {
      const double dx = x - 640.0, dy = y - 360.0;
      if (dx * dx + dy * dy < 300.0 * 300.0) ids[size_t(y) * width + x] = dx < 0 ? 3 : 7;
    }
  const std::string patch = tempPath("patch_regions.png");
  writePatchIdPng(patch, ids, width, height);
  FILE* file = std::fopen(patch.c_str(), "rb");
  ASSERT_TRUE(file);
  std::fseek(file, 0, SEEK_END);
  const long size = std::ftell(file);
  std::fclose(file);
  std::printf("patch-id PNG 1280 x 720, three regions: %ld bytes (raw rows %zu)\n", size,
              size_t(height) * (1 + 2 * width));
  EXPECT_LT(size, 40000);  // the raw rows: 1.84 MB
  uint32_t w = 0, h = 0;
  EXPECT_EQ(readPatchIdPng(patch, &w, &h), ids);
  std::remove(patch.c_str());
}

TEST(ImageIo, ErrorsNameTheFile) {
  const std::string missing = tempPath("does_not_exist.pfm");
  try {
    readPfm(missing);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find(missing), std::string::npos);
  }
  EXPECT_THROW(writePatchIdPng(tempPath("bad.png"), {70000}, 1, 1), std::runtime_error);
  EXPECT_THROW(writePfm(tempPath("bad.pfm"), FloatImage{2, 2, 2, std::vector<float>(8)}), std::runtime_error);
  EXPECT_THROW(writePng(tempPath("bad.png"), std::vector<Rgba>(3), 2, 2), std::runtime_error);
}

TEST(ImageIo, WritesAllRenderImages) {
  RenderImages images;
  images.width = 4;
  images.height = 3;
  images.color.assign(12, Rgba{1, 2, 3, 255});
  images.depth.assign(12, 2.5f);
  images.normal.assign(12, Eigen::Vector3f(0, 0, -1));
  images.weight.assign(12, 0.5f);
  images.patch_id.assign(12, 4);
  const std::string prefix = tempPath("render");
  writeRenderImages(prefix, images);
  const FloatImage normal = readPfm(prefix + "_normal.pfm");
  EXPECT_EQ(normal.channels, 3);
  EXPECT_EQ(normal.values[2], -1.0f);
  EXPECT_EQ(readPfm(prefix + "_depth.pfm").values[5], 2.5f);
  uint32_t w, h;
  EXPECT_EQ(readPatchIdPng(prefix + "_patch.png", &w, &h)[11], 4);
  for (const char* suffix : {"_color.png", "_depth.pfm", "_normal.pfm", "_weight.pfm", "_patch.png"})
    std::remove((prefix + suffix).c_str());
}

}  // namespace
}  // namespace rc
