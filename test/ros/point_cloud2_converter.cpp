// rc::PointCloud2Converter: pcl::PointSurfel layout (checked against pcl::toROSMsg), extra and unknown fields
// (bit-exact round trip), organised clouds, plain scanner clouds, and clear errors for malformed messages.
#include <gtest/gtest.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl_conversions/pcl_conversions.h>
#include <ros/ros.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {
namespace {

using sensor_msgs::PointField;

float bitsToFloat(uint32_t bits) {
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

template <typename T>
T readAt(const sensor_msgs::PointCloud2& msg, size_t point, const std::string& field,
         uint32_t component = 0) {
  for (const auto& f : msg.fields)
    if (f.name == field) {
      T v;
      std::memcpy(&v, msg.data.data() + point * msg.point_step + f.offset + component * sizeof(T), sizeof(T));
      return v;
    }
  ADD_FAILURE() << "no field " << field;
  return T();
}

/// A random surfel cloud with every channel of pcl::PointSurfel, values exactly representable as float.
SurfelCloud randomSurfels(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-2.f, 2.f);
  std::uniform_int_distribution<int> byte(0, 255);
  SurfelCloud c;
  for (size_t i = 0; i < n; ++i) {
    c.positions.emplace_back(u(rng), u(rng), u(rng));
    c.normals.push_back(Vec3(u(rng), u(rng), u(rng)).cast<float>().cast<double>());
    c.radii.push_back(std::abs(u(rng)));
    c.colors.push_back({uint8_t(byte(rng)), uint8_t(byte(rng)), uint8_t(byte(rng)), uint8_t(byte(rng))});
    c.confidence.push_back(u(rng));
    c.curvature.push_back(u(rng));
  }
  c.frame_id = "world";
  c.stamp_ns = 1234567890123ull;
  return c;
}

std::string errorOf(const sensor_msgs::PointCloud2& msg) {
  try {
    PointCloud2Converter::fromMessage(msg);
  } catch (const PointCloud2Error& e) {
    return e.what();
  }
  return "";
}

TEST(PointCloud2Converter, PointSurfelLayoutIsByteIdenticalToPclToRosMsg) {
  const SurfelCloud cloud = randomSurfels(37, 1);
  pcl::PointCloud<pcl::PointSurfel> pcl_cloud;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud.positions[i];
    const auto& n = cloud.normals[i];
    const auto& c = cloud.colors[i];
    pcl_cloud.push_back(pcl::PointSurfel(p.x(), p.y(), p.z(), n.x(), n.y(), n.z(), c[0], c[1], c[2], c[3],
                                         cloud.radii[i], cloud.confidence[i], cloud.curvature[i]));
  }
  sensor_msgs::PointCloud2 expected, actual;
  pcl::toROSMsg(pcl_cloud, expected);
  PointCloud2Converter::toMessage(cloud, actual);

  EXPECT_EQ(sizeof(pcl::PointSurfel), 48u);
  EXPECT_EQ(actual.point_step, 48u);
  ASSERT_EQ(actual.fields.size(), expected.fields.size());
  for (size_t i = 0; i < expected.fields.size(); ++i) {
    EXPECT_EQ(actual.fields[i].name, expected.fields[i].name);
    EXPECT_EQ(actual.fields[i].offset, expected.fields[i].offset) << expected.fields[i].name;
    EXPECT_EQ(actual.fields[i].datatype, expected.fields[i].datatype) << expected.fields[i].name;
    EXPECT_EQ(actual.fields[i].count, expected.fields[i].count) << expected.fields[i].name;
  }
  EXPECT_EQ(actual.point_step, expected.point_step);
  EXPECT_EQ(actual.row_step, expected.row_step);
  EXPECT_EQ(actual.width, expected.width);
  EXPECT_EQ(actual.height, expected.height);
  EXPECT_TRUE(actual.data == expected.data) << "data bytes differ from pcl::toROSMsg";
  EXPECT_TRUE(PointCloud2Converter::hasPointSurfelLayout(actual));
  EXPECT_EQ(actual.header.frame_id, "world");
  EXPECT_EQ(actual.header.stamp.toNSec(), 1234567890123ull);

