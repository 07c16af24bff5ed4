#include "relaxed_connectivity/io/surfel_fields.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <type_traits>
#include <unordered_map>

#include "relaxed_connectivity/io/io_error.h"

namespace rc {

namespace {

// Channel field names; a channel takes any of its groups when reading.
const char* const kXyz[] = {"x", "y", "z"};
const char* const kPlyNormals[] = {"nx", "ny", "nz"};
const char* const kPcdNormals[] = {"normal_x", "normal_y", "normal_z"};
const char* const kFileAxes[] = {"axis1_x", "axis1_y", "axis1_z", "axis2_x", "axis2_y", "axis2_z"};
const char* const kPointCloud2Axes[] = {"t1x", "t1y", "t1z", "t2x", "t2y", "t2z"};
const char* const kRgbComponents[] = {"red", "green", "blue", "alpha"};
const char* const kDiffuseRgbComponents[] = {"diffuse_red", "diffuse_green", "diffuse_blue"};
const char* const kRadius[] = {"radius"};
const char* const kConfidence[] = {"confidence"};
const char* const kCurvature[] = {"curvature"};
const char* const kPackedRgba[] = {"rgba"};
const char* const kPackedRgb[] = {"rgb"};
const char* const kDiffuseAlpha[] = {"diffuse_alpha"};

/// What a channel field must hold.
enum class Holds { kReal, kUInt8, kPacked };

class FieldMatcher {
 public:
  FieldMatcher(const std::vector<FieldSpec>& fields, bool strict, const std::string& file,
               const std::string& where, std::vector<FieldBinding>* bindings)
      : fields_(fields), strict_(strict), file_(file), where_(where), bindings_(*bindings) {
    for (size_t k = 0; k < fields.size(); ++k) index_.emplace(fields[k].name, k);
  }

  /// True with the indices of `names` in `found` if all are present and hold `holds`. A group of which some
  /// fields are present but that cannot fill its channel: false (lenient) or IoError naming the field
  /// (strict).
  bool findGroup(const char* const* names, int n, Holds holds, int* found) const {
    int present = 0;
    for (int a = 0; a < n; ++a) {
      const auto it = index_.find(names[a]);
      found[a] = it == index_.end() ? -1 : static_cast<int>(it->second);
      present += found[a] >= 0;
    }
    if (present == 0) return false;
    for (int a = 0; a < n; ++a) {
      const std::string field = std::string("field '") + names[a] + "' ";
      if (found[a] < 0) return reject(field + "is missing (the other fields of its group are present)");
      const FieldSpec& f = fields_[found[a]];
      if (f.count != 1) return reject(field + "has count " + std::to_string(f.count) + ", expected 1");
      const char* expected = typeProblem(f.type, holds);
      if (expected)
        return reject(field + "has datatype " + pointFieldTypeName(f.type) + ", expected " + expected);
    }
    return true;
  }

  /// Binds found[0..n) to target with axis first_axis + their position.
  void bind(const int* found, int n, FieldTarget target, int first_axis = 0) {
    for (int a = 0; a < n; ++a) {
      FieldBinding& b = bindings_[found[a]];
      b.target = target;
      b.axis = static_cast<uint8_t>(first_axis + a);
    }
  }

 private:
  bool reject(const std::string& problem) const {
    if (strict_) throw IoError(file_, where_, problem);
    return false;
  }
  /// The types `holds` takes if `type` is not one of them.
  const char* typeProblem(ScalarType type, Holds holds) const {
    switch (holds) {
      case Holds::kReal:
        return strict_ && type != ScalarType::kFloat32 && type != ScalarType::kFloat64 ? "FLOAT32 or FLOAT64"
                                                                                       : nullptr;
      case Holds::kUInt8:
        return type != ScalarType::kUInt8 ? "UINT8" : nullptr;
      case Holds::kPacked:
        return scalarSize(type) != 4 ? "one packed UINT32/FLOAT32" : nullptr;
    }
    return nullptr;
  }

