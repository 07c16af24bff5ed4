// Maps named scalar fields (PLY vertex properties, PCD fields, PointCloud2 fields) onto SurfelCloud channels
// and back. Fields that name no channel become attribute columns (raw bytes, so they survive a round trip
// bit-exactly). Reading accepts the names of every format (nx or normal_x, axis1_x or t1x, ...), so a field
// name means the same channel in every format.
#pragma once

#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

struct FieldSpec {
  std::string name;
  ScalarType type = ScalarType::kFloat32;
  uint32_t count = 1;  ///< values per surfel
};

enum class FieldTarget : uint8_t {
  kPosition,
  kNormal,
  kRadius,
  kAxis1,
  kAxis2,
  kColorComponent,  ///< one uint8 of r, g, b, a
  kPackedRgb,       ///< 4 bytes 0x??RRGGBB (PCL "rgb"); alpha is set to 255
  kPackedRgba,      ///< 4 bytes 0xAARRGGBB (PCL "rgba")
  kConfidence,
  kCurvature,
  kAttribute,
  kSkip,  ///< padding ("_"), or a channel the cloud lacks (written as zeros)
};

struct FieldBinding {
  FieldTarget target = FieldTarget::kSkip;
  uint8_t axis = 0;  ///< vector component (0..2) or colour byte (r g b a = 0..3)
  ScalarType type = ScalarType::kFloat32;
  uint32_t count = 1;
  size_t attribute = 0;  ///< column index in cloud.attributes for kAttribute
};

/// The conventions of a format. Written names: PLY nx/red/green/blue/alpha/axis1_x, PCD normal_x/rgba
/// (packed)/axis1_x, PointCloud2 as PCD but t1x..t2z and in pcl::PointSurfel's order (x y z normal rgba
/// radius confidence curvature, then the axes). Reading: PLY and PCD keep a field named like a channel that
/// cannot fill it (type, count, incomplete group) as an attribute; PointCloud2 rejects it (IoError naming the
/// field).
enum class FieldNaming { kPly, kPcd, kPointCloud2 };

/// Binds `fields` (in order) to channels of `cloud`, which is resized to n surfels with every bound channel
/// allocated. Throws IoError(file, where, ...) on duplicate field names and, for kPointCloud2, on channel
/// fields that are not float32/float64 (colours: uint8 components or one packed 4-byte value), have a count
/// other than 1 or miss a member of their group (x y z, the normal, the axes, red green blue). Returns
/// whether x, y, z were found.
bool bindFields(const std::vector<FieldSpec>& fields, FieldNaming naming, size_t n, const std::string& file,
                const std::string& where, SurfelCloud* cloud, std::vector<FieldBinding>* bindings);

/// Stores value `component` of surfels first .. first + n - 1; the value of surfel first + j is one scalar of
/// binding.type (host byte order) at `values + j * stride`.
void storeFieldValues(const FieldBinding& binding, uint32_t component, const uint8_t* values, size_t stride,
                      size_t first, size_t n, SurfelCloud* cloud);
inline void storeField(const FieldBinding& binding, size_t i, uint32_t component, const uint8_t* value,
                       SurfelCloud* cloud) {
  storeFieldValues(binding, component, value, 0, i, 1, cloud);
}

/// The fields (with bindings) that write every present channel and attribute of `cloud`; with
/// `all_point_surfel_channels` also the pcl::PointSurfel channels it lacks (normal, rgba, radius, confidence,
/// curvature; bound to kSkip). Throws IoError if an attribute name collides with a channel field or (PLY,
/// PCD) contains blanks.
void describeCloudFields(const SurfelCloud& cloud, FieldNaming naming, bool double_precision,
                         const std::string& file, std::vector<FieldSpec>* fields,
                         std::vector<FieldBinding>* bindings, bool all_point_surfel_channels = false);

/// Loads value `component` of surfels first .. first + n - 1 as binding.type (host byte order) to
/// `values + j * stride`.
void loadFieldValues(const FieldBinding& binding, uint32_t component, const SurfelCloud& cloud, size_t first,
                     size_t n, uint8_t* values, size_t stride);
inline void loadField(const FieldBinding& binding, size_t i, uint32_t component, const SurfelCloud& cloud,
                      uint8_t* value) {
  loadFieldValues(binding, component, cloud, i, 1, value, 0);
}

/// Binary records (PointCloud2 points, PCD binary rows): record j, at records + j * stride, holds surfel
/// first + j with field k at byte offsets[k] (host byte order). Moves whole vectors (x y z in a row) at once;
/// pass small blocks (the PointCloud2 converter: 16 records) so that a block stays in the cache while every
/// field is moved. loadRecords leaves kSkip fields as they are.
void storeRecords(const std::vector<FieldBinding>& bindings, const std::vector<uint32_t>& offsets,
                  const uint8_t* records, size_t stride, size_t first, size_t n, SurfelCloud* cloud);
void loadRecords(const std::vector<FieldBinding>& bindings, const std::vector<uint32_t>& offsets,
                 const SurfelCloud& cloud, size_t first, size_t n, uint8_t* records, size_t stride);

/// sensor_msgs/PointField datatype codes (INT8 = 1 .. FLOAT64 = 8, the order of ScalarType) and names.
inline uint8_t pointFieldDatatype(ScalarType type) {
  return static_cast<uint8_t>(static_cast<uint8_t>(type) + 1);
}
/// False for a code outside 1..8.
bool scalarTypeOfPointField(uint8_t datatype, ScalarType* type);
/// "INT8" .. "FLOAT64"
const char* pointFieldTypeName(ScalarType type);

}  // namespace rc