  // And PCL reads our message back to the same values.
  pcl::PointCloud<pcl::PointSurfel> back;
  pcl::fromROSMsg(actual, back);
  ASSERT_EQ(back.size(), cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_EQ(back[i].x, float(cloud.positions[i].x()));
    EXPECT_EQ(back[i].normal_z, float(cloud.normals[i].z()));
    EXPECT_EQ(back[i].r, cloud.colors[i][0]);
    EXPECT_EQ(back[i].a, cloud.colors[i][3]);
    EXPECT_EQ(back[i].radius, float(cloud.radii[i]));
    EXPECT_EQ(back[i].curvature, cloud.curvature[i]);
  }
}

TEST(PointCloud2Converter, ReadsPclSurfelsExactly) {
  pcl::PointCloud<pcl::PointSurfel> pcl_cloud;
  pcl_cloud.push_back(
      pcl::PointSurfel(1.5f, -2.f, 3.25f, 0.f, 0.6f, 0.8f, 10, 20, 30, 40, 0.01f, 0.5f, 0.125f));
  pcl_cloud.push_back(pcl::PointSurfel(-1.f, 0.f, 7.f, 1.f, 0.f, 0.f, 255, 0, 128, 255, 0.02f, 1.f, 0.f));
  sensor_msgs::PointCloud2 msg;
  pcl::toROSMsg(pcl_cloud, msg);
  const SurfelCloud c = PointCloud2Converter::fromMessage(msg);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_TRUE(c.attributes.empty()) << "PointSurfel has no unknown fields";
  EXPECT_EQ(c.positions[0], Vec3(1.5, -2.0, 3.25));
  EXPECT_EQ(c.normals[0], Vec3(0.0, double(0.6f), double(0.8f)));
  EXPECT_EQ(c.colors[0], (Rgba{10, 20, 30, 40}));
  EXPECT_EQ(c.colors[1], (Rgba{255, 0, 128, 255}));
  EXPECT_EQ(c.radii[1], double(0.02f));
  EXPECT_EQ(c.confidence[0], 0.5f);
  EXPECT_EQ(c.curvature[0], 0.125f);
  EXPECT_EQ(c.width, 0u);
  EXPECT_EQ(c.height, 0u);
}

