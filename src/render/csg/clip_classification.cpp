#include "relaxed_connectivity/render/csg/clip_classification.h"

#include <algorithm>
#include <memory>
#include <stdexcept>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/render/csg/clip_inside_patch.h"

namespace rc {

std::vector<SurfelClass> classifySurfels(const SurfelDiscs& discs, const ClipPartners& partners,
                                         const CsgTree& tree) {
  if (!tree.isNormalized()) throw std::invalid_argument("classifySurfels: the CSG tree is not normalised");
  if (partners.size() != discs.size())
    throw std::invalid_argument("classifySurfels: partner lists for " + std::to_string(partners.size()) +
                                " surfels, cloud has " + std::to_string(discs.size()));
  const std::vector<int> patch_ids = tree.patches();
  const size_t patch_count = patch_ids.size();
  auto dense = [&](int patch) {
    return static_cast<size_t>(std::lower_bound(patch_ids.begin(), patch_ids.end(), patch) -
                               patch_ids.begin());
  };
  // Per patch: its surfels (global ids), their centres and a kd-tree; texture-only flag.
  std::vector<std::vector<uint32_t>> members(patch_count);
  std::vector<std::vector<Vec3>> points(patch_count);
  std::vector<char> texture_only(patch_count, 1);
  for (uint32_t i = 0; i < discs.size(); ++i) {
    const int patch = discs.patches[i];
    const size_t d = dense(patch);
    if (d == patch_count || patch_ids[d] != patch)
      throw std::invalid_argument("classifySurfels: surfel " + std::to_string(i) + " has patch_id " +
                                  std::to_string(patch) + ", which is not in the CSG tree \"" +
                                  tree.toString() + "\"");
    members[d].push_back(i);
    points[d].push_back(discs.centers[i]);
    if (discs.roles[i] != SurfelRole::kTextureDiscontinuity) texture_only[d] = 0;
  }
  std::vector<std::unique_ptr<KdTree>> trees(patch_count);
  for (size_t d = 0; d < patch_count; ++d)
    if (!points[d].empty()) trees[d].reset(new KdTree(points[d]));

  std::vector<SurfelClass> classes(discs.size());
  const int64_t n = static_cast<int64_t>(discs.size());
  constexpr size_t kMaxVaryingPatches = 12;
#pragma omp parallel
  {
    std::vector<Tri> global(patch_count);
    std::vector<char> known(patch_count);
#pragma omp for schedule(dynamic, 256)
    for (int64_t i = 0; i < n; ++i) {
      const uint32_t s = static_cast<uint32_t>(i);
      const Vec3& x = discs.centers[i];
      // Patches the disc intersects (its partners' patches) vary over the disc; all others are constant on
      // it.
      int varying[kMaxVaryingPatches];
      size_t k = 0;
      bool too_many = false;
      for (const uint32_t* p = partners.begin(s); p != partners.end(s); ++p) {
        const int patch = discs.patches[*p];
        if (std::find(varying, varying + k, patch) != varying + k) continue;
        if (k == kMaxVaryingPatches) {
          too_many = true;
          break;
        }
        varying[k++] = patch;
      }
      if (too_many) {
        classes[i] = SurfelClass::kEdge;
        continue;
      }
      std::fill(known.begin(), known.end(), 0);
      auto global_inside = [&](int patch) -> Tri {
        const size_t d = dense(patch);
        if (!known[d]) {
          known[d] = 1;
          global[d] = Tri::kUnknown;
          if (!texture_only[d] && trees[d]) {
            Neighbor nearest[2];
            const size_t found = trees[d]->knn(x, 2, nearest);
            uint32_t ids[2];
            for (size_t j = 0; j < found; ++j) ids[j] = members[d][nearest[j].index];
            global[d] = insidePatchFromSurfels(x, ids, found, discs.centers.data(), discs.normals.data());
          }
        }
        return global[d];
      };
      // Outside iff Algorithm 4.2 discards the surfel for every in/out assignment of the varying patches.
      bool on_somewhere = false;
      for (uint32_t mask = 0; mask < (1u << k) && !on_somewhere; ++mask) {
        auto inside_patch = [&](int patch) -> Tri {
          for (size_t j = 0; j < k; ++j)
            if (varying[j] == patch) return toTri((mask >> j) & 1u);
          return global_inside(patch);
        };
        on_somewhere = tree.fragmentOnSurface(discs.patches[i], inside_patch);
      }
      classes[i] =
          !on_somewhere ? SurfelClass::kOutside : (k > 0 ? SurfelClass::kEdge : SurfelClass::kSurface);
    }
  }
  return classes;
}

}  // namespace rc
