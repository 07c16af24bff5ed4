// The surfel patches of one CSG frame (thesis 4.1-4.3): per-source patch clouds merged into one cloud with
// patch ids and roles, restricted to the patches the CSG tree names, and the clipper built on that cloud. The
// csg_renderer node builds one per input change (aside, so the last good set stays when a build fails); the
// paint model's per-patch deltas will arrive as sources too.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/csg/csg_clipper.h"
#include "relaxed_connectivity/render/csg/csg_tree.h"
#include "relaxed_connectivity/render/csg/patch_clouds.h"

namespace rc {

class PatchCloudSet {
 public:
  /// Merges the inputs (mergePatchClouds); with a tree keeps only the surfels of the patches it names and
  /// builds a CsgClipper on them (none without a tree or when nothing is left). Throws std::invalid_argument
  /// for an input that fails checkRenderableCloud and what CsgClipper throws.
  PatchCloudSet(const std::vector<PatchCloudInput>& inputs, const std::optional<CsgTree>& tree,
                const std::string& frame_id, const CsgClipperOptions& options = {});
  PatchCloudSet(const PatchCloudSet&) = delete;  // the clipper refers to the cloud
  PatchCloudSet& operator=(const PatchCloudSet&) = delete;

  /// The merged (and, with a tree, filtered) surfels with int32 "patch_id" and "surfel_role" columns.
  const SurfelCloud& cloud() const { return cloud_; }
  /// The clipper of the tree on cloud(); null without a tree or for an empty cloud.
  CsgClipper* clipper() { return clipper_.get(); }
  const CsgClipper* clipper() const { return clipper_.get(); }
  /// Surfels of the merged inputs that the tree does not name (not part of the CSG object).
  size_t droppedSurfels() const { return dropped_; }

 private:
  SurfelCloud cloud_;
  std::unique_ptr<CsgClipper> clipper_;
  size_t dropped_ = 0;
};

}  // namespace rc