TEST(PointCloud2Converter, ExtraChannelsAndAttributesRoundTripBitExactly) {
  SurfelCloud cloud = randomSurfels(11, 2);
  for (size_t i = 0; i < cloud.size(); ++i) {
    cloud.axes1.emplace_back(0.25 * i, 0.5, -1.0);
    cloud.axes2.emplace_back(0.0, 0.125, 2.0 * i);
  }
  cloud.attributes.add("patch_id", ScalarType::kUInt16, 1, cloud.size());
  cloud.attributes.add("paint", ScalarType::kFloat64, 3, cloud.size());
  cloud.attributes.add("flag", ScalarType::kInt8, 1, cloud.size());
  Attribute& patch = *cloud.attributes.find("patch_id");  // (references taken after all columns exist)
  Attribute& paint = *cloud.attributes.find("paint");
  Attribute& flag = *cloud.attributes.find("flag");
  for (size_t i = 0; i < cloud.size(); ++i) {
    patch.set(i, 1000 + i);
    for (uint32_t k = 0; k < 3; ++k) paint.set(i, 0.1 * i + k / 3.0, k);
    flag.set(i, -int(i));
  }
  // A NaN with a payload must survive unchanged.
  const double nan_payload = [] {
    uint64_t bits = 0x7ff8000000001234ull;
    double d;
    std::memcpy(&d, &bits, 8);
    return d;
  }();
  std::memcpy(paint.bytes.data() + 8, &nan_payload, 8);

  sensor_msgs::PointCloud2 msg;
  PointCloud2Converter::toMessage(cloud, msg);
  // Base layout first, then the axes, then the attributes, naturally aligned.
  std::vector<std::string> names;
  for (const auto& f : msg.fields) names.push_back(f.name);
  const std::vector<std::string> expected_names = {
      "x",      "y",          "z",         "normal_x", "normal_y", "normal_z", "rgba",
      "radius", "confidence", "curvature", "t1x",      "t1y",      "t1z",      "t2x",
      "t2y",    "t2z",        "patch_id",  "paint",    "flag"};
  EXPECT_EQ(names, expected_names);
  EXPECT_EQ(msg.fields[10].offset, 48u);
  EXPECT_EQ(msg.fields[16].offset, 72u);  // uint16 after 6 floats
  EXPECT_EQ(msg.fields[16].datatype, PointField::UINT16);
  EXPECT_EQ(msg.fields[17].offset, 80u);  // float64 x 3, 8-byte aligned
  EXPECT_EQ(msg.fields[17].count, 3u);
  EXPECT_EQ(msg.fields[18].offset, 104u);
  EXPECT_EQ(msg.fields[18].datatype, PointField::INT8);
  EXPECT_EQ(msg.point_step, 108u);
  EXPECT_EQ(readAt<uint16_t>(msg, 4, "patch_id"), 1004);
  EXPECT_EQ(readAt<float>(msg, 4, "t2z"), 8.0f);

  const SurfelCloud back = PointCloud2Converter::fromMessage(msg);
  ASSERT_EQ(back.size(), cloud.size());
  ASSERT_TRUE(back.hasAxes());
  EXPECT_EQ(back.axes2[4], Vec3(0.0, 0.125, 8.0));
  ASSERT_EQ(back.attributes.columns().size(), 3u);
  for (const auto& a : cloud.attributes.columns()) {
    const Attribute* b = back.attributes.find(a.name);
    ASSERT_NE(b, nullptr) << a.name;
    EXPECT_EQ(b->type, a.type) << a.name;
    EXPECT_EQ(b->count, a.count) << a.name;
    EXPECT_TRUE(b->bytes == a.bytes) << a.name << " not bit-exact";
  }
  sensor_msgs::PointCloud2 again;
  PointCloud2Converter::toMessage(back, again);
  EXPECT_EQ(again.point_step, msg.point_step);
  EXPECT_TRUE(again.data == msg.data) << "second round trip changed bytes";
}

/// A scanner-like message: x y z float32, "intensity" float32 and "ring" uint16 (unknown to the converter),
/// organised 4 x 3 with NaN pixels and padded rows.
sensor_msgs::PointCloud2 organisedScan() {
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = "scanner_optical";
  msg.width = 4;
  msg.height = 3;
  msg.point_step = 20;
  msg.row_step = 4 * 20 + 8;  // row padding
  msg.fields = {};
  auto field = [](const std::string& n, uint32_t off, uint8_t type) {
    PointField f;
    f.name = n;
    f.offset = off;
    f.datatype = type;
    f.count = 1;
    return f;
  };
  msg.fields = {field("x", 0, PointField::FLOAT32), field("y", 4, PointField::FLOAT32),
                field("z", 8, PointField::FLOAT32), field("intensity", 12, PointField::FLOAT32),
                field("ring", 16, PointField::UINT16)};
  msg.data.assign(msg.row_step * msg.height, 0xAB);
  for (uint32_t r = 0; r < 3; ++r)
    for (uint32_t c = 0; c < 4; ++c) {
      uint8_t* p = msg.data.data() + r * msg.row_step + c * msg.point_step;
      const bool invalid = (r + c) % 5 == 0;
      const float nan = std::numeric_limits<float>::quiet_NaN();
      const float xyz[3] = {invalid ? nan : float(c), invalid ? nan : float(r), invalid ? nan : 2.0f};
      std::memcpy(p, xyz, 12);
      const float intensity = bitsToFloat(0x7fc00000u | (r * 4 + c));  // NaN payload
      std::memcpy(p + 12, &intensity, 4);
      const uint16_t ring = uint16_t(100 * r + c);
      std::memcpy(p + 16, &ring, 2);
    }
  return msg;
}