  const std::vector<FieldSpec>& fields_;
  const bool strict_;
  const std::string& file_;
  const std::string& where_;
  std::vector<FieldBinding>& bindings_;
  std::unordered_map<std::string, size_t> index_;
};

uint32_t packRgba(const Rgba& c) {
  return (uint32_t(c[3]) << 24) | (uint32_t(c[0]) << 16) | (uint32_t(c[1]) << 8) | uint32_t(c[2]);
}

/// Calls fn(T()) with the C++ type T of `type`.
template <typename Fn>
void withScalarType(ScalarType type, Fn&& fn) {
  switch (type) {
    case ScalarType::kInt8:
      return fn(int8_t());
    case ScalarType::kUInt8:
      return fn(uint8_t());
    case ScalarType::kInt16:
      return fn(int16_t());
    case ScalarType::kUInt16:
      return fn(uint16_t());
    case ScalarType::kInt32:
      return fn(int32_t());
    case ScalarType::kUInt32:
      return fn(uint32_t());
    case ScalarType::kFloat32:
      return fn(float());
    case ScalarType::kFloat64:
      return fn(double());
  }
}

/// Converts n elements of kWidth values each through double: value c of element j from
/// from + j * from_stride + from_offsets[c] to to + j * to_stride + to_offsets[c] (memcpy keeps the loops
/// free of aliasing and alignment assumptions).
template <typename From, typename To, int kWidth>
void convertValues(const uint8_t* from, const uint32_t* from_offsets, size_t from_stride, uint8_t* to,
                   const uint32_t* to_offsets, size_t to_stride, size_t n) {
  uint32_t in[kWidth], out[kWidth];
  std::copy_n(from_offsets, kWidth, in);
  std::copy_n(to_offsets, kWidth, out);
  for (size_t j = 0; j < n; ++j, from += from_stride, to += to_stride)
    for (int c = 0; c < kWidth; ++c) {
      From v;
      std::memcpy(&v, from + in[c], sizeof(From));
      const To w = static_cast<To>(static_cast<double>(v));
      std::memcpy(to + out[c], &w, sizeof(To));
    }
}

/// Copies n values of kSize bytes.
template <size_t kSize>
void copyValues(const uint8_t* from, size_t from_stride, uint8_t* to, size_t to_stride, size_t n) {
  for (size_t j = 0; j < n; ++j, from += from_stride, to += to_stride) std::memcpy(to, from, kSize);
}

/// Where the kWidth values of an element lie, in the records and in the channel.
template <int kWidth>
struct ValueOffsets {
  const uint32_t* values;
  const uint32_t* channel;
};

/// Record values of `type` into a channel of Real (double or float).
template <typename Real, int kWidth>
void storeReals(ScalarType type, const uint8_t* values, size_t stride, uint8_t* channel,
                size_t channel_stride, ValueOffsets<kWidth> offsets, size_t n) {
  withScalarType(type, [&](auto zero) {
    convertValues<decltype(zero), Real, kWidth>(values, offsets.values, stride, channel, offsets.channel,
                                                channel_stride, n);
  });
}

/// A channel of Real (double or float) into record values of `type`.
template <typename Real, int kWidth>
void loadReals(const uint8_t* channel, size_t channel_stride, ScalarType type, uint8_t* values, size_t stride,
               ValueOffsets<kWidth> offsets, size_t n) {
  withScalarType(type, [&](auto zero) {
    convertValues<Real, decltype(zero), kWidth>(channel, offsets.channel, channel_stride, values,
                                                offsets.values, stride, n);
  });
}

void copyScalars(ScalarType type, const uint8_t* from, size_t from_stride, uint8_t* to, size_t to_stride,
                 size_t n) {
  withScalarType(type, [&](auto zero) { copyValues<sizeof(zero)>(from, from_stride, to, to_stride, n); });
}

template <typename Cloud>
auto vectorChannel(Cloud& cloud, FieldTarget target) {
  switch (target) {
    case FieldTarget::kPosition:
      return &cloud.positions;
    case FieldTarget::kNormal:
      return &cloud.normals;
    case FieldTarget::kAxis1:
      return &cloud.axes1;
    case FieldTarget::kAxis2:
      return &cloud.axes2;
    default:
      return decltype(&cloud.positions)(nullptr);
  }
}

/// Whether bindings k, k + 1, k + 2 are x, y, z of one vector channel, in one type.
bool isVectorRun(const std::vector<FieldBinding>& bindings, size_t k, const SurfelCloud& cloud) {
  if (k + 3 > bindings.size() || !vectorChannel(cloud, bindings[k].target)) return false;
  for (uint8_t a = 0; a < 3; ++a) {
    const FieldBinding& b = bindings[k + a];
    if (b.target != bindings[k].target || b.axis != a || b.type != bindings[k].type || b.count != 1)
      return false;
  }
  return true;
}

constexpr uint32_t kVectorOffsets[3] = {0, sizeof(double), 2 * sizeof(double)};
constexpr uint32_t kNoOffset[1] = {0};

/// The bytes of element i, from byte `offset` on.
template <typename Element>
auto elementBytes(Element* elements, size_t i, size_t offset = 0) {
  using Byte = std::conditional_t<std::is_const_v<Element>, const uint8_t, uint8_t>;
  return reinterpret_cast<Byte*>(elements + i) + offset;
}

enum class Channel { kNormals, kRadius, kAxes, kColors, kConfidence, kCurvature };

bool hasChannel(const SurfelCloud& cloud, Channel channel) {
  switch (channel) {
    case Channel::kNormals:
      return cloud.hasNormals();
    case Channel::kRadius:
      return cloud.hasRadii();
    case Channel::kAxes:
      return cloud.hasAxes();
    case Channel::kColors:
      return cloud.hasColors();
    case Channel::kConfidence:
      return cloud.hasConfidence();
    case Channel::kCurvature:
      return cloud.hasCurvature();
  }
  return false;
}

}  // namespace

bool bindFields(const std::vector<FieldSpec>& fields, FieldNaming naming, size_t n, const std::string& file,
                const std::string& where, SurfelCloud* cloud, std::vector<FieldBinding>* bindings) {
  bindings->assign(fields.size(), FieldBinding());
  {
    std::unordered_map<std::string, size_t> seen;
    for (size_t k = 0; k < fields.size(); ++k) {
      (*bindings)[k].type = fields[k].type;
      (*bindings)[k].count = fields[k].count;
      if (fields[k].name != "_" && !seen.emplace(fields[k].name, k).second)
        throw IoError(file, where, "duplicate field '" + fields[k].name + "'");
    }
  }
  FieldMatcher match(fields, naming == FieldNaming::kPointCloud2, file, where, bindings);
  int found[6];

  const bool has_positions = match.findGroup(kXyz, 3, Holds::kReal, found);
  if (has_positions) match.bind(found, 3, FieldTarget::kPosition);

  const bool has_normals = match.findGroup(kPlyNormals, 3, Holds::kReal, found) ||
                           match.findGroup(kPcdNormals, 3, Holds::kReal, found);
  if (has_normals) match.bind(found, 3, FieldTarget::kNormal);

  const bool has_axes = match.findGroup(kFileAxes, 6, Holds::kReal, found) ||
                        match.findGroup(kPointCloud2Axes, 6, Holds::kReal, found);
  if (has_axes) {
    match.bind(found, 3, FieldTarget::kAxis1);
    match.bind(found + 3, 3, FieldTarget::kAxis2);
  }

  const bool has_radii = match.findGroup(kRadius, 1, Holds::kReal, found);
  if (has_radii) match.bind(found, 1, FieldTarget::kRadius);

  bool has_colors = true;
  if (match.findGroup(kRgbComponents, 3, Holds::kUInt8, found) ||
      match.findGroup(kDiffuseRgbComponents, 3, Holds::kUInt8, found)) {
    match.bind(found, 3, FieldTarget::kColorComponent);
    if (match.findGroup(kRgbComponents + 3, 1, Holds::kUInt8, found) ||
        match.findGroup(kDiffuseAlpha, 1, Holds::kUInt8, found))
      match.bind(found, 1, FieldTarget::kColorComponent, 3);
  } else if (match.findGroup(kPackedRgba, 1, Holds::kPacked, found)) {
    match.bind(found, 1, FieldTarget::kPackedRgba);
  } else if (match.findGroup(kPackedRgb, 1, Holds::kPacked, found)) {
    match.bind(found, 1, FieldTarget::kPackedRgb);
  } else {
    has_colors = false;
  }

  const bool has_confidence = match.findGroup(kConfidence, 1, Holds::kReal, found);
  if (has_confidence) match.bind(found, 1, FieldTarget::kConfidence);
  const bool has_curvature = match.findGroup(kCurvature, 1, Holds::kReal, found);
  if (has_curvature) match.bind(found, 1, FieldTarget::kCurvature);

  // Bound without errors: only now is the cloud replaced, in the memory of its channels (a caller that reads
  // into one cloud again and again allocates nothing). Every bound field is stored for every surfel; only
  // colours need a start value (alpha 255 for the fields without alpha).
  cloud->clear();
  cloud->attributes = AttributeSet();
  cloud->frame_id.clear();
  cloud->stamp_ns = 0;
  cloud->positions.resize(n);
  if (has_normals) cloud->normals.resize(n);
  if (has_axes) {
    cloud->axes1.resize(n);
    cloud->axes2.resize(n);
  }
  if (has_radii) cloud->radii.resize(n);
  if (has_colors) cloud->colors.assign(n, Rgba{0, 0, 0, 255});
  if (has_confidence) cloud->confidence.resize(n);
  if (has_curvature) cloud->curvature.resize(n);
  for (size_t k = 0; k < fields.size(); ++k) {
    FieldBinding& b = (*bindings)[k];
    if (b.target != FieldTarget::kSkip || fields[k].name == "_") continue;
    b.target = FieldTarget::kAttribute;
    b.attribute = cloud->attributes.columns().size();
    cloud->attributes.add(fields[k].name, fields[k].type, fields[k].count, n);
  }
  return has_positions;
}

void storeFieldValues(const FieldBinding& b, uint32_t component, const uint8_t* values, size_t stride,
                      size_t first, size_t n, SurfelCloud* cloud) {
  const ValueOffsets<1> offsets{kNoOffset, kNoOffset};
  if (std::vector<Vec3>* vectors = vectorChannel(*cloud, b.target))
    return storeReals<double>(b.type, values, stride,
                              elementBytes(vectors->data(), first, b.axis * sizeof(double)), sizeof(Vec3),
                              offsets, n);
  const auto scalars = [&](auto& channel) {
    using Real = typename std::decay_t<decltype(channel)>::value_type;
    storeReals<Real>(b.type, values, stride, elementBytes(channel.data(), first), sizeof(Real), offsets, n);
  };
  switch (b.target) {
    case FieldTarget::kRadius:
      return scalars(cloud->radii);
    case FieldTarget::kConfidence:
      return scalars(cloud->confidence);
    case FieldTarget::kCurvature:
      return scalars(cloud->curvature);
    case FieldTarget::kColorComponent:
      return copyValues<1>(values, stride, elementBytes(cloud->colors.data(), first, b.axis), sizeof(Rgba),
                           n);
    case FieldTarget::kPackedRgb:
    case FieldTarget::kPackedRgba: {
      const bool has_alpha = b.target == FieldTarget::kPackedRgba;
      Rgba* colors = cloud->colors.data() + first;
      for (size_t j = 0; j < n; ++j) {
        uint32_t packed;
        std::memcpy(&packed, values + j * stride, 4);
        const uint8_t alpha = has_alpha ? uint8_t(packed >> 24) : uint8_t(255);
        colors[j] = Rgba{uint8_t(packed >> 16), uint8_t(packed >> 8), uint8_t(packed), alpha};
      }
      return;
    }
    case FieldTarget::kAttribute: {
      Attribute& column = cloud->attributes.columns()[b.attribute];
      uint8_t* out = column.bytes.data() + first * column.stride() + component * scalarSize(b.type);
      return copyScalars(b.type, values, stride, out, column.stride(), n);
    }
    default:  // kSkip; vectors above
      return;
  }
}

void describeCloudFields(const SurfelCloud& cloud, FieldNaming naming, bool double_precision,
                         const std::string& file, std::vector<FieldSpec>* fields,
                         std::vector<FieldBinding>* bindings, bool all_point_surfel_channels) {
  fields->clear();
  bindings->clear();
  try {
    cloud.validate();
  } catch (const std::invalid_argument& e) {
    throw IoError(file, e.what());
  }
  const ScalarType real = double_precision ? ScalarType::kFloat64 : ScalarType::kFloat32;
  auto add = [&](const std::string& name, ScalarType type, uint32_t count, FieldTarget target, uint8_t axis,
                 size_t attribute) {
    fields->push_back(FieldSpec{name, type, count});
    FieldBinding b;
    b.target = target;
    b.axis = axis;
    b.type = type;
    b.count = count;
    b.attribute = attribute;
    bindings->push_back(b);
  };
  const bool ply = naming == FieldNaming::kPly;
  const bool point_cloud2 = naming == FieldNaming::kPointCloud2;
  for (uint8_t a = 0; a < 3; ++a) add(kXyz[a], real, 1, FieldTarget::kPosition, a, 0);
  static const Channel kFileOrder[] = {Channel::kNormals, Channel::kRadius,     Channel::kAxes,
                                       Channel::kColors,  Channel::kConfidence, Channel::kCurvature};
  static const Channel kPointSurfelOrder[] = {Channel::kNormals,    Channel::kColors,    Channel::kRadius,
                                              Channel::kConfidence, Channel::kCurvature, Channel::kAxes};
  for (const Channel channel : point_cloud2 ? kPointSurfelOrder : kFileOrder) {
    const bool present = hasChannel(cloud, channel);
    if (!present && !(all_point_surfel_channels && channel != Channel::kAxes)) continue;
    const auto target = [&](FieldTarget t) { return present ? t : FieldTarget::kSkip; };
    switch (channel) {
      case Channel::kNormals:
        for (uint8_t a = 0; a < 3; ++a)
          add((ply ? kPlyNormals : kPcdNormals)[a], real, 1, target(FieldTarget::kNormal), a, 0);
        break;
      case Channel::kRadius:
        add(kRadius[0], real, 1, target(FieldTarget::kRadius), 0, 0);
        break;
      case Channel::kAxes:
        for (uint8_t a = 0; a < 6; ++a)
          add((point_cloud2 ? kPointCloud2Axes : kFileAxes)[a], real, 1,
              a < 3 ? FieldTarget::kAxis1 : FieldTarget::kAxis2, a % 3, 0);
        break;
      case Channel::kColors:
        if (ply)
          for (uint8_t a = 0; a < 4; ++a)
            add(kRgbComponents[a], ScalarType::kUInt8, 1, target(FieldTarget::kColorComponent), a, 0);
        else
          add(kPackedRgba[0], ScalarType::kUInt32, 1, target(FieldTarget::kPackedRgba), 0, 0);
        break;
      case Channel::kConfidence:
        add(kConfidence[0], ScalarType::kFloat32, 1, target(FieldTarget::kConfidence), 0, 0);
        break;
      case Channel::kCurvature:
        add(kCurvature[0], ScalarType::kFloat32, 1, target(FieldTarget::kCurvature), 0, 0);
        break;
    }
  }

  const size_t channel_fields = fields->size();
  const auto& columns = cloud.attributes.columns();
  for (size_t c = 0; c < columns.size(); ++c) {
    const Attribute& a = columns[c];
    if (!point_cloud2 && (a.name.empty() || a.name.find_first_of(" \t\r\n") != std::string::npos))
      throw IoError(file, "attribute '" + a.name + "' has an empty name or contains blanks");
    for (size_t k = 0; k < channel_fields; ++k)
      if ((*fields)[k].name == a.name)
        throw IoError(file, "attribute '" + a.name + "' has the name of a channel field");
    if (a.size() != cloud.size())
      throw IoError(file, "attribute '" + a.name + "' has " + std::to_string(a.size()) +
                              " elements, expected " + std::to_string(cloud.size()));
    add(a.name, a.type, a.count, FieldTarget::kAttribute, 0, c);
  }
}

void loadFieldValues(const FieldBinding& b, uint32_t component, const SurfelCloud& cloud, size_t first,
                     size_t n, uint8_t* values, size_t stride) {
  const ValueOffsets<1> offsets{kNoOffset, kNoOffset};
  if (const std::vector<Vec3>* vectors = vectorChannel(cloud, b.target))
    return loadReals<double>(elementBytes(vectors->data(), first, b.axis * sizeof(double)), sizeof(Vec3),
                             b.type, values, stride, offsets, n);
  const auto scalars = [&](const auto& channel) {
    using Real = typename std::decay_t<decltype(channel)>::value_type;
    loadReals<Real>(elementBytes(channel.data(), first), sizeof(Real), b.type, values, stride, offsets, n);
  };
  switch (b.target) {
    case FieldTarget::kRadius:
      return scalars(cloud.radii);
    case FieldTarget::kConfidence:
      return scalars(cloud.confidence);
    case FieldTarget::kCurvature:
      return scalars(cloud.curvature);
    case FieldTarget::kColorComponent:
      return copyValues<1>(elementBytes(cloud.colors.data(), first, b.axis), sizeof(Rgba), values, stride, n);
    case FieldTarget::kPackedRgb:
    case FieldTarget::kPackedRgba: {
      const Rgba* colors = cloud.colors.data() + first;
      for (size_t j = 0; j < n; ++j) {
        const uint32_t packed = packRgba(colors[j]);
        std::memcpy(values + j * stride, &packed, 4);
      }
      return;
    }
    case FieldTarget::kAttribute: {
      const Attribute& column = cloud.attributes.columns()[b.attribute];
      const uint8_t* in = column.bytes.data() + first * column.stride() + component * scalarSize(b.type);
      return copyScalars(b.type, in, column.stride(), values, stride, n);
    }
    case FieldTarget::kSkip:
      for (size_t j = 0; j < n; ++j) std::memset(values + j * stride, 0, scalarSize(b.type));
      return;
    default:  // vectors above
      return;
  }
}

void storeRecords(const std::vector<FieldBinding>& bindings, const std::vector<uint32_t>& offsets,
                  const uint8_t* records, size_t stride, size_t first, size_t n, SurfelCloud* cloud) {
  for (size_t k = 0; k < bindings.size(); ++k) {
    const FieldBinding& b = bindings[k];
    if (isVectorRun(bindings, k, *cloud)) {
      const uint32_t* value_offsets = &offsets[k];
      storeReals<double, 3>(b.type, records, stride,
                            elementBytes(vectorChannel(*cloud, b.target)->data(), first), sizeof(Vec3),
                            ValueOffsets<3>{value_offsets, kVectorOffsets}, n);
      k += 2;
      continue;
    }
    const size_t size = scalarSize(b.type);
    for (uint32_t c = 0; c < b.count; ++c)
      storeFieldValues(b, c, records + offsets[k] + c * size, stride, first, n, cloud);
  }
}

void loadRecords(const std::vector<FieldBinding>& bindings, const std::vector<uint32_t>& offsets,
                 const SurfelCloud& cloud, size_t first, size_t n, uint8_t* records, size_t stride) {
  for (size_t k = 0; k < bindings.size(); ++k) {
    const FieldBinding& b = bindings[k];
    if (b.target == FieldTarget::kSkip) continue;
    if (isVectorRun(bindings, k, cloud)) {
      const uint32_t* value_offsets = &offsets[k];
      loadReals<double, 3>(elementBytes(vectorChannel(cloud, b.target)->data(), first), sizeof(Vec3), b.type,
                           records, stride, ValueOffsets<3>{value_offsets, kVectorOffsets}, n);
      k += 2;
      continue;
    }
    const size_t size = scalarSize(b.type);
    for (uint32_t c = 0; c < b.count; ++c)
      loadFieldValues(b, c, cloud, first, n, records + offsets[k] + c * size, stride);
  }
}

bool scalarTypeOfPointField(uint8_t datatype, ScalarType* type) {
  if (datatype < 1 || datatype > 8) return false;
  *type = static_cast<ScalarType>(datatype - 1);
  return true;
}

const char* pointFieldTypeName(ScalarType type) {
  static const char* const kNames[] = {"INT8",  "UINT8",  "INT16",   "UINT16",
                                       "INT32", "UINT32", "FLOAT32", "FLOAT64"};
  return kNames[static_cast<uint8_t>(type)];
}

}  // namespace rc
