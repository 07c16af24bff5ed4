#include "ros/point_cloud2_converter.h"

#include <sensor_msgs/PointField.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>

namespace rc {

namespace {

using sensor_msgs::PointField;

const char* datatypeName(uint8_t datatype) {
  switch (datatype) {
    case PointField::INT8:
      return "INT8";
    case PointField::UINT8:
      return "UINT8";
    case PointField::INT16:
      return "INT16";
    case PointField::UINT16:
      return "UINT16";
    case PointField::INT32:
      return "INT32";
    case PointField::UINT32:
      return "UINT32";
    case PointField::FLOAT32:
      return "FLOAT32";
    case PointField::FLOAT64:
      return "FLOAT64";
    default:
      return "unknown";
  }
}

bool isValidDatatype(uint8_t datatype) {
  return datatype >= PointField::INT8 && datatype <= PointField::FLOAT64;
}

uint32_t datatypeSize(uint8_t datatype) {
  switch (datatype) {
    case PointField::INT8:
    case PointField::UINT8:
      return 1;
    case PointField::INT16:
    case PointField::UINT16:
      return 2;
    case PointField::INT32:
    case PointField::UINT32:
    case PointField::FLOAT32:
      return 4;
    case PointField::FLOAT64:
      return 8;
    default:
      return 0;
  }
}

ScalarType toScalarType(uint8_t datatype) {
  switch (datatype) {
    case PointField::INT8:
      return ScalarType::kInt8;
    case PointField::UINT8:
      return ScalarType::kUInt8;
    case PointField::INT16:
      return ScalarType::kInt16;
    case PointField::UINT16:
      return ScalarType::kUInt16;
    case PointField::INT32:
      return ScalarType::kInt32;
    case PointField::UINT32:
      return ScalarType::kUInt32;
    case PointField::FLOAT32:
      return ScalarType::kFloat32;
    default:
      return ScalarType::kFloat64;
  }
}

uint8_t toDatatype(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
      return PointField::INT8;
    case ScalarType::kUInt8:
      return PointField::UINT8;
    case ScalarType::kInt16:
      return PointField::INT16;
    case ScalarType::kUInt16:
      return PointField::UINT16;
    case ScalarType::kInt32:
      return PointField::INT32;
    case ScalarType::kUInt32:
      return PointField::UINT32;
    case ScalarType::kFloat32:
      return PointField::FLOAT32;
    default:
      return PointField::FLOAT64;
  }
}

PointField makeField(const std::string& name, uint32_t offset, uint8_t datatype, uint32_t count = 1) {
  PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = datatype;
  f.count = count;
  return f;
}

uint32_t alignUp(uint32_t offset, uint32_t alignment) {
  return (offset + alignment - 1) / alignment * alignment;
}

/// A float32/float64 scalar field of a message (offset < 0: absent).
struct RealField {
  int64_t offset = -1;
  uint8_t datatype = PointField::FLOAT32;
  bool present() const { return offset >= 0; }
  double read(const uint8_t* point) const {
    if (datatype == PointField::FLOAT32) {
      float v;
      std::memcpy(&v, point + offset, 4);
      return v;
    }
    double v;
    std::memcpy(&v, point + offset, 8);
    return v;
  }
};

void writeFloat(uint8_t* dst, double value) {
  const float v = static_cast<float>(value);
  std::memcpy(dst, &v, 4);
}

const std::vector<std::string> kSurfelFieldNames = {"x",        "y",    "z",      "normal_x",   "normal_y",
                                                    "normal_z", "rgba", "radius", "confidence", "curvature"};
const std::vector<uint32_t> kSurfelFieldOffsets = {0, 4, 8, 16, 20, 24, 32, 36, 40, 44};

std::string fieldList(const sensor_msgs::PointCloud2& msg) {
  std::string s;
  for (const auto& f : msg.fields) s += (s.empty() ? "" : " ") + f.name;
  return s.empty() ? "none" : s;
}

RealField realField(const std::map<std::string, const PointField*>& by_name, const std::string& name) {
  RealField r;
  auto it = by_name.find(name);
  if (it == by_name.end()) return r;
  const PointField& f = *it->second;
  if (f.datatype != PointField::FLOAT32 && f.datatype != PointField::FLOAT64)
    throw PointCloud2Error("PointCloud2: field '" + name + "' has datatype " + datatypeName(f.datatype) +
                           ", expected FLOAT32 or FLOAT64");
  if (f.count != 1)
    throw PointCloud2Error("PointCloud2: field '" + name + "' has count " + std::to_string(f.count) +
                           ", expected 1");
  r.offset = f.offset;
  r.datatype = f.datatype;
  return r;
}

/// All of `names` or none of them; throws naming the first missing one otherwise.
bool allOrNone(const std::map<std::string, const PointField*>& by_name,
               const std::vector<std::string>& names) {
  size_t found = 0;
  for (const auto& n : names) found += by_name.count(n);
  if (found == 0) return false;
  if (found == names.size()) return true;
  for (const auto& n : names)
    if (!by_name.count(n))
      throw PointCloud2Error("PointCloud2: field '" + n +
                             "' is missing (the other fields of its group are present)");
  return true;
}

}  // namespace

