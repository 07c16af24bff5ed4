#include "relaxed_connectivity/render/csg/patch_cloud_set.h"

#include <algorithm>

#include "relaxed_connectivity/core/surfel_attributes.h"

namespace rc {

PatchCloudSet::PatchCloudSet(const std::vector<PatchCloudInput>& inputs, const std::optional<CsgTree>& tree,
                             const std::string& frame_id, const CsgClipperOptions& options) {
  if (!inputs.empty()) cloud_ = mergePatchClouds(inputs, frame_id);
  if (!tree || cloud_.empty()) return;
  // Patches the tree does not name are not part of the CSG object.
  const std::vector<int> in_tree = tree->patches();
  const Attribute* ids = cloud_.attributes.find(kPatchIdAttribute);
  std::vector<size_t> keep;
  keep.reserve(cloud_.size());
  for (size_t i = 0; i < cloud_.size(); ++i)
    if (std::binary_search(in_tree.begin(), in_tree.end(), int(ids->get(i)))) keep.push_back(i);
  dropped_ = cloud_.size() - keep.size();
  if (dropped_ > 0) cloud_.select(keep);
  if (!cloud_.empty()) clipper_ = std::make_unique<CsgClipper>(cloud_, *tree, options);
}

}  // namespace rc