TEST(PointCloud2Converter, OrganisedCloudKeepsShapeAndUnknownFieldsBitExactly) {
  const sensor_msgs::PointCloud2 msg = organisedScan();
  const SurfelCloud c = PointCloud2Converter::fromMessage(msg);
  ASSERT_EQ(c.size(), 12u);
  EXPECT_EQ(c.width, 4u);
  EXPECT_EQ(c.height, 3u);
  EXPECT_TRUE(c.isOrganized());
  EXPECT_EQ(c.frame_id, "scanner_optical");
  EXPECT_FALSE(c.positions[0].allFinite());
  EXPECT_EQ(c.positions[6], Vec3(2.0, 1.0, 2.0));  // row 1, column 2
  EXPECT_FALSE(c.hasNormals());
  EXPECT_FALSE(c.hasColors());
  const Attribute* ring = c.attributes.find("ring");
  const Attribute* intensity = c.attributes.find("intensity");
  ASSERT_NE(ring, nullptr);
  ASSERT_NE(intensity, nullptr);
  EXPECT_EQ(ring->type, ScalarType::kUInt16);
  EXPECT_EQ(ring->get(6), 102.0);

  sensor_msgs::PointCloud2 out;
  PointCloud2Converter::toMessage(c, out, PointCloud2Layout::kCompact);
  EXPECT_EQ(out.width, 4u);
  EXPECT_EQ(out.height, 3u);
  EXPECT_EQ(out.point_step, 20u);  // x y z intensity ring (+2 bytes padding)
  EXPECT_FALSE(out.is_dense);
  for (size_t i = 0; i < 12; ++i) {
    uint32_t bits;
    const float v = readAt<float>(out, i, "intensity");
    std::memcpy(&bits, &v, 4);
    EXPECT_EQ(bits, 0x7fc00000u | uint32_t(i)) << "intensity payload of point " << i;
    EXPECT_EQ(readAt<uint16_t>(out, i, "ring"), uint16_t(100 * (i / 4) + i % 4));
  }
}

TEST(PointCloud2Converter, ReadsPlainXyzFloat64AndPclXyzrgb) {
  pcl::PointCloud<pcl::PointXYZRGB> rgb_cloud;
  pcl::PointXYZRGB p(uint8_t(200), uint8_t(100), uint8_t(50));
  p.x = 1.f;
  p.y = 2.f;
  p.z = 3.f;
  rgb_cloud.push_back(p);
  sensor_msgs::PointCloud2 rgb_msg;
  pcl::toROSMsg(rgb_cloud, rgb_msg);
  const SurfelCloud c = PointCloud2Converter::fromMessage(rgb_msg);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.positions[0], Vec3(1, 2, 3));
  ASSERT_TRUE(c.hasColors());
  EXPECT_EQ(c.colors[0], (Rgba{200, 100, 50, 255}));
  EXPECT_TRUE(c.attributes.empty());

  sensor_msgs::PointCloud2 msg;
  msg.width = 2;
  msg.height = 1;
  msg.point_step = 24;
  msg.row_step = 48;
  for (int k = 0; k < 3; ++k) {
    PointField f;
    f.name = std::string(1, char('x' + k));
    f.offset = 8 * k;
    f.datatype = PointField::FLOAT64;
    f.count = 1;
    msg.fields.push_back(f);
  }
  const double values[6] = {0.1, 0.2, 0.3, -1e10, 5.5, 1.0 / 3.0};
  msg.data.resize(48);
  std::memcpy(msg.data.data(), values, 48);
  const SurfelCloud d = PointCloud2Converter::fromMessage(msg);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d.positions[0], Vec3(0.1, 0.2, 0.3));  // double precision kept
  EXPECT_EQ(d.positions[1], Vec3(-1e10, 5.5, 1.0 / 3.0));
}

