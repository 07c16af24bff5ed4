#include "relaxed_connectivity/render/csg/csg_clipper.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "relaxed_connectivity/render/csg/clip_inside_patch.h"

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
  partners_current_ = false;  // these are the partners of all surfels; prepare() restricts to edge surfels
  edge_surfels_.clear();
  for (uint32_t i = 0; i < discs_.size(); ++i)
    if (classes_[i] == SurfelClass::kEdge) edge_surfels_.push_back(i);
  refreshFlags();
}

void CsgClipper::update(const Camera& camera) {
  last_camera_ = camera;
  has_camera_ = true;
  if (options_.method == PartnerMethod::kSpatialIndex) {
    prepare();
    return;
  }
  discs_.updateGeometry(cloud_);
  finder_.find(options_.method, discs_, &camera, &partners_, &edge_surfels_, &stats_);
  refreshFlags();
  partners_current_ = false;
}

void CsgClipper::prepare() {
  if (options_.method == PartnerMethod::kClipBuffer && has_camera_) {
    update(last_camera_);
    return;
  }
  // Spatial partners depend on the geometry only: unchanged surfels keep the last frame's partners.
  if (partners_current_ && !geometryChanged()) return;
  discs_.updateGeometry(cloud_);
  finder_.findSpatial(discs_, &partners_, &edge_surfels_, &stats_);
  refreshFlags();
  snapshotGeometry();
  partners_current_ = true;
}

namespace {

template <class T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

}  // namespace

bool CsgClipper::geometryChanged() const {
  return !sameBytes(cloud_.positions, snapshot_.positions) || !sameBytes(cloud_.normals, snapshot_.normals) ||
         !sameBytes(cloud_.radii, snapshot_.radii) || !sameBytes(cloud_.axes1, snapshot_.axes1) ||
         !sameBytes(cloud_.axes2, snapshot_.axes2);
}

void CsgClipper::snapshotGeometry() {
  snapshot_.positions = cloud_.positions;
  snapshot_.normals = cloud_.normals;
  snapshot_.radii = cloud_.radii;
  snapshot_.axes1 = cloud_.axes1;
  snapshot_.axes2 = cloud_.axes2;
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

namespace {

/// Emits the postfix code of `node`'s inside test (Algorithm 4.3) with the patches without a group dropped
/// (they are `unknown` over the whole surfel: b AND/OR unknown = b, (4.9)/(4.10)). False if the whole
/// subtree is unknown (nothing emitted).
bool emitInsideTree(const CsgTree& tree, int node, const std::vector<std::pair<int, int>>& group_of_patch,
                    ClipProgram* program) {
  const CsgTree::Node& n = tree.node(node);
  if (n.op == CsgTree::Op::kLeaf) {
    for (const auto& [patch, group] : group_of_patch)
      if (patch == n.patch) {
        program->pushGroup(group, n.inverted);
        return true;
      }
    return false;
  }
  const bool left = emitInsideTree(tree, n.left, group_of_patch, program);
  const bool right = emitInsideTree(tree, n.right, group_of_patch, program);
  if (left && right) {
    if (n.op == CsgTree::Op::kIntersection) {
      program->pushAnd();
    } else {
      program->pushOr();
    }
  }
  return left || right;
}

}  // namespace

bool CsgClipper::compileClip(uint32_t surfel, const ClipFrame& frame, ClipProgram* program) const {
  if (!options_.compiled_clipping) return false;
  program->reset(frame);
  // One group per partner patch, in the order of by_patch_ (as insidePatch() sees them).
  std::vector<std::pair<int, int>> group_of_patch;  // (patch, group)
  const uint32_t begin = partners_.offsets[surfel], end = partners_.offsets[surfel + 1];
  for (uint32_t first = begin; first < end;) {
    uint32_t last = first;
    while (last < end && by_patch_patch_[last] == by_patch_patch_[first]) ++last;
    const int group = program->addGroup(by_patch_.data() + first, last - first, discs_.centers.data(),
                                        discs_.normals.data());
    if (group < 0) return false;
    group_of_patch.emplace_back(by_patch_patch_[first], group);
    first = last;
  }
  // Algorithm 4.2: walk up from the surfel's leaf; each level's sibling decides by (4.5) or (4.6).
  int a = tree_.leafOf(discs_.patches[surfel]);
  if (a < 0) return false;
  while (tree_.node(a).parent >= 0) {
    const CsgTree::Node& father = tree_.node(tree_.node(a).parent);
    const int sibling = father.left == a ? father.right : father.left;
    if (emitInsideTree(tree_, sibling, group_of_patch, program)) {
      if (father.op == CsgTree::Op::kIntersection) {
        program->levelIntersection();
      } else {
        program->levelUnion();
      }
    }
    a = tree_.node(a).parent;
  }
  return program->valid();
}

}  // namespace rc
