// Surfel patch clouds for CSG rendering (thesis 4.1): clouds checked for splatting and merged into one cloud
// with the int32 attributes "patch_id" and "surfel_role" that rc::CsgClipper reads (the csg_renderer node's
// inputs).
#pragma once

#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_attributes.h"
#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// Checks that `cloud` can be splatted: not empty, normals and radii (or tangent axes) present, every
/// position/normal/radius finite, normals non-zero, radii positive; with `require_patch_id` also a "patch_id"
/// attribute of non-negative integers; a "surfel_role" attribute must hold 0, 1 or 2. Throws
/// std::invalid_argument naming the channel and the problem (e.g. "no normals (fields normal_x, normal_y,
/// normal_z)", "3 of 100 surfels have non-finite positions").
void checkRenderableCloud(const SurfelCloud& cloud, bool require_patch_id);

/// One checked input cloud. patch_id >= 0 overrides the cloud's own "patch_id" attribute (patch topics);
/// -1 keeps the attribute (the `surfels` topic).
struct PatchCloudInput {
  const SurfelCloud* cloud = nullptr;
  int patch_id = -1;
};

/// Concatenates the inputs into one cloud: positions, unit normals, radii (an input's own radii when every
/// input has radii or it has no tangent axes; else the radius of the enclosing disc, max(|t1|, |t2|)), the
/// tangent axes when every input has them, colours when any input has them (`default_color` for the others),
/// and int32 columns "patch_id" and "surfel_role" (0 where an input has no role). Other attributes are
/// dropped. Throws std::invalid_argument for an input that fails checkRenderableCloud.
SurfelCloud mergePatchClouds(const std::vector<PatchCloudInput>& inputs, const std::string& frame_id,
                             const Rgba& default_color = {200, 200, 200, 255});

/// Sorted distinct values of the "patch_id" attribute (empty if absent).
std::vector<int> patchIds(const SurfelCloud& cloud);

}  // namespace rc