TEST(PointCloud2Converter, CompactLayoutHoldsOnlyPresentChannels) {
  SurfelCloud c;
  c.positions = {Vec3(1, 2, 3), Vec3(4, 5, 6)};
  c.colors = {Rgba{1, 2, 3, 4}, Rgba{5, 6, 7, 8}};
  const auto msg = PointCloud2Converter::toMessage(c, PointCloud2Layout::kCompact);
  ASSERT_EQ(msg->fields.size(), 4u);
  EXPECT_EQ(msg->fields[3].name, "rgba");
  EXPECT_EQ(msg->fields[3].offset, 12u);
  EXPECT_EQ(msg->point_step, 16u);
  EXPECT_EQ(readAt<uint32_t>(*msg, 1, "rgba"),
            (8u << 24) | (5u << 16) | (6u << 8) | 7u);  // a r g b as in PCL
  EXPECT_TRUE(msg->is_dense);
  EXPECT_FALSE(PointCloud2Converter::hasPointSurfelLayout(*msg));
}

TEST(PointCloud2Converter, EmptyCloudIsValid) {
  SurfelCloud empty;
  const auto msg = PointCloud2Converter::toMessage(empty);
  EXPECT_EQ(msg->width, 0u);
  EXPECT_EQ(msg->height, 1u);
  EXPECT_TRUE(msg->data.empty());
  EXPECT_TRUE(PointCloud2Converter::fromMessage(*msg).empty());
}

TEST(PointCloud2Converter, MalformedMessagesThrowNamingTheProblem) {
  const sensor_msgs::PointCloud2 good = organisedScan();
  ASSERT_EQ(errorOf(good), "");

  auto without_z = good;
  without_z.fields.erase(without_z.fields.begin() + 2);
  EXPECT_NE(errorOf(without_z).find("missing field 'z'"), std::string::npos) << errorOf(without_z);

  auto bad_type = good;
  bad_type.fields[3].datatype = 9;
  EXPECT_NE(errorOf(bad_type).find("'intensity' has unsupported datatype 9"), std::string::npos)
      << errorOf(bad_type);

  auto int_x = good;
  int_x.fields[0].datatype = PointField::INT32;
  EXPECT_NE(errorOf(int_x).find("'x' has datatype INT32"), std::string::npos) << errorOf(int_x);

  auto short_data = good;
  short_data.data.pop_back();
  EXPECT_NE(errorOf(short_data).find("data holds"), std::string::npos) << errorOf(short_data);

  auto bad_row = good;
  bad_row.row_step = 4 * 20 - 1;
  bad_row.data.resize(bad_row.row_step * bad_row.height);
  EXPECT_NE(errorOf(bad_row).find("row_step"), std::string::npos) << errorOf(bad_row);

  auto outside = good;
  outside.fields[4].offset = 19;  // uint16 at 19..21 > point_step 20
  EXPECT_NE(errorOf(outside).find("'ring'"), std::string::npos) << errorOf(outside);
  EXPECT_NE(errorOf(outside).find("point_step"), std::string::npos) << errorOf(outside);

  auto twice = good;
  twice.fields[3].name = "ring";
  EXPECT_NE(errorOf(twice).find("'ring' appears twice"), std::string::npos) << errorOf(twice);

  auto big_endian = good;
  big_endian.is_bigendian = true;
  EXPECT_NE(errorOf(big_endian).find("big-endian"), std::string::npos);

  auto partial_normals = good;
  partial_normals.fields[3].name = "normal_x";
  EXPECT_NE(errorOf(partial_normals).find("'normal_y' is missing"), std::string::npos)
      << errorOf(partial_normals);

  auto zero_count = good;
  zero_count.fields[1].count = 0;
  EXPECT_NE(errorOf(zero_count).find("'y' has count 0"), std::string::npos) << errorOf(zero_count);
}

TEST(PointCloud2Converter, AttributeNamedLikeALayoutFieldIsRejected) {
  SurfelCloud c;
  c.positions = {Vec3(0, 0, 0)};
  c.attributes.add("radius", ScalarType::kFloat32, 1, 1);
  sensor_msgs::PointCloud2 msg;
  try {
    PointCloud2Converter::toMessage(c, msg);
    FAIL() << "expected PointCloud2Error";
  } catch (const PointCloud2Error& e) {
    EXPECT_NE(std::string(e.what()).find("'radius'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
