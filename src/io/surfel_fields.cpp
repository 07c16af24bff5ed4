#include "io/surfel_fields.h"

#include <cstring>
#include <stdexcept>
#include <unordered_map>

#include "io/io_error.h"
#include "io/scalar_codec.h"

namespace rc {

namespace {

constexpr const char* kAxisNames[2][3] = {{"axis1_x", "axis1_y", "axis1_z"},
                                          {"axis2_x", "axis2_y", "axis2_z"}};

class FieldMatcher {
 public:
  explicit FieldMatcher(const std::vector<FieldSpec>& fields)
      : fields_(fields), bound_(fields.size(), false) {
    for (size_t k = 0; k < fields.size(); ++k) index_.emplace(fields[k].name, k);
  }
  /// Index of an unbound scalar (count 1) field called `name` (and of `type` if given), or -1.
  int find(const char* name, const ScalarType* type = nullptr) const {
    const auto it = index_.find(name);
    if (it == index_.end() || bound_[it->second] || fields_[it->second].count != 1) return -1;
    if (type && fields_[it->second].type != *type) return -1;
    return static_cast<int>(it->second);
  }
  /// Binds all of `names` (n of them) to target with axis = position in the list, if all are present.
  bool bindAll(const char* const* names, int n, FieldTarget target, std::vector<FieldBinding>* bindings,
               const ScalarType* type = nullptr) {
    int found[4];
    for (int a = 0; a < n; ++a)
      if ((found[a] = find(names[a], type)) < 0) return false;
    for (int a = 0; a < n; ++a) bind(found[a], target, static_cast<uint8_t>(a), bindings);
    return true;
  }
  void bind(int k, FieldTarget target, uint8_t axis, std::vector<FieldBinding>* bindings) {
    bound_[k] = true;
    FieldBinding& b = (*bindings)[k];
    b.target = target;
    b.axis = axis;
  }
  bool bound(size_t k) const { return bound_[k]; }

