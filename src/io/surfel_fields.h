// Maps named scalar fields (PLY vertex properties, PCD fields) onto SurfelCloud channels and back. Fields
// that name no channel become attribute columns (raw bytes, so they survive a round trip bit-exactly).
#pragma once

#include <string>
#include <vector>

#include "core/surfel_cloud.h"

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
  kSkip,  ///< padding ("_")
};

struct FieldBinding {
  FieldTarget target = FieldTarget::kSkip;
  uint8_t axis = 0;  ///< vector component (0..2) or colour byte (r g b a = 0..3)
  ScalarType type = ScalarType::kFloat32;
  uint32_t count = 1;
  size_t attribute = 0;  ///< column index in cloud.attributes for kAttribute
};

/// Field names differ between formats: PLY uses nx/red/green/blue/alpha, PCD normal_x/rgba (packed).
enum class FieldNaming { kPly, kPcd };

/// Binds `fields` (in order) to channels of `cloud`, which is resized to n surfels with every bound channel
/// allocated. Throws IoError(file, where, ...) on duplicate field names. Returns whether x, y, z were found.
bool bindFields(const std::vector<FieldSpec>& fields, size_t n, const std::string& file,
                const std::string& where, SurfelCloud* cloud, std::vector<FieldBinding>* bindings);

/// Stores value `component` of surfel i; `value` holds one scalar of binding.type in host byte order.
void storeField(const FieldBinding& binding, size_t i, uint32_t component, const uint8_t* value,
                SurfelCloud* cloud);

/// The fields (with bindings) that write every present channel and attribute of `cloud`. Throws IoError if an
/// attribute name collides with a channel field or contains blanks.
void describeCloudFields(const SurfelCloud& cloud, FieldNaming naming, bool double_precision,
                         const std::string& file, std::vector<FieldSpec>* fields,
                         std::vector<FieldBinding>* bindings);

/// Loads value `component` of surfel i into `value` (binding.type, host byte order).
void loadField(const FieldBinding& binding, size_t i, uint32_t component, const SurfelCloud& cloud,
               uint8_t* value);

}  // namespace rc
