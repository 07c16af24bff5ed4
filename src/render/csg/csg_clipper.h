// The FragmentClipper of "CSG with sharp edges from surfels" (thesis 4.2): decides per fragment whether a
// point on an edge surfel is on the surface of the CSG tree (Algorithm 4.2 with insideTree (4.3) and
// insidePatch (4.4) over the surfel's clipping partners), drops outside surfels and hides discontinuity
// surfels (4.3).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/csg/clip_classification.h"
#include "relaxed_connectivity/render/csg/clip_partners.h"
#include "relaxed_connectivity/render/csg/clip_surfel_discs.h"
#include "relaxed_connectivity/render/csg/csg_tree.h"
#include "relaxed_connectivity/render/splat/camera.h"
#include "relaxed_connectivity/render/splat/fragment_clipper.h"

namespace rc {

struct CsgClipperOptions {
  /// Per-frame partner search. The spatial index was faster in bench_clip_partners (see its output), so it
  /// is the default; both give identical partner sets.
  PartnerMethod method = PartnerMethod::kSpatialIndex;
  ClipBufferOptions clip_buffer;
  /// Compile each clipped surfel's test per frame into screen-space affine tests (compileClip, float, four
  /// pixels at a time) instead of evaluating Algorithms 4.2-4.4 in double per fragment (keepFragment).
  bool compiled_clipping = true;
};

class CsgClipper : public FragmentClipper {
 public:
  /// `cloud` (normals, radii or axes, int attribute "patch_id", optional "surfel_role") must outlive the
  /// clipper. The tree is normalised (4.3); every patch of the cloud must occur in it. Classifies the surfels
  /// (classify()). Throws std::invalid_argument naming the problem.
  CsgClipper(const SurfelCloud& cloud, const CsgTree& tree, const CsgClipperOptions& options = {});

  /// Re-reads the geometry and recomputes partners of ALL surfels (spatial index) and the surface / edge /
  /// outside classes (4.1.2). Use after surfels moved or changed.
  void classify();
  /// Per frame (4.2.1): re-reads the geometry and recomputes the partners of the edge surfels with the chosen
  /// method (clip buffer for `camera`, or spatial index). Call once before SurfelRenderer::render().
  void update(const Camera& camera);
  /// Same as update() with the camera of the last update() (the spatial method needs none; the clip buffer
  /// method without a previous update() falls back to the spatial index). Spatial partners depend on the
  /// geometry only: when the cloud's positions, normals, radii and axes are byte-identical to those of the
  /// last search, the partners are kept (a static scene searches once).
  void prepare() override;

  bool needsClipping(uint32_t surfel) const override { return needs_clipping_[surfel] != 0; }
  bool keepFragment(uint32_t surfel, const Vec3& x) const override;
  bool compileClip(uint32_t surfel, const ClipFrame& frame, ClipProgram* program) const override;
  bool isVisible(uint32_t surfel) const override { return visible_[surfel] != 0; }
  bool clipsColorOnly(uint32_t surfel) const override { return color_only_[surfel] != 0; }
  /// Surfels of complemented patches (isInverted()) are shaded with the reversed normal.
  bool flipsNormal(uint32_t surfel) const override { return inverted_[surfel] != 0; }
  bool flipsAnyNormal() const override {
    return std::any_of(inverted_.begin(), inverted_.end(), [](auto v) { return v != 0; });
  }

  /// Algorithm 4.4: x against `patch` from the partners of `surfel` in that patch (not inverted).
  Tri insidePatch(uint32_t surfel, int patch, const Vec3& x) const;
  /// Algorithm 4.3 from the partners of `surfel` on node `node` of tree().
  Tri insideTree(uint32_t surfel, int node, const Vec3& x) const;

  const CsgTree& tree() const { return tree_; }  ///< normalised
  const SurfelDiscs& discs() const { return discs_; }
  const ClipPartners& partners() const { return partners_; }
  SurfelClass surfelClass(uint32_t surfel) const { return classes_[surfel]; }
  const std::vector<SurfelClass>& surfelClasses() const { return classes_; }
  /// The edge surfels (partner candidates of update()).
  const std::vector<uint32_t>& edgeSurfels() const { return edge_surfels_; }
  /// True if the surfel's patch is complemented in the normalised tree (its rendered normal should point the
  /// other way: it bounds the complement).
  bool isInverted(uint32_t surfel) const { return inverted_[surfel] != 0; }
  const ClipPartnerStats& lastStats() const { return stats_; }
  const CsgClipperOptions& options() const { return options_; }

 private:
  void refreshFlags();
  bool geometryChanged() const;
  void snapshotGeometry();

  const SurfelCloud& cloud_;
  CsgTree tree_;
  CsgClipperOptions options_;
  SurfelDiscs discs_;
  ClipPartnerFinder finder_;
  ClipPartners partners_;
  std::vector<uint32_t> by_patch_;       // partner ids of each surfel, grouped by patch (partners_ offsets)
  std::vector<int32_t> by_patch_patch_;  // patch of each entry of by_patch_
  std::vector<SurfelClass> classes_;
  std::vector<uint32_t> edge_surfels_;
  std::vector<uint8_t> needs_clipping_, visible_, color_only_, inverted_;
  Camera last_camera_;
  bool has_camera_ = false;
  bool partners_current_ = false;  ///< partners_ are the spatial partners of the edge surfels of snapshot_
  SurfelCloud snapshot_;           ///< geometry channels at the last spatial search
  ClipPartnerStats stats_;
};

}  // namespace rc