 private:
  const std::vector<FieldSpec>& fields_;
  std::unordered_map<std::string, size_t> index_;
  std::vector<bool> bound_;
};

bool isFourBytes(const FieldSpec& f) {
  return f.count == 1 && scalarSize(f.type) == 4;
}

uint32_t packRgba(const Rgba& c) {
  return (uint32_t(c[3]) << 24) | (uint32_t(c[0]) << 16) | (uint32_t(c[1]) << 8) | uint32_t(c[2]);
}

}  // namespace

bool bindFields(const std::vector<FieldSpec>& fields, size_t n, const std::string& file,
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
  *cloud = SurfelCloud();
  cloud->positions.resize(n);
  FieldMatcher match(fields);

  static const char* const kXyz[] = {"x", "y", "z"};
  const bool has_positions = match.bindAll(kXyz, 3, FieldTarget::kPosition, bindings);

  static const char* const kNormalsShort[] = {"nx", "ny", "nz"};
  static const char* const kNormalsLong[] = {"normal_x", "normal_y", "normal_z"};
  if (match.bindAll(kNormalsShort, 3, FieldTarget::kNormal, bindings) ||
      match.bindAll(kNormalsLong, 3, FieldTarget::kNormal, bindings))
    cloud->normals.assign(n, Vec3::Zero());

  if (match.bindAll(kAxisNames[0], 3, FieldTarget::kAxis1, bindings) &&
      match.bindAll(kAxisNames[1], 3, FieldTarget::kAxis2, bindings)) {
    cloud->axes1.assign(n, Vec3::Zero());
    cloud->axes2.assign(n, Vec3::Zero());
  }

  const int radius = match.find("radius");
  if (radius >= 0) {
    match.bind(radius, FieldTarget::kRadius, 0, bindings);
    cloud->radii.assign(n, 0.0);
  }

  static const char* const kRgb[] = {"red", "green", "blue"};
  static const char* const kDiffuseRgb[] = {"diffuse_red", "diffuse_green", "diffuse_blue"};
  const ScalarType uint8_type = ScalarType::kUInt8;
  bool has_colors = false;
  if (match.bindAll(kRgb, 3, FieldTarget::kColorComponent, bindings, &uint8_type) ||
      match.bindAll(kDiffuseRgb, 3, FieldTarget::kColorComponent, bindings, &uint8_type)) {
    has_colors = true;
    int alpha = match.find("alpha", &uint8_type);
    if (alpha < 0) alpha = match.find("diffuse_alpha", &uint8_type);
    if (alpha >= 0) match.bind(alpha, FieldTarget::kColorComponent, 3, bindings);
  } else {
    const int rgba = match.find("rgba");
    const int rgb = match.find("rgb");
    if (rgba >= 0 && isFourBytes(fields[rgba])) {
      match.bind(rgba, FieldTarget::kPackedRgba, 0, bindings);
      has_colors = true;
    } else if (rgb >= 0 && isFourBytes(fields[rgb])) {
      match.bind(rgb, FieldTarget::kPackedRgb, 0, bindings);
      has_colors = true;
    }
  }
  if (has_colors) cloud->colors.assign(n, Rgba{0, 0, 0, 255});

  const int confidence = match.find("confidence");
  if (confidence >= 0) {
    match.bind(confidence, FieldTarget::kConfidence, 0, bindings);
    cloud->confidence.assign(n, 0.0f);
  }
  const int curvature = match.find("curvature");
  if (curvature >= 0) {
    match.bind(curvature, FieldTarget::kCurvature, 0, bindings);
    cloud->curvature.assign(n, 0.0f);
  }

  for (size_t k = 0; k < fields.size(); ++k) {
    if (match.bound(k)) continue;
    FieldBinding& b = (*bindings)[k];
    if (fields[k].name == "_") {
      b.target = FieldTarget::kSkip;
      continue;
    }
    b.target = FieldTarget::kAttribute;
    b.attribute = cloud->attributes.columns().size();
    cloud->attributes.add(fields[k].name, fields[k].type, fields[k].count, n);
  }
  return has_positions;
}

void storeField(const FieldBinding& b, size_t i, uint32_t component, const uint8_t* value,
                SurfelCloud* cloud) {
  switch (b.target) {
    case FieldTarget::kPosition:
      cloud->positions[i][b.axis] = scalarToDouble(value, b.type);
      break;
    case FieldTarget::kNormal:
      cloud->normals[i][b.axis] = scalarToDouble(value, b.type);
      break;
    case FieldTarget::kRadius:
      cloud->radii[i] = scalarToDouble(value, b.type);
      break;
    case FieldTarget::kAxis1:
      cloud->axes1[i][b.axis] = scalarToDouble(value, b.type);
      break;
    case FieldTarget::kAxis2:
      cloud->axes2[i][b.axis] = scalarToDouble(value, b.type);
      break;
    case FieldTarget::kColorComponent:
      cloud->colors[i][b.axis] = value[0];
      break;
    case FieldTarget::kPackedRgb:
    case FieldTarget::kPackedRgba: {
      uint32_t packed;
      std::memcpy(&packed, value, 4);
      const uint8_t alpha = b.target == FieldTarget::kPackedRgba ? uint8_t(packed >> 24) : uint8_t(255);
      cloud->colors[i] = Rgba{uint8_t(packed >> 16), uint8_t(packed >> 8), uint8_t(packed), alpha};
      break;
    }
    case FieldTarget::kConfidence:
      cloud->confidence[i] = static_cast<float>(scalarToDouble(value, b.type));
      break;
    case FieldTarget::kCurvature:
      cloud->curvature[i] = static_cast<float>(scalarToDouble(value, b.type));
      break;
    case FieldTarget::kAttribute: {
      Attribute& column = cloud->attributes.columns()[b.attribute];
      const size_t size = scalarSize(b.type);
      std::memcpy(column.bytes.data() + i * column.stride() + component * size, value, size);
      break;
    }
    case FieldTarget::kSkip:
      break;
  }
}

void describeCloudFields(const SurfelCloud& cloud, FieldNaming naming, bool double_precision,
                         const std::string& file, std::vector<FieldSpec>* fields,
                         std::vector<FieldBinding>* bindings) {
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
  static const char* const kXyz[] = {"x", "y", "z"};
  static const char* const kPlyNormals[] = {"nx", "ny", "nz"};
  static const char* const kPcdNormals[] = {"normal_x", "normal_y", "normal_z"};
  static const char* const kRgba[] = {"red", "green", "blue", "alpha"};
  for (uint8_t a = 0; a < 3; ++a) add(kXyz[a], real, 1, FieldTarget::kPosition, a, 0);
  if (cloud.hasNormals())
    for (uint8_t a = 0; a < 3; ++a)
      add((ply ? kPlyNormals : kPcdNormals)[a], real, 1, FieldTarget::kNormal, a, 0);
  if (cloud.hasRadii()) add("radius", real, 1, FieldTarget::kRadius, 0, 0);
  if (cloud.hasAxes()) {
    for (uint8_t a = 0; a < 3; ++a) add(kAxisNames[0][a], real, 1, FieldTarget::kAxis1, a, 0);
    for (uint8_t a = 0; a < 3; ++a) add(kAxisNames[1][a], real, 1, FieldTarget::kAxis2, a, 0);
  }
  if (cloud.hasColors()) {
    if (ply)
      for (uint8_t a = 0; a < 4; ++a)
        add(kRgba[a], ScalarType::kUInt8, 1, FieldTarget::kColorComponent, a, 0);
    else
      add("rgba", ScalarType::kUInt32, 1, FieldTarget::kPackedRgba, 0, 0);
  }
  if (cloud.hasConfidence()) add("confidence", ScalarType::kFloat32, 1, FieldTarget::kConfidence, 0, 0);
  if (cloud.hasCurvature()) add("curvature", ScalarType::kFloat32, 1, FieldTarget::kCurvature, 0, 0);

  const size_t channel_fields = fields->size();
  const auto& columns = cloud.attributes.columns();
  for (size_t c = 0; c < columns.size(); ++c) {
    const Attribute& a = columns[c];
    if (a.name.empty() || a.name.find_first_of(" \t\r\n") != std::string::npos)
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

void loadField(const FieldBinding& b, size_t i, uint32_t component, const SurfelCloud& cloud,
               uint8_t* value) {
  switch (b.target) {
    case FieldTarget::kPosition:
      doubleToScalar(cloud.positions[i][b.axis], b.type, value);
      break;
    case FieldTarget::kNormal:
      doubleToScalar(cloud.normals[i][b.axis], b.type, value);
      break;
    case FieldTarget::kRadius:
      doubleToScalar(cloud.radii[i], b.type, value);
      break;
    case FieldTarget::kAxis1:
      doubleToScalar(cloud.axes1[i][b.axis], b.type, value);
      break;
    case FieldTarget::kAxis2:
      doubleToScalar(cloud.axes2[i][b.axis], b.type, value);
      break;
    case FieldTarget::kColorComponent:
      value[0] = cloud.colors[i][b.axis];
      break;
    case FieldTarget::kPackedRgb:
    case FieldTarget::kPackedRgba: {
      const uint32_t packed = packRgba(cloud.colors[i]);
      std::memcpy(value, &packed, 4);
      break;
    }
    case FieldTarget::kConfidence:
      doubleToScalar(cloud.confidence[i], b.type, value);
      break;
    case FieldTarget::kCurvature:
      doubleToScalar(cloud.curvature[i], b.type, value);
      break;
    case FieldTarget::kAttribute: {
      const Attribute& column = cloud.attributes.columns()[b.attribute];
      const size_t size = scalarSize(b.type);
      std::memcpy(value, column.bytes.data() + i * column.stride() + component * size, size);
      break;
    }
    case FieldTarget::kSkip:
      std::memset(value, 0, scalarSize(b.type));
      break;
  }
}

}  // namespace rc
