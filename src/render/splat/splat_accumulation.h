// The per-pixel state of the splatting renderer's two tile passes (3.2.2), kept for the whole image after a
// full render so that a differential update (thesis 5.7) can splat and un-splat surfels into it and normalise
// only the tiles it touched: the visibility bounds of pass 1 (which a partial update does not change) and the
// unnormalised weight-sums of pass 2. Tile-major, each sum of a tile in the renderer's tile buffer layout
// (kTileSize rows of kTileStride floats, pixel (x, y) of the tile at (x0, y0) at (y - y0) * kTileStride + x -
// x0).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/render/splat/splat_rasterizer.h"

namespace rc {

struct SplatAccumulation {
  enum Sum {
    kBound,
    kFront,
    kWeight,
    kDepth,
    kColor0,
    kColor1,
    kColor2,
    kNormal0,
    kNormal1,
    kNormal2,
    kSums
  };

  uint32_t width = 0, height = 0;
  int tiles_x = 0, tiles_y = 0;
  /// Sums the last full render accumulated (bounds, fronts and weights always): those its images need.
  bool has_depth = false, has_color = false, has_normal = false;

  /// Sizes the store for an image (contents undefined until a render fills them).
  void resize(uint32_t image_width, uint32_t image_height) {
    width = image_width;
    height = image_height;
    tiles_x = int((width + splat_tile::kTileSize - 1) / splat_tile::kTileSize);
    tiles_y = int((height + splat_tile::kTileSize - 1) / splat_tile::kTileSize);
    storage_.resize(size_t(tiles_x) * size_t(tiles_y) * kSums * splat_tile::kTileBufferSize);
  }
  int tiles() const { return tiles_x * tiles_y; }
  float* sum(int tile, Sum s) {
    return storage_.data() + (size_t(tile) * kSums + s) * splat_tile::kTileBufferSize;
  }
  const float* sum(int tile, Sum s) const {
    return storage_.data() + (size_t(tile) * kSums + s) * splat_tile::kTileBufferSize;
  }
  /// The pixel rectangle of a tile.
  splat_tile::TileRect rect(int tile) const {
    splat_tile::TileRect r;
    r.x0 = (tile % tiles_x) * splat_tile::kTileSize;
    r.y0 = (tile / tiles_x) * splat_tile::kTileSize;
    r.x1 = std::min(int(width), r.x0 + splat_tile::kTileSize) - 1;
    r.y1 = std::min(int(height), r.y0 + splat_tile::kTileSize) - 1;
    return r;
  }
  size_t bytes() const { return storage_.size() * sizeof(float); }

 private:
  std::vector<float> storage_;
};

}  // namespace rc
