// The two tile passes of the splat renderer (3.2.2) for unclipped splats without patch separation, eight
// pixels at a time with AVX2 where the CPU has it (runtime dispatch: the build itself stays SSE2-only). Same
// arithmetic per pixel and the same splat order as the four-wide SSE2 passes, so the images are bitwise
// identical whichever path runs.
#pragma once

#include <cstddef>
#include <cstdint>

#include "relaxed_connectivity/render/splat/ewa_splat.h"
#include "relaxed_connectivity/render/splat/splat_rasterizer.h"

namespace rc {
namespace splat_tile {

/// True if this build has the AVX2 passes and the CPU executes AVX2.
bool avx2TilePassesAvailable();

/// Pass 1 of one splat: bound = min(bound, z + eps_z), front = min(front, z) over its fragments (tile
/// buffers of kTileStride floats per row).
void visibilitySplatAvx2(const SplatRaster& s, const TileRect& tile, float* bound, float* front);

/// Attributes a splat blends into the pass-2 sums.
struct SplatBlend {
  float normal[3], color[3];
  int32_t patch_id;
};

/// The pass-2 sums of a tile; null members are not accumulated (the weight always is).
struct TileSums {
  float* weight;
  float* depth;
  float* normal[3];
  float* color[3];
  float* max_weight;  ///< with patch_id: the patch of the largest weight
  int32_t* patch_id;
};

/// Pass 2 of one splat: blends every fragment with z <= bound and z - eps_z <= front with the Gaussian weight
/// weight_table[round(r2 * table_steps)]; with nearer_filter >= 0 (SplatConfig::exact_silhouettes) one nearer
/// than the front by more than eps_z only where the splat's own footprint covers the pixel
/// (NearerFragmentTest). Returns the number of blended fragments.
size_t accumulateSplatAvx2(const SplatRaster& s, const TileRect& tile, const float* bound, const float* front,
                           const SplatBlend& blend, const float* weight_table, int table_steps,
                           const TileSums& sums, double nearer_filter);

}  // namespace splat_tile
}  // namespace rc
