#include <gtest/gtest.h>

#include "io_test_support.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/pcd_io.h"

namespace rc {
namespace {

using test::expectCloudsEqual;
using test::tempPath;
using test::writeText;

template <typename T>
void appendRaw(std::string* out, T value) {
  out->append(reinterpret_cast<const char*>(&value), sizeof(T));
}

TEST(PcdIo, RichCloudRoundTripsBitExactlyInEveryEncoding) {
  const SurfelCloud cloud = test::makeRichCloud(301);
  for (Encoding e : {Encoding::kAscii, Encoding::kBinary, Encoding::kBinaryCompressed}) {
    SCOPED_TRACE(static_cast<int>(e));
    const std::string path = tempPath("rich.pcd");
    WriteOptions options;
    options.encoding = e;
    writePcdCloud(path, cloud, options);
    expectCloudsEqual(cloud, readPcdCloud(path));
    options.double_precision = true;
    writePcdCloud(path, cloud, options);
    expectCloudsEqual(cloud, readPcdCloud(path));
  }
}

TEST(PcdIo, OrganisedCloudKeepsNaNsAndShapeUnlessAskedToDrop) {
  SurfelCloud cloud;
  cloud.width = 4;
  cloud.height = 5;
  size_t invalid = 0;
  for (int i = 0; i < 20; ++i) {
    const bool hole = i % 3 == 1;
    invalid += hole;
    cloud.positions.emplace_back(hole ? std::nan("") : i * 0.25, -i * 0.5, 1.0 + i);
    cloud.colors.push_back(Rgba{uint8_t(i), uint8_t(2 * i), uint8_t(3 * i), 255});
  }
  for (Encoding e : {Encoding::kAscii, Encoding::kBinary, Encoding::kBinaryCompressed}) {
    const std::string path = tempPath("organised.pcd");
    writePcdCloud(path, cloud, WriteOptions{e, false, false});
    const SurfelCloud all = readPcdCloud(path);
    EXPECT_EQ(all.width, 4u);
    EXPECT_EQ(all.height, 5u);
    EXPECT_TRUE(all.isOrganized());
    expectCloudsEqual(cloud, all);
    ReadOptions drop;
    drop.keep_invalid = false;
    const SurfelCloud valid = readPcdCloud(path, drop);
    EXPECT_EQ(valid.size(), 20 - invalid);
    EXPECT_FALSE(valid.isOrganized());
    EXPECT_EQ(valid.positions[1], Vec3(0.5, -1.0, 3.0));  // point 2 (point 1 was a hole)
    EXPECT_EQ(valid.colors[1], (Rgba{2, 4, 6, 255}));
  }
}

TEST(PcdIo, AsciiWithPaddingPackedRgbAndCountedFields) {
  // an old-style header: no VERSION, VIEWPOINT or HEIGHT
  const std::string pcd =
      "# hand written\nFIELDS x y z _ rgb histogram label\nSIZE 4 4 4 4 4 2 1\nTYPE F F F F F U I\n"
      "COUNT 1 1 1 1 1 3 1\nPOINTS 2\nDATA ascii\n"
      "1 2 3 0 4.2108e+06 1 2 3 -5\n"
      "nan nan nan 0 0 65535 0 7 127\n";
  const std::string path = tempPath("hand.pcd");
  writeText(path, pcd);
  const SurfelCloud cloud = readPcdCloud(path);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.width, 0u);  // unorganised
  EXPECT_EQ(cloud.positions[0], Vec3(1, 2, 3));
  EXPECT_TRUE(std::isnan(cloud.positions[1].x()));
  // 4.2108e+06f has the bit pattern 0x4A808280: r = 0x80, g = 0x82, b = 0x80; "rgb" gets alpha 255
  float packed_float = 4.2108e+06f;
  uint32_t bits;
  std::memcpy(&bits, &packed_float, 4);
  ASSERT_TRUE(cloud.hasColors());
  EXPECT_EQ(cloud.colors[0], (Rgba{uint8_t(bits >> 16), uint8_t(bits >> 8), uint8_t(bits), 255}));
  EXPECT_EQ(cloud.colors[1], (Rgba{0, 0, 0, 255}));
  const Attribute* histogram = cloud.attributes.find("histogram");
  ASSERT_NE(histogram, nullptr);
  EXPECT_EQ(histogram->type, ScalarType::kUInt16);
  EXPECT_EQ(histogram->count, 3u);
  EXPECT_EQ(histogram->get(1, 0), 65535.0);
  EXPECT_EQ(histogram->get(1, 2), 7.0);
  const Attribute* label = cloud.attributes.find("label");
  ASSERT_NE(label, nullptr);
  EXPECT_EQ(label->type, ScalarType::kInt8);
  EXPECT_EQ(label->get(0), -5.0);
  EXPECT_EQ(cloud.attributes.columns().size(), 2u);  // "_" is dropped
}

TEST(PcdIo, ReadsHandBuiltCompressedFieldMajorData) {
  // Three points, fields x (F4), y (F4), z (F4), intensity (U2); field-major arrays, stored as LZF literal
  // runs (control byte n-1 followed by n bytes), written without the library's compressor.
  const float xs[3] = {1, 2, 3}, ys[3] = {-1, -2, -3}, zs[3] = {0.5f, 0.25f, 0.125f};
  const uint16_t intensity[3] = {100, 200, 300};
  std::string raw;
  for (float v : xs) appendRaw(&raw, v);
  for (float v : ys) appendRaw(&raw, v);
  for (float v : zs) appendRaw(&raw, v);
  for (uint16_t v : intensity) appendRaw(&raw, v);
  std::string lzf;
  for (size_t start = 0; start < raw.size(); start += 32) {
    const size_t n = std::min<size_t>(32, raw.size() - start);
    lzf.push_back(static_cast<char>(n - 1));
    lzf.append(raw, start, n);
  }
  std::string pcd =
      "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 2\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 3\nHEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA binary_compressed\n";
  appendRaw<uint32_t>(&pcd, static_cast<uint32_t>(lzf.size()));
  appendRaw<uint32_t>(&pcd, static_cast<uint32_t>(raw.size()));
  pcd += lzf;
  const std::string path = tempPath("hand_compressed.pcd");
  writeText(path, pcd);
  const SurfelCloud cloud = readPcdCloud(path);
  ASSERT_EQ(cloud.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(cloud.positions[i], Vec3(xs[i], ys[i], zs[i]));
  const Attribute* a = cloud.attributes.find("intensity");
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->get(2), 300.0);
}

TEST(PcdIo, UnsupportedTypeIsNamed) {
  const std::string path = tempPath("u8.pcd");
  writeText(path,
            "VERSION 0.7\nFIELDS x y z stamp\nSIZE 4 4 4 8\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 1\nHEIGHT 1\n"
            "POINTS 1\nDATA ascii\n0 0 0 12\n");
  try {
    readPcdCloud(path);
    FAIL() << "no exception";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("u8.pcd"), std::string::npos) << what;
    EXPECT_NE(what.find("'stamp' has unsupported TYPE U SIZE 8"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace rc
