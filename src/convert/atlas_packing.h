// Packing triangular texture patches into square power-of-two texture pages (thesis 6.3, Algorithm 6.1): rows
// of patches of similar height, each patch chosen by how well one of its base angles matches the free base
// angle left by the previous one, flipped horizontally to match and vertically every second time, and pushed
// as far left as its texels allow; then shorter patches fill the gaps and the end of the row, each at the
// leftmost place its texels fit. Patches are never resized or sheared: each keeps the size its texture
// error asked for (6.2.1). Collisions are tested on texels: a patch claims the texels its triangle touches
// plus a border (so bilinear filtering never reads a neighbour's texels), and no texel is claimed twice.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <vector>

namespace rc {

/// The triangle's base: k such that the edge from v[k] to v[(k + 1) % 3] is the longest (ties: the first);
/// v[(k + 2) % 3] is the apex. PatchShape::ofTriangle and the texture patches' frames both take it.
int longestEdge(const std::array<Eigen::Vector3d, 3>& v);

/// A triangle's texture patch in its own texel frame: the longest edge (the base) from (0, 0) to (base, 0),
/// the third vertex (the apex) at (apex_x, height), 0 <= apex_x <= base, height > 0 (texels).
struct PatchShape {
  double base = 0, apex_x = 0, height = 0;
  /// The patch of a triangle with these vertices (any order) at `texels_per_unit` texels per unit length.
  static PatchShape ofTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                               double texels_per_unit);
};

struct AtlasOptions {
  /// Texels kept around each triangle (claimed by it): 1 lets bilinear filtering stay inside the patch.
  int border = 1;
  /// Patches whose height is within this fraction of a row's height are candidates for the row (Delta h).
  double height_tolerance = 0.15;
  /// Page size (a power of two); 0: the smallest power of two that holds the patches on one page at 80 %
  /// usage, at most max_page_size (then several pages).
  int page_size = 0;
  int max_page_size = 4096;
  /// Mip levels assembled in the atlas' pattern (6.5): level k halves level k - 1, each texel the mean of the
  /// texels below it that belong to its patch, so no level blends two patches (buildTexturedMesh; 0: none).
  int mip_levels = 0;
  /// After a row's end is filled, its gaps (between its patches) take shorter patches too: more usage for
  /// more packing time (the patches alone, bench_conversion's models: Igea 84 -> 90 % claimed with borders,
  /// 0.04 -> 0.13 s; the 30k-triangle dragon 79 -> 89 %, 0.17 -> 2.95 s).
  bool fill_gaps = true;
};

struct PatchPlacement {
  int page = -1;
  /// The patch's base start, base end and apex on its page [texels; texel centres at i + 0.5].
  std::array<Eigen::Vector2d, 3> corners;
  bool flipped_horizontally = false, flipped_vertically = false;
};

struct AtlasLayout {
  int page_size = 0;
  int pages = 0;
  int last_page_height = 0;                ///< the last page is cropped to its used rows
  std::vector<PatchPlacement> placements;  ///< one per patch, in the input order
  /// Texture usage: the texels inside the triangles (their area) over the atlas area (all pages, the last one
  /// cropped to last_page_height); with_borders counts every texel the patches claim (triangles and borders).
  double usage = 0, usage_with_borders = 0;
};

/// Packs the patches (Algorithm 6.1). Throws std::invalid_argument for a malformed patch (non-finite, apex
/// outside the base, non-positive height or base), a non-power-of-two page_size, or a patch wider or taller
/// than the largest page.
AtlasLayout packPatches(const std::vector<PatchShape>& patches, const AtlasOptions& options = {});

/// The texels a patch claims in its own frame (the mask packPatches uses), row-major `width` x `height`; the
/// patch's base start sits at (origin, origin).
struct PatchMask {
  int width = 0, height = 0;
  double origin = 0;
  std::vector<unsigned char> texels;
};
PatchMask patchMask(const PatchShape& patch, int border);
/// The mask's margin around the triangle's bounding box (its base start sits at (origin, origin)).
double patchMaskOrigin(int border);

}  // namespace rc
