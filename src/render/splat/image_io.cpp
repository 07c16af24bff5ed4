#include "relaxed_connectivity/render/splat/image_io.h"

#include <array>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "relaxed_connectivity/render/splat/splat_config.h"  // RenderImages

// stb with internal linkage, so other translation units may include their own copies.
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#include <stb/stb_image.h>

namespace rc {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw std::runtime_error("image file '" + path + "': " + problem);
}

void checkSize(const std::string& path, size_t values, uint32_t width, uint32_t height, size_t per_pixel) {
  if (width == 0 || height == 0) fail(path, "empty image (width or height 0)");
  if (values != size_t(width) * height * per_pixel)
    fail(path, "pixel buffer holds " + std::to_string(values) + " values, expected " +
                   std::to_string(size_t(width) * height * per_pixel));
}

uint32_t crc32(const uint8_t* data, size_t size, uint32_t crc = 0) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t n = 0; n < 256; ++n) {
      uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (size_t i = 0; i < size; ++i) crc = table[(crc ^ data[i]) & 0xff] ^ (crc >> 8);
  return ~crc;
}

void appendBigEndian(std::vector<uint8_t>& bytes, uint32_t value) {
  for (int shift = 24; shift >= 0; shift -= 8) bytes.push_back(uint8_t(value >> shift));
}

void appendChunk(std::vector<uint8_t>& file, const char* type, const std::vector<uint8_t>& data) {
  appendBigEndian(file, uint32_t(data.size()));
  const size_t type_at = file.size();
  file.insert(file.end(), type, type + 4);
  file.insert(file.end(), data.begin(), data.end());
  appendBigEndian(file, crc32(file.data() + type_at, data.size() + 4));
}

void writeFile(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream file(path, std::ios::binary);
  if (!file) fail(path, "cannot open for writing");
  file.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!file) fail(path, "write failed");
}

}  // namespace

void writePng(const std::string& path, const std::vector<Rgba>& pixels, uint32_t width, uint32_t height) {
  checkSize(path, pixels.size(), width, height, 1);
  if (!stbi_write_png(path.c_str(), int(width), int(height), 4, pixels.data(), int(width * 4)))
    fail(path, "cannot write PNG");
}

std::vector<uint8_t> encodePng(const std::vector<Rgba>& pixels, uint32_t width, uint32_t height) {
  checkSize("(PNG in memory)", pixels.size(), width, height, 1);
  std::vector<uint8_t> bytes;
  auto append = [](void* context, void* data, int size) {
    auto* out = static_cast<std::vector<uint8_t>*>(context);
    out->insert(out->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
  };
  if (!stbi_write_png_to_func(append, &bytes, int(width), int(height), 4, pixels.data(), int(width * 4)))
    throw std::runtime_error("encodePng: cannot encode a " + std::to_string(width) + " x " +
                             std::to_string(height) + " image");
  return bytes;
}

std::vector<Rgba> readPng(const std::string& path, uint32_t* width, uint32_t* height) {
  int w = 0, h = 0, channels = 0;
  std::unique_ptr<uint8_t, void (*)(void*)> data(stbi_load(path.c_str(), &w, &h, &channels, 4),
                                                 stbi_image_free);
  if (!data) fail(path, std::string("cannot read PNG: ") + stbi_failure_reason());
  std::vector<Rgba> pixels(size_t(w) * h);
  std::memcpy(pixels.data(), data.get(), pixels.size() * 4);
  *width = uint32_t(w);
  *height = uint32_t(h);
  return pixels;
}

void writePfm(const std::string& path, const FloatImage& image) {
  if (image.channels != 1 && image.channels != 3)
    fail(path, "PFM needs 1 or 3 channels, got " + std::to_string(image.channels));
  checkSize(path, image.values.size(), image.width, image.height, size_t(image.channels));
  std::ostringstream header;
  header << (image.channels == 3 ? "PF" : "Pf") << "\n" << image.width << " " << image.height << "\n-1.0\n";
  const std::string text = header.str();
  std::vector<uint8_t> bytes(text.begin(), text.end());
  const size_t row_bytes = size_t(image.width) * image.channels * sizeof(float);
  const size_t start = bytes.size();
  bytes.resize(start + row_bytes * image.height);
  for (uint32_t y = 0; y < image.height; ++y)  // PFM rows run bottom to top; little endian ("-1.0")
    std::memcpy(bytes.data() + start + row_bytes * (image.height - 1 - y),
                image.values.data() + size_t(y) * image.width * image.channels, row_bytes);
  writeFile(path, bytes);
}

FloatImage readPfm(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) fail(path, "cannot open for reading");
  std::string magic;
  double scale = 0;
  FloatImage image;
  file >> magic >> image.width >> image.height >> scale;
  if (!file || (magic != "PF" && magic != "Pf")) fail(path, "not a PFM file (bad header)");
  if (scale >= 0) fail(path, "big-endian PFM is not supported");
  if (image.width == 0 || image.height == 0) fail(path, "empty image in PFM header");
  file.get();  // the single whitespace after the scale
  image.channels = magic == "PF" ? 3 : 1;
  const size_t row_values = size_t(image.width) * image.channels;
  image.values.resize(row_values * image.height);
  for (uint32_t y = 0; y < image.height; ++y)
    file.read(reinterpret_cast<char*>(image.values.data() + row_values * (image.height - 1 - y)),
              std::streamsize(row_values * sizeof(float)));
  if (!file) fail(path, "truncated PFM data");
  return image;
}

