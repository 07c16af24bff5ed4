#include "relaxed_connectivity/ros/point_cloud2_converter.h"

#include <sensor_msgs/PointField.h>

#include <algorithm>
#include <cstring>
#include <set>

#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/surfel_fields.h"

namespace rc {

namespace {

using sensor_msgs::PointField;

static_assert(PointField::INT8 == 1 && PointField::FLOAT64 == 8 && PointField::FLOAT32 == 7,
              "io's PointField codes (surfel_fields.h) follow sensor_msgs/PointField");

/// Surfels per pass over the fields. Measured on 1M surfels: 16 is as fast as one loop per point (8 pays the
/// calls, 32 to 512 are 10-25 % slower).
constexpr size_t kBlockSize = 16;

PointField makeField(const FieldSpec& spec, uint32_t offset) {
  PointField f;
  f.name = spec.name;
  f.offset = offset;
  f.datatype = pointFieldDatatype(spec.type);
  f.count = spec.count;
  return f;
}

uint32_t alignUp(uint32_t offset, uint32_t alignment) {
  return (offset + alignment - 1) / alignment * alignment;
}

std::string fieldList(const sensor_msgs::PointCloud2& msg) {
  std::string s;
  for (const auto& f : msg.fields) s += (s.empty() ? "" : " ") + f.name;
  return s.empty() ? "none" : s;
}

std::vector<uint32_t> fieldOffsets(const sensor_msgs::PointCloud2& msg) {
  std::vector<uint32_t> offsets;
  for (const auto& f : msg.fields) offsets.push_back(f.offset);
  return offsets;
}

}  // namespace

const std::vector<std::string>& PointCloud2Converter::axisFieldNames() {
  static const std::vector<std::string> names = [] {
    SurfelCloud cloud;
    cloud.positions.resize(1);
    cloud.axes1.resize(1);
    cloud.axes2.resize(1);
    std::vector<FieldSpec> fields;
    std::vector<FieldBinding> bindings;
    describeCloudFields(cloud, FieldNaming::kPointCloud2, false, "", &fields, &bindings);
    std::vector<std::string> axes;
    for (size_t k = 3; k < fields.size(); ++k) axes.push_back(fields[k].name);
    return axes;
  }();
  return names;
}

void PointCloud2Converter::toMessage(const SurfelCloud& cloud, sensor_msgs::PointCloud2& msg,
                                     PointCloud2Layout layout) {
  const bool surfel_layout = layout == PointCloud2Layout::kPointSurfel;
  std::vector<FieldSpec> specs;
  std::vector<FieldBinding> bindings;
  try {
    describeCloudFields(cloud, FieldNaming::kPointCloud2, false, "PointCloud2 conversion", &specs, &bindings,
                        surfel_layout);
  } catch (const IoError& e) {
    throw PointCloud2Error(e.what());
  }
  const size_t n = cloud.size();

  // Field layout: in order, naturally aligned.
  msg.fields.clear();
  uint32_t offset = 0;
  for (size_t k = 0; k < specs.size(); ++k) {
    const uint32_t size = static_cast<uint32_t>(scalarSize(specs[k].type));
    offset = alignUp(offset, size);
    msg.fields.push_back(makeField(specs[k], offset));
    offset += size * specs[k].count;
    // kPointSurfel begins with x y z and the normal, each a 4-float vector in PCL (PCL_ADD_POINT4D,
    // PCL_ADD_NORMAL4D).
    if (surfel_layout && (k == 2 || k == 5)) offset += 4;
  }
  const uint32_t point_step = alignUp(offset, 4);

  // Header and geometry of the message.
  msg.header.frame_id = cloud.frame_id;
  msg.header.stamp.fromNSec(cloud.stamp_ns);
  if (cloud.isOrganized()) {
    msg.width = cloud.width;
    msg.height = cloud.height;
  } else {
    msg.width = static_cast<uint32_t>(n);
    msg.height = 1;
  }
  msg.is_bigendian = false;
  msg.point_step = point_step;
  msg.row_step = point_step * msg.width;
  msg.data.assign(static_cast<size_t>(point_step) * n, 0);

  const std::vector<uint32_t> offsets = fieldOffsets(msg);
  const float one = 1.0f;  // PCL's homogeneous coordinate after x y z
  bool dense = true;
  for (size_t first = 0; first < n; first += kBlockSize) {
    const size_t count = std::min(kBlockSize, n - first);
    uint8_t* block = msg.data.data() + first * point_step;
    loadRecords(bindings, offsets, cloud, first, count, block, point_step);
    for (size_t j = 0; j < count; ++j) {
      if (surfel_layout) std::memcpy(block + j * point_step + 12, &one, 4);
      dense = dense && cloud.positions[first + j].allFinite();
    }
  }
  msg.is_dense = dense;
}

sensor_msgs::PointCloud2Ptr PointCloud2Converter::toMessage(const SurfelCloud& cloud,
                                                            PointCloud2Layout layout) {
  sensor_msgs::PointCloud2Ptr msg(new sensor_msgs::PointCloud2);
  toMessage(cloud, *msg, layout);
  return msg;
}

void PointCloud2Converter::checkMessage(const sensor_msgs::PointCloud2& msg) {
  if (msg.is_bigendian) throw PointCloud2Error("PointCloud2: big-endian data is not supported");
  std::set<std::string> names;
  for (const auto& f : msg.fields) {
    ScalarType type;
    if (!scalarTypeOfPointField(f.datatype, &type))
      throw PointCloud2Error("PointCloud2: field '" + f.name + "' has unsupported datatype " +
                             std::to_string(f.datatype));
    if (f.count == 0) throw PointCloud2Error("PointCloud2: field '" + f.name + "' has count 0");
    const uint64_t end = uint64_t(f.offset) + uint64_t(scalarSize(type)) * f.count;
    if (end > msg.point_step)
      throw PointCloud2Error("PointCloud2: field '" + f.name + "' (offset " + std::to_string(f.offset) +
                             ", " + std::to_string(f.count) + " x " + pointFieldTypeName(type) +
                             ") extends beyond point_step " + std::to_string(msg.point_step));
    if (f.name != "_" && !names.insert(f.name).second)
      throw PointCloud2Error("PointCloud2: field '" + f.name + "' appears twice");
  }
  for (const char* name : {"x", "y", "z"})
    if (!names.count(name))
      throw PointCloud2Error(std::string("PointCloud2: missing field '") + name +
                             "' (fields: " + fieldList(msg) + ")");
  const uint64_t min_row = uint64_t(msg.width) * msg.point_step;
  if (msg.row_step < min_row)
    throw PointCloud2Error("PointCloud2: row_step " + std::to_string(msg.row_step) +
                           " is smaller than width * point_step = " + std::to_string(min_row));
  const uint64_t expected = uint64_t(msg.row_step) * msg.height;
  if (msg.data.size() != expected)
    throw PointCloud2Error("PointCloud2: data holds " + std::to_string(msg.data.size()) +
                           " bytes, expected row_step * height = " + std::to_string(expected));
}

bool PointCloud2Converter::hasPointSurfelLayout(const sensor_msgs::PointCloud2& msg) {
  static const std::vector<PointField> point_surfel = toMessage(SurfelCloud())->fields;
  if (msg.point_step < kPointSurfelStep || msg.fields.size() < point_surfel.size()) return false;
  return std::equal(point_surfel.begin(), point_surfel.end(), msg.fields.begin());
}

void PointCloud2Converter::fromMessage(const sensor_msgs::PointCloud2& msg, SurfelCloud& cloud) {
  checkMessage(msg);
  std::vector<FieldSpec> specs;
  for (const auto& f : msg.fields) {
    FieldSpec spec{f.name, ScalarType::kFloat32, f.count};
    scalarTypeOfPointField(f.datatype, &spec.type);
    specs.push_back(spec);
  }
  std::vector<FieldBinding> bindings;
  try {
    bindFields(specs, FieldNaming::kPointCloud2, size_t(msg.width) * msg.height, "PointCloud2", "", &cloud,
               &bindings);
  } catch (const IoError& e) {
    throw PointCloud2Error(e.what());
  }
  cloud.frame_id = msg.header.frame_id;
  cloud.stamp_ns = msg.header.stamp.toNSec();

  const std::vector<uint32_t> offsets = fieldOffsets(msg);
  for (uint32_t row = 0; row < msg.height; ++row) {
    const uint8_t* row_data = msg.data.data() + size_t(row) * msg.row_step;
    for (size_t col = 0; col < msg.width; col += kBlockSize) {
      const size_t count = std::min<size_t>(kBlockSize, msg.width - col);
      const uint8_t* block = row_data + col * msg.point_step;
      const size_t first = size_t(row) * msg.width + col;
      storeRecords(bindings, offsets, block, msg.point_step, first, count, &cloud);
    }
  }
  if (msg.height > 1) {
    cloud.width = msg.width;
    cloud.height = msg.height;
  }
}

SurfelCloud PointCloud2Converter::fromMessage(const sensor_msgs::PointCloud2& msg) {
  SurfelCloud cloud;
  fromMessage(msg, cloud);
  return cloud;
}

}  // namespace rc
