// The field mapping shared by PLY, PCD and the PointCloud2 converter: names and order per format, reading
// aliases, PointCloud2's strict rules, strided value ranges and the PointField datatype codes.
#include <gtest/gtest.h>

#include <cstring>

#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/surfel_fields.h"

namespace rc {
namespace {

std::vector<std::string> names(const std::vector<FieldSpec>& fields) {
  std::vector<std::string> out;
  for (const FieldSpec& f : fields) out.push_back(f.name);
  return out;
}

SurfelCloud everyChannel() {
  SurfelCloud c;
  c.positions = {Vec3(1, 2, 3)};
  c.normals = {Vec3(0, 0, 1)};
  c.radii = {0.5};
  c.axes1 = {Vec3(1, 0, 0)};
  c.axes2 = {Vec3(0, 1, 0)};
  c.colors = {Rgba{1, 2, 3, 4}};
  c.confidence = {0.25f};
  c.curvature = {0.125f};
  c.attributes.add("label", ScalarType::kUInt16, 1, 1);
  return c;
}

std::vector<FieldSpec> floats(const std::vector<std::string>& field_names) {
  std::vector<FieldSpec> fields;
  for (const std::string& name : field_names) fields.push_back(FieldSpec{name, ScalarType::kFloat32, 1});
  return fields;
}

/// The IoError message of bindFields, or "" if it binds.
std::string bindError(const std::vector<FieldSpec>& fields, FieldNaming naming) {
  SurfelCloud cloud;
  std::vector<FieldBinding> bindings;
  try {
    bindFields(fields, naming, 2, "msg", "", &cloud, &bindings);
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

TEST(SurfelFields, EachFormatWritesItsNamesInItsOrder) {
  std::vector<FieldSpec> fields;
  std::vector<FieldBinding> bindings;
  describeCloudFields(everyChannel(), FieldNaming::kPcd, false, "f", &fields, &bindings);
  EXPECT_EQ(names(fields),
            (std::vector<std::string>{"x", "y", "z", "normal_x", "normal_y", "normal_z", "radius", "axis1_x",
                                      "axis1_y", "axis1_z", "axis2_x", "axis2_y", "axis2_z", "rgba",
                                      "confidence", "curvature", "label"}));
  describeCloudFields(everyChannel(), FieldNaming::kPointCloud2, false, "f", &fields, &bindings);
  EXPECT_EQ(names(fields), (std::vector<std::string>{"x", "y", "z", "normal_x", "normal_y", "normal_z",
                                                     "rgba", "radius", "confidence", "curvature", "t1x",
                                                     "t1y", "t1z", "t2x", "t2y", "t2z", "label"}));
  EXPECT_EQ(fields[6].type, ScalarType::kUInt32);
  EXPECT_EQ(bindings[6].target, FieldTarget::kPackedRgba);
  EXPECT_EQ(bindings[13].target, FieldTarget::kAxis2);
  EXPECT_EQ(bindings[13].axis, 0);
}

TEST(SurfelFields, PointSurfelChannelsTheCloudLacksAreZeroFields) {
  SurfelCloud cloud;
  cloud.positions = {Vec3(1, 2, 3)};
  std::vector<FieldSpec> fields;
  std::vector<FieldBinding> bindings;
  describeCloudFields(cloud, FieldNaming::kPointCloud2, false, "f", &fields, &bindings, true);
  EXPECT_EQ(names(fields), (std::vector<std::string>{"x", "y", "z", "normal_x", "normal_y", "normal_z",
                                                     "rgba", "radius", "confidence", "curvature"}));
  for (size_t k = 3; k < bindings.size(); ++k) EXPECT_EQ(bindings[k].target, FieldTarget::kSkip) << k;
  uint8_t value[4] = {9, 9, 9, 9};
  loadField(bindings[6], 0, 0, cloud, value);
  EXPECT_EQ(value[0] | value[1] | value[2] | value[3], 0) << "absent channels are written as zeros";

  cloud.attributes.add("radius", ScalarType::kFloat32, 1, 1);  // would read back as the radius channel
  EXPECT_THROW(describeCloudFields(cloud, FieldNaming::kPointCloud2, false, "f", &fields, &bindings, true),
               IoError);
  EXPECT_NO_THROW(describeCloudFields(cloud, FieldNaming::kPointCloud2, false, "f", &fields, &bindings));
  cloud.attributes.columns()[0].name = "my radius";  // blanks: fine in a message, not in a PCD header
  EXPECT_NO_THROW(describeCloudFields(cloud, FieldNaming::kPointCloud2, false, "f", &fields, &bindings));
  EXPECT_THROW(describeCloudFields(cloud, FieldNaming::kPcd, false, "f", &fields, &bindings), IoError);
}

TEST(SurfelFields, ANameMeansTheSameChannelInEveryFormat) {
  for (const FieldNaming naming : {FieldNaming::kPly, FieldNaming::kPcd, FieldNaming::kPointCloud2})
    for (const char* first_axis : {"axis1_x", "t1x"}) {
      const bool short_names = first_axis[0] == 't';
      const std::vector<FieldSpec> fields =
          short_names
              ? floats({"x", "y", "z", "t1x", "t1y", "t1z", "t2x", "t2y", "t2z"})
              : floats({"x", "y", "z", "axis1_x", "axis1_y", "axis1_z", "axis2_x", "axis2_y", "axis2_z"});
      SurfelCloud cloud;
      std::vector<FieldBinding> bindings;
      EXPECT_TRUE(bindFields(fields, naming, 3, "f", "", &cloud, &bindings));
      EXPECT_TRUE(cloud.hasAxes()) << first_axis;
      EXPECT_EQ(bindings[8].target, FieldTarget::kAxis2);
      EXPECT_EQ(bindings[8].axis, 2);
      EXPECT_TRUE(cloud.attributes.empty());
    }
}

TEST(SurfelFields, FilesKeepUnusableChannelFieldsAsAttributes) {
  // axis1 without axis2 (once bound half-way to unallocated axes), an integer x, a lone normal, a byte rgba
  std::vector<FieldSpec> fields = floats({"x", "y", "z", "axis1_x", "axis1_y", "axis1_z", "normal_x"});
  fields[0].type = ScalarType::kInt32;
  fields.push_back(FieldSpec{"rgba", ScalarType::kUInt8, 3});
  SurfelCloud cloud;
  std::vector<FieldBinding> bindings;
  ASSERT_TRUE(bindFields(fields, FieldNaming::kPcd, 2, "f", "", &cloud, &bindings));
  EXPECT_EQ(bindings[0].target, FieldTarget::kPosition);
  EXPECT_FALSE(cloud.hasAxes());
  EXPECT_FALSE(cloud.hasNormals());
  EXPECT_FALSE(cloud.hasColors());
  EXPECT_EQ(cloud.attributes.columns().size(), 5u);
  const int32_t x = -7;
  storeField(bindings[0], 1, 0, reinterpret_cast<const uint8_t*>(&x), &cloud);
  EXPECT_EQ(cloud.positions[1].x(), -7.0);
}

TEST(SurfelFields, PointCloud2RejectsUnusableChannelFieldsNamingThem) {
  std::vector<FieldSpec> int_x = floats({"x", "y", "z"});
  int_x[0].type = ScalarType::kInt32;
  EXPECT_EQ(bindError(int_x, FieldNaming::kPointCloud2),
            "msg: field 'x' has datatype INT32, expected FLOAT32 or FLOAT64");
  EXPECT_EQ(bindError(floats({"x", "y", "z", "normal_x"}), FieldNaming::kPointCloud2),
            "msg: field 'normal_y' is missing (the other fields of its group are present)");
  EXPECT_EQ(bindError(floats({"x", "y", "z", "t1x", "t1y", "t1z"}), FieldNaming::kPointCloud2),
            "msg: field 't2x' is missing (the other fields of its group are present)");
  std::vector<FieldSpec> counted = floats({"x", "y", "z", "radius"});
  counted[3].count = 2;
  EXPECT_EQ(bindError(counted, FieldNaming::kPointCloud2), "msg: field 'radius' has count 2, expected 1");
  std::vector<FieldSpec> byte_rgb = floats({"x", "y", "z", "rgb"});
  byte_rgb[3].type = ScalarType::kUInt16;
  EXPECT_EQ(bindError(byte_rgb, FieldNaming::kPointCloud2),
            "msg: field 'rgb' has datatype UINT16, expected one packed UINT32/FLOAT32");
  for (const auto& fields : {int_x, counted, byte_rgb}) EXPECT_EQ(bindError(fields, FieldNaming::kPcd), "");
  // Both packed colours: rgba fills the channel, rgb stays an attribute.
  SurfelCloud cloud;
  std::vector<FieldBinding> bindings;
  bindFields(floats({"x", "y", "z", "rgb", "rgba"}), FieldNaming::kPointCloud2, 1, "msg", "", &cloud,
             &bindings);
  EXPECT_EQ(bindings[3].target, FieldTarget::kAttribute);
  EXPECT_EQ(bindings[4].target, FieldTarget::kPackedRgba);
}

TEST(SurfelFields, BindingReplacesTheWholeCloud) {
  SurfelCloud cloud = everyChannel();
  cloud.frame_id = "old";
  cloud.width = 1;
  cloud.height = 1;
  std::vector<FieldBinding> bindings;
  ASSERT_TRUE(bindFields(floats({"x", "y", "z", "rgb"}), FieldNaming::kPcd, 3, "f", "", &cloud, &bindings));
  EXPECT_EQ(cloud.size(), 3u);
  EXPECT_FALSE(cloud.hasNormals() || cloud.hasRadii() || cloud.hasAxes() || cloud.hasConfidence() ||
               cloud.hasCurvature());
  EXPECT_TRUE(cloud.attributes.empty());
  EXPECT_TRUE(cloud.frame_id.empty());
  EXPECT_EQ(cloud.height, 0u);
  EXPECT_EQ(cloud.colors[2], (Rgba{0, 0, 0, 255}));
}

TEST(SurfelFields, StridedRangesRoundTrip) {
  // Three records of 16 bytes: float64 x at 0, packed rgba at 8, a uint16 x 2 attribute at 12.
  const std::vector<FieldSpec> fields = {{"x", ScalarType::kFloat64, 1},
                                         {"y", ScalarType::kFloat32, 1},
                                         {"z", ScalarType::kFloat32, 1},
                                         {"rgba", ScalarType::kUInt32, 1},
                                         {"pair", ScalarType::kUInt16, 2}};
  SurfelCloud cloud;
  std::vector<FieldBinding> bindings;
  ASSERT_TRUE(bindFields(fields, FieldNaming::kPointCloud2, 4, "f", "", &cloud, &bindings));
  uint8_t records[3 * 16];
  for (int j = 0; j < 3; ++j) {
    const double x = 0.1 * j;
    const uint32_t rgba = 0x04010203u + uint32_t(j);  // a r g b
    const uint16_t pair[2] = {uint16_t(j), uint16_t(100 + j)};
    std::memcpy(records + 16 * j, &x, 8);
    std::memcpy(records + 16 * j + 8, &rgba, 4);
    std::memcpy(records + 16 * j + 12, pair, 4);
  }
  const size_t first = 1;  // surfels 1..3
  storeFieldValues(bindings[0], 0, records, 16, first, 3, &cloud);
  storeFieldValues(bindings[3], 0, records + 8, 16, first, 3, &cloud);
  for (uint32_t k = 0; k < 2; ++k)
    storeFieldValues(bindings[4], k, records + 12 + 2 * k, 16, first, 3, &cloud);
  EXPECT_EQ(cloud.positions[3].x(), 0.2);
  EXPECT_EQ(cloud.colors[2], (Rgba{1, 2, 4, 4}));
  EXPECT_EQ(cloud.attributes.columns()[0].get(3, 1), 102.0);

  uint8_t back[3 * 16] = {};
  loadFieldValues(bindings[0], 0, cloud, first, 3, back, 16);
  loadFieldValues(bindings[3], 0, cloud, first, 3, back + 8, 16);
  for (uint32_t k = 0; k < 2; ++k) loadFieldValues(bindings[4], k, cloud, first, 3, back + 12 + 2 * k, 16);
  EXPECT_EQ(std::memcmp(back, records, sizeof(records)), 0);
}

TEST(SurfelFields, RecordsRoundTripWithFieldsInAnyOrder) {
  // z y x (no vector run), the normal (a run), padding, packed rgba, a uint16 x 2 attribute: 40-byte records.
  const std::vector<FieldSpec> fields = {
      {"z", ScalarType::kFloat32, 1},        {"y", ScalarType::kFloat32, 1},
      {"x", ScalarType::kFloat64, 1},        {"normal_x", ScalarType::kFloat32, 1},
      {"normal_y", ScalarType::kFloat32, 1}, {"normal_z", ScalarType::kFloat32, 1},
      {"_", ScalarType::kFloat32, 1},        {"rgba", ScalarType::kUInt32, 1},
      {"pair", ScalarType::kUInt16, 2}};
  const std::vector<uint32_t> offsets = {0, 4, 8, 16, 20, 24, 28, 32, 36};
  const size_t stride = 40, n = 5;
  SurfelCloud cloud;
  std::vector<FieldBinding> bindings;
  ASSERT_TRUE(bindFields(fields, FieldNaming::kPointCloud2, n, "f", "", &cloud, &bindings));
  for (size_t i = 0; i < n; ++i) {
    cloud.positions[i] = Vec3(0.5 * i, -1.0 * i, 0.25);
    cloud.normals[i] = Vec3(0, 0.5, -0.75 * i);
    cloud.colors[i] = Rgba{uint8_t(i), 2, 3, 4};
    cloud.attributes.columns()[0].set(i, 10.0 * i, 1);
  }
  std::vector<uint8_t> records(n * stride, 0xAB);
  loadRecords(bindings, offsets, cloud, 1, n - 1, records.data() + stride, stride);  // surfels 1..4
  float z;
  double x;
  std::memcpy(&z, records.data() + 2 * stride, 4);
  std::memcpy(&x, records.data() + 2 * stride + 8, 8);
  EXPECT_EQ(z, 0.25f);
  EXPECT_EQ(x, 1.0);
  EXPECT_EQ(records[3 * stride + 28], 0xAB) << "padding is left as it is";
  EXPECT_EQ(records[0], 0xAB) << "surfel 0 not written";

  SurfelCloud back;
  ASSERT_TRUE(bindFields(fields, FieldNaming::kPointCloud2, n - 1, "f", "", &back, &bindings));
  storeRecords(bindings, offsets, records.data() + stride, stride, 0, n - 1, &back);
  for (size_t i = 1; i < n; ++i) {
    EXPECT_EQ(back.positions[i - 1], cloud.positions[i]);
    EXPECT_EQ(back.normals[i - 1], cloud.normals[i]);
    EXPECT_EQ(back.colors[i - 1], cloud.colors[i]);
    EXPECT_EQ(back.attributes.columns()[0].get(i - 1, 1), 10.0 * i);
  }
}

TEST(SurfelFields, PointFieldDatatypeCodes) {
  EXPECT_EQ(pointFieldDatatype(ScalarType::kInt8), 1);
  EXPECT_EQ(pointFieldDatatype(ScalarType::kUInt32), 6);
  EXPECT_EQ(pointFieldDatatype(ScalarType::kFloat64), 8);
  ScalarType type = ScalarType::kInt8;
  EXPECT_TRUE(scalarTypeOfPointField(7, &type));
  EXPECT_EQ(type, ScalarType::kFloat32);
  EXPECT_FALSE(scalarTypeOfPointField(0, &type));
  EXPECT_FALSE(scalarTypeOfPointField(9, &type));
  EXPECT_STREQ(pointFieldTypeName(ScalarType::kUInt16), "UINT16");
}

}  // namespace
}  // namespace rc