const std::vector<std::string>& PointCloud2Converter::axisFieldNames() {
  static const std::vector<std::string> names = {"t1x", "t1y", "t1z", "t2x", "t2y", "t2z"};
  return names;
}

void PointCloud2Converter::toMessage(const SurfelCloud& cloud, sensor_msgs::PointCloud2& msg,
                                     PointCloud2Layout layout) {
  try {
    cloud.validate();
  } catch (const std::invalid_argument& e) {
    throw PointCloud2Error(std::string("PointCloud2 conversion: ") + e.what());
  }
  const size_t n = cloud.size();
  const bool surfel_layout = layout == PointCloud2Layout::kPointSurfel;

  // Field layout.
  msg.fields.clear();
  uint32_t offset = 0;
  int64_t off_normal = -1, off_rgba = -1, off_radius = -1, off_conf = -1, off_curv = -1, off_axes = -1;
  if (surfel_layout) {
    for (size_t i = 0; i < kSurfelFieldNames.size(); ++i)
      msg.fields.push_back(
          makeField(kSurfelFieldNames[i], kSurfelFieldOffsets[i],
                    kSurfelFieldNames[i] == "rgba" ? PointField::UINT32 : PointField::FLOAT32));
    off_normal = 16;
    off_rgba = 32;
    off_radius = 36;
    off_conf = 40;
    off_curv = 44;
    offset = kPointSurfelStep;
  } else {
    for (const char* name : {"x", "y", "z"}) {
      msg.fields.push_back(makeField(name, offset, PointField::FLOAT32));
      offset += 4;
    }
    auto add = [&](bool present, const std::vector<std::string>& names, uint8_t datatype, int64_t* where) {
      if (!present) return;
      *where = offset;
      for (const auto& name : names) {
        msg.fields.push_back(makeField(name, offset, datatype));
        offset += 4;
      }
    };
    add(cloud.hasNormals(), {"normal_x", "normal_y", "normal_z"}, PointField::FLOAT32, &off_normal);
    add(cloud.hasColors(), {"rgba"}, PointField::UINT32, &off_rgba);
    add(cloud.hasRadii(), {"radius"}, PointField::FLOAT32, &off_radius);
    add(cloud.hasConfidence(), {"confidence"}, PointField::FLOAT32, &off_conf);
    add(cloud.hasCurvature(), {"curvature"}, PointField::FLOAT32, &off_curv);
  }
  if (cloud.hasAxes()) {
    off_axes = offset;
    for (const auto& name : axisFieldNames()) {
      msg.fields.push_back(makeField(name, offset, PointField::FLOAT32));
      offset += 4;
    }
  }
  std::set<std::string> used;
  for (const auto& f : msg.fields) used.insert(f.name);
  std::vector<uint32_t> attribute_offsets;
  for (const auto& a : cloud.attributes.columns()) {
    if (!used.insert(a.name).second)
      throw PointCloud2Error("PointCloud2 conversion: attribute '" + a.name +
                             "' has the name of a field that is already written");
    const uint8_t datatype = toDatatype(a.type);
    offset = alignUp(offset, datatypeSize(datatype));
    attribute_offsets.push_back(offset);
    msg.fields.push_back(makeField(a.name, offset, datatype, a.count));
    offset += static_cast<uint32_t>(a.stride());
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

  bool dense = true;
  const float one = 1.0f;
  for (size_t i = 0; i < n; ++i) {
    uint8_t* p = msg.data.data() + i * point_step;
    const Vec3& x = cloud.positions[i];
    dense = dense && x.allFinite();
    for (int k = 0; k < 3; ++k) writeFloat(p + 4 * k, x[k]);
    if (surfel_layout) std::memcpy(p + 12, &one, 4);  // PCL's homogeneous coordinate
    if (off_normal >= 0 && cloud.hasNormals())
      for (int k = 0; k < 3; ++k) writeFloat(p + off_normal + 4 * k, cloud.normals[i][k]);
    if (off_rgba >= 0 && cloud.hasColors()) {
      const Rgba& c = cloud.colors[i];
      const uint8_t bgra[4] = {c[2], c[1], c[0], c[3]};  // uint32 a<<24 | r<<16 | g<<8 | b, little endian
      std::memcpy(p + off_rgba, bgra, 4);
    }
    if (off_radius >= 0 && cloud.hasRadii()) writeFloat(p + off_radius, cloud.radii[i]);
    if (off_conf >= 0 && cloud.hasConfidence()) std::memcpy(p + off_conf, &cloud.confidence[i], 4);
    if (off_curv >= 0 && cloud.hasCurvature()) std::memcpy(p + off_curv, &cloud.curvature[i], 4);
    if (off_axes >= 0)
      for (int k = 0; k < 3; ++k) {
        writeFloat(p + off_axes + 4 * k, cloud.axes1[i][k]);
        writeFloat(p + off_axes + 12 + 4 * k, cloud.axes2[i][k]);
      }
    const auto& columns = cloud.attributes.columns();
    for (size_t c = 0; c < columns.size(); ++c) {
      const size_t stride = columns[c].stride();
      std::memcpy(p + attribute_offsets[c], columns[c].bytes.data() + i * stride, stride);
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
    if (!isValidDatatype(f.datatype))
      throw PointCloud2Error("PointCloud2: field '" + f.name + "' has unsupported datatype " +
                             std::to_string(f.datatype));
    if (f.count == 0) throw PointCloud2Error("PointCloud2: field '" + f.name + "' has count 0");
    const uint64_t end = uint64_t(f.offset) + uint64_t(datatypeSize(f.datatype)) * f.count;
    if (end > msg.point_step)
      throw PointCloud2Error("PointCloud2: field '" + f.name + "' (offset " + std::to_string(f.offset) +
                             ", " + std::to_string(f.count) + " x " + datatypeName(f.datatype) +
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
  if (msg.point_step < kPointSurfelStep || msg.fields.size() < kSurfelFieldNames.size()) return false;
  for (size_t i = 0; i < kSurfelFieldNames.size(); ++i) {
    const auto& f = msg.fields[i];
    const uint8_t type = kSurfelFieldNames[i] == "rgba" ? PointField::UINT32 : PointField::FLOAT32;
    if (f.name != kSurfelFieldNames[i] || f.offset != kSurfelFieldOffsets[i] || f.datatype != type ||
        f.count != 1)
      return false;
  }
  return true;
}

void PointCloud2Converter::fromMessage(const sensor_msgs::PointCloud2& msg, SurfelCloud& cloud) {
  checkMessage(msg);
  std::map<std::string, const PointField*> by_name;
  for (const auto& f : msg.fields)
    if (f.name != "_") by_name[f.name] = &f;

  const RealField fx = realField(by_name, "x"), fy = realField(by_name, "y"), fz = realField(by_name, "z");
  RealField normal[3], axes[6];
  const bool has_normals = allOrNone(by_name, {"normal_x", "normal_y", "normal_z"});
  if (has_normals)
    for (int k = 0; k < 3; ++k) normal[k] = realField(by_name, std::string("normal_") + char('x' + k));
  const bool has_axes = allOrNone(by_name, axisFieldNames());
  if (has_axes)
    for (int k = 0; k < 6; ++k) axes[k] = realField(by_name, axisFieldNames()[k]);
  const RealField radius = realField(by_name, "radius");
  const RealField confidence = realField(by_name, "confidence");
  const RealField curvature = realField(by_name, "curvature");

  const PointField* color = nullptr;
  bool color_has_alpha = true;
  for (const char* name : {"rgba", "rgb"}) {
    auto it = by_name.find(name);
    if (it == by_name.end()) continue;
    const PointField& f = *it->second;
    if ((f.datatype != PointField::UINT32 && f.datatype != PointField::INT32 &&
         f.datatype != PointField::FLOAT32) ||
        f.count != 1)
      throw PointCloud2Error(std::string("PointCloud2: field '") + name + "' has datatype " +
                             datatypeName(f.datatype) + " x " + std::to_string(f.count) +
                             ", expected one packed UINT32/FLOAT32");
    color = &f;
    color_has_alpha = std::string(name) == "rgba";
    break;
  }

  std::set<std::string> known = {"x", "y", "z", "radius", "confidence", "curvature"};
  if (has_normals) known.insert({"normal_x", "normal_y", "normal_z"});
  if (has_axes) known.insert(axisFieldNames().begin(), axisFieldNames().end());
  if (color) known.insert(color->name);

  const size_t n = size_t(msg.width) * msg.height;
  cloud = SurfelCloud();
  cloud.frame_id = msg.header.frame_id;
  cloud.stamp_ns = msg.header.stamp.toNSec();
  cloud.positions.resize(n);
  if (has_normals) cloud.normals.resize(n);
  if (has_axes) {
    cloud.axes1.resize(n);
    cloud.axes2.resize(n);
  }
  if (radius.present()) cloud.radii.resize(n);
  if (confidence.present()) cloud.confidence.resize(n);
  if (curvature.present()) cloud.curvature.resize(n);
  if (color) cloud.colors.resize(n);
  std::vector<uint32_t> extra_offsets;  // field offset of attribute column c
  for (const auto& f : msg.fields) {
    if (f.name == "_" || known.count(f.name)) continue;
    cloud.attributes.add(f.name, toScalarType(f.datatype), f.count, n);
    extra_offsets.push_back(f.offset);
  }
  AttributeSet::Columns& columns = cloud.attributes.columns();

  for (uint32_t row = 0; row < msg.height; ++row) {
    const uint8_t* row_data = msg.data.data() + size_t(row) * msg.row_step;
    for (uint32_t col = 0; col < msg.width; ++col) {
      const size_t i = size_t(row) * msg.width + col;
      const uint8_t* p = row_data + size_t(col) * msg.point_step;
      cloud.positions[i] = Vec3(fx.read(p), fy.read(p), fz.read(p));
      if (has_normals) cloud.normals[i] = Vec3(normal[0].read(p), normal[1].read(p), normal[2].read(p));
      if (has_axes) {
        cloud.axes1[i] = Vec3(axes[0].read(p), axes[1].read(p), axes[2].read(p));
        cloud.axes2[i] = Vec3(axes[3].read(p), axes[4].read(p), axes[5].read(p));
      }
      if (radius.present()) cloud.radii[i] = radius.read(p);
      if (confidence.present()) cloud.confidence[i] = static_cast<float>(confidence.read(p));
      if (curvature.present()) cloud.curvature[i] = static_cast<float>(curvature.read(p));
      if (color) {
        const uint8_t* c = p + color->offset;  // bytes b g r a
        cloud.colors[i] = Rgba{c[2], c[1], c[0], color_has_alpha ? c[3] : uint8_t(255)};
      }
      for (size_t c = 0; c < columns.size(); ++c) {
        const size_t stride = columns[c].stride();
        std::memcpy(columns[c].bytes.data() + i * stride, p + extra_offsets[c], stride);
      }
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