void writeGray16Png(const std::string& path, const std::vector<uint16_t>& values, uint32_t width,
                    uint32_t height) {
  checkSize(path, values.size(), width, height, 1);
  // Raw scanlines (filter 0: constant regions, as in patch-id images, deflate to almost nothing), 16-bit
  // big-endian samples.
  std::vector<uint8_t> raw;
  raw.reserve(size_t(height) * (1 + 2 * width));
  for (uint32_t y = 0; y < height; ++y) {
    raw.push_back(0);
    for (uint32_t x = 0; x < width; ++x) {
      const uint16_t value = values[size_t(y) * width + x];
      raw.push_back(uint8_t(value >> 8));
      raw.push_back(uint8_t(value));
    }
  }
  // Deflate by stb_image_write's compressor (a zlib stream with its Adler-32).
  int compressed_size = 0;
  std::unique_ptr<unsigned char, void (*)(void*)> compressed(
      stbi_zlib_compress(raw.data(), int(raw.size()), &compressed_size, 8), free);
  if (!compressed) fail(path, "cannot compress the 16-bit PNG data");
  const std::vector<uint8_t> zlib(compressed.get(), compressed.get() + compressed_size);

  std::vector<uint8_t> file = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<uint8_t> header;
  appendBigEndian(header, width);
  appendBigEndian(header, height);
  header.insert(header.end(), {16, 0, 0, 0, 0});  // 16 bit, greyscale, deflate, filter 0, no interlace
  appendChunk(file, "IHDR", header);
  appendChunk(file, "IDAT", zlib);
  appendChunk(file, "IEND", {});
  writeFile(path, file);
}

std::vector<uint16_t> readGray16Png(const std::string& path, uint32_t* width, uint32_t* height) {
  int w = 0, h = 0, channels = 0;
  std::unique_ptr<uint16_t, void (*)(void*)> data(stbi_load_16(path.c_str(), &w, &h, &channels, 1),
                                                  stbi_image_free);
  if (!data) fail(path, std::string("cannot read 16-bit PNG: ") + stbi_failure_reason());
  *width = uint32_t(w);
  *height = uint32_t(h);
  return std::vector<uint16_t>(data.get(), data.get() + size_t(w) * size_t(h));
}

void writePatchIdPng(const std::string& path, const std::vector<int32_t>& patch_ids, uint32_t width,
                     uint32_t height) {
  checkSize(path, patch_ids.size(), width, height, 1);
  std::vector<uint16_t> values(patch_ids.size());
  for (size_t i = 0; i < values.size(); ++i) {
    if (patch_ids[i] < -1 || patch_ids[i] > 65534)
      fail(path, "patch id " + std::to_string(patch_ids[i]) + " does not fit 16 bits");
    values[i] = uint16_t(patch_ids[i] + 1);
  }
  writeGray16Png(path, values, width, height);
}

std::vector<int32_t> readPatchIdPng(const std::string& path, uint32_t* width, uint32_t* height) {
  const std::vector<uint16_t> values = readGray16Png(path, width, height);
  std::vector<int32_t> ids(values.size());
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = int32_t(values[i]) - 1;
  return ids;
}

void writeRenderImages(const std::string& prefix, const RenderImages& images) {
  const uint32_t width = images.width, height = images.height;
  writePng(prefix + "_color.png", images.color, width, height);
  FloatImage depth{width, height, 1, images.depth};
  writePfm(prefix + "_depth.pfm", depth);
  FloatImage weight{width, height, 1, images.weight};
  writePfm(prefix + "_weight.pfm", weight);
  FloatImage normal{width, height, 3, {}};
  normal.values.reserve(images.normal.size() * 3);
  for (const Eigen::Vector3f& n : images.normal)
    normal.values.insert(normal.values.end(), {n.x(), n.y(), n.z()});
  writePfm(prefix + "_normal.pfm", normal);
  writePatchIdPng(prefix + "_patch.png", images.patch_id, width, height);
}

}  // namespace rc
