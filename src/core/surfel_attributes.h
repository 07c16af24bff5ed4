// Names and values of the per-surfel attributes that modules exchange: the CSG patch of a surfel (thesis 4.1)
// and its role (4.3). Scenes, shells and the ROS layer write them; the renderer reads them.
#pragma once

#include <cstdint>

namespace rc {

/// int32 attribute: the CSG patch a surfel belongs to (4.1); also the PointCloud2 field name.
constexpr const char* kPatchIdAttribute = "patch_id";
/// int32 attribute holding a SurfelRole value (4.3).
constexpr const char* kSurfelRoleAttribute = "surfel_role";

/// Values of the "surfel_role" attribute (4.3).
enum class SurfelRole : uint8_t {
  kSurface = 0,               ///< normal surfel
  kDiscontinuity = 1,         ///< invisible, clips geometry
  kTextureDiscontinuity = 2,  ///< invisible, clips colour only
};

/// The attribute value of a role.
constexpr int32_t surfelRoleValue(SurfelRole role) {
  return static_cast<int32_t>(role);
}

}  // namespace rc
