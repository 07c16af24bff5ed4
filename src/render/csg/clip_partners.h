// Clipping partners (thesis 4.2.1): for every surfel the set I_s of surfels of OTHER patches whose discs
// intersect it. Two methods that return identical sets:
//  - the clip buffer of Algorithm 4.1: surfels are splatted into a 2D grid of cells holding surfel lists for
//  a
//    camera; surfels of different patches sharing a cell are tested for a 3D disc-disc intersection;
//  - a spatial index: kd-tree range query with the sum of radii, then the same disc-disc test.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "relaxed_connectivity/render/csg/clip_surfel_discs.h"
#include "relaxed_connectivity/render/splat/camera.h"

namespace rc {

/// Partner lists in CSR form: the partners of surfel i are ids[offsets[i] .. offsets[i+1]), ascending.
struct ClipPartners {
  std::vector<uint32_t> offsets;  ///< size() + 1 entries
  std::vector<uint32_t> ids;

  size_t size() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  uint32_t count(uint32_t i) const { return offsets[i + 1] - offsets[i]; }
  const uint32_t* begin(uint32_t i) const { return ids.data() + offsets[i]; }
  const uint32_t* end(uint32_t i) const { return ids.data() + offsets[i + 1]; }
  size_t pairCount() const { return ids.size() / 2; }
  bool operator==(const ClipPartners& o) const { return offsets == o.offsets && ids == o.ids; }
};

enum class PartnerMethod { kClipBuffer, kSpatialIndex };

struct ClipBufferOptions {
  double cell_size_px = 1.0;     ///< cell edge in pixels (the thesis uses pixels, 1)
  double edge_on_cosine = 0.05;  ///< |n . view| below this: the splat is rasterised as a thick line (4.2.3)
};

struct ClipPartnerStats {
  size_t candidates = 0;    ///< surfels splatted / queried
  size_t cell_entries = 0;  ///< clip buffer: surfel entries written into cells
  size_t edge_on = 0;       ///< clip buffer: surfels rasterised as thick lines
  size_t tested_pairs = 0;  ///< pairs that reached the disc-disc test (each direction counted)
  size_t pairs = 0;         ///< partner pairs found
};

/// Finds clipping partners. Keeps its work buffers between calls (per-frame use does not reallocate once the
/// buffers have grown). Not thread-safe itself; the work inside a call is multi-threaded (OpenMP).
class ClipPartnerFinder {
 public:
  explicit ClipPartnerFinder(const ClipBufferOptions& options = {});
  ~ClipPartnerFinder();

  /// Clip buffer (Algorithm 4.1) for `camera`. Each candidate is rasterised conservatively: its disc lies in
  /// the rectangle c +- r u +- r v (r the bounding radius), whose projection is a convex quad; every cell the
  /// quad touches receives the surfel. Surfels seen edge-on become thick lines (the quad dilated by half a
  /// cell), surfels crossing the near plane are tested against all candidates, and off-screen extents are
  /// clamped to the border cells (clamping keeps overlapping extents overlapping), so no intersecting pair is
  /// ever missed. `candidates`: surfels to consider (e.g. the edge surfels); nullptr: all.
  void findClipBuffer(const SurfelDiscs& discs, const Camera& camera, ClipPartners* out,
                      const std::vector<uint32_t>* candidates = nullptr, ClipPartnerStats* stats = nullptr);

  /// kd-tree range query with radius r_s + r_max, filtered by ||c1 - c2|| < r1 + r2 and the disc-disc test.
  void findSpatial(const SurfelDiscs& discs, ClipPartners* out,
                   const std::vector<uint32_t>* candidates = nullptr, ClipPartnerStats* stats = nullptr);

  void find(PartnerMethod method, const SurfelDiscs& discs, const Camera* camera, ClipPartners* out,
            const std::vector<uint32_t>* candidates = nullptr, ClipPartnerStats* stats = nullptr);

  const ClipBufferOptions& options() const { return options_; }

 private:
  struct Work;
  ClipBufferOptions options_;
  std::unique_ptr<Work> work_;
};

}  // namespace rc
