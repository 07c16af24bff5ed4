#include "render/csg_clipper.h"

#include <algorithm>
#include <stdexcept>

#include "render/clip_inside_patch.h"

namespace rc {

CsgClipper::CsgClipper(const SurfelCloud& cloud, const CsgTree& tree, const CsgClipperOptions& options)
    : cloud_(cloud),
      tree_(tree.normalized()),
      options_(options),
      discs_(SurfelDiscs::fromCloud(cloud)),
      finder_(options.clip_buffer) {
  if (tree_.empty()) throw std::invalid_argument("CsgClipper: the CSG tree is empty");
  for (size_t i = 0; i < discs_.size(); ++i)
    if (tree_.leafOf(discs_.patches[i]) < 0)
      throw std::invalid_argument("CsgClipper: surfel " + std::to_string(i) + " has patch_id " +
                                  std::to_string(discs_.patches[i]) + ", which is not in the CSG tree \"" +
                                  tree_.toString() + "\"");
  inverted_.resize(discs_.size());
  for (size_t i = 0; i < discs_.size(); ++i)
    inverted_[i] = tree_.node(tree_.leafOf(discs_.patches[i])).inverted;
  classify();
}

void CsgClipper::classify() {
  discs_.updateGeometry(cloud_);
  finder_.findSpatial(discs_, &partners_, nullptr, &stats_);
  classes_ = classifySurfels(discs_, partners_, tree_);
  edge_surfels_.clear();
  for (uint32_t i = 0; i < discs_.size(); ++i)
    if (classes_[i] == SurfelClass::kEdge) edge_surfels_.push_back(i);
  refreshFlags();
}

void CsgClipper::update(const Camera& camera) {
  last_camera_ = camera;
  has_camera_ = true;
  discs_.updateGeometry(cloud_);
  finder_.find(options_.method, discs_, &camera, &partners_, &edge_surfels_, &stats_);
  refreshFlags();
}

void CsgClipper::prepare() {
  if (options_.method == PartnerMethod::kClipBuffer && has_camera_) {
    update(last_camera_);
    return;
  }
  discs_.updateGeometry(cloud_);
  finder_.findSpatial(discs_, &partners_, &edge_surfels_, &stats_);
  refreshFlags();
}

void CsgClipper::refreshFlags() {
  const size_t n = discs_.size();
  by_patch_ = partners_.ids;
  by_patch_patch_.resize(by_patch_.size());
  needs_clipping_.assign(n, 0);
  visible_.assign(n, 0);
  color_only_.assign(n, 0);
  for (uint32_t i = 0; i < n; ++i) {
    uint32_t* first = by_patch_.data() + partners_.offsets[i];
    uint32_t* last = by_patch_.data() + partners_.offsets[i + 1];
    std::sort(first, last, [&](uint32_t a, uint32_t b) {
      return discs_.patches[a] != discs_.patches[b] ? discs_.patches[a] < discs_.patches[b] : a < b;
    });
    bool all_texture = first != last;
    for (uint32_t* p = first; p != last; ++p) {
      by_patch_patch_[p - by_patch_.data()] = discs_.patches[*p];
      if (discs_.roles[*p] != SurfelRole::kTextureDiscontinuity) all_texture = false;
    }
    visible_[i] = discs_.roles[i] == SurfelRole::kSurface && classes_[i] != SurfelClass::kOutside;
    needs_clipping_[i] = visible_[i] && first != last;
    color_only_[i] = needs_clipping_[i] && all_texture;
  }
}

Tri CsgClipper::insidePatch(uint32_t surfel, int patch, const Vec3& x) const {
  const uint32_t begin = partners_.offsets[surfel], end = partners_.offsets[surfel + 1];
  uint32_t first = begin;
  while (first < end && by_patch_patch_[first] < patch) ++first;
  uint32_t last = first;
  while (last < end && by_patch_patch_[last] == patch) ++last;
  return insidePatchFromSurfels(x, by_patch_.data() + first, last - first, discs_.centers.data(),
                                discs_.normals.data());
}

Tri CsgClipper::insideTree(uint32_t surfel, int node, const Vec3& x) const {
  return tree_.insideTree(node, [&](int patch) { return insidePatch(surfel, patch, x); });
}

bool CsgClipper::keepFragment(uint32_t surfel, const Vec3& x) const {
  return tree_.fragmentOnSurface(discs_.patches[surfel],
                                 [&](int patch) { return insidePatch(surfel, patch, x); });
}

}  // namespace rc
