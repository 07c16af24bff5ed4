// Scratch memory of the splatting renderer, kept between frames so that a frame allocates (and touches
// fresh pages) only when the scene or the image grows.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <type_traits>
#include <vector>

#include "relaxed_connectivity/render/csg/clip_program.h"
#include "relaxed_connectivity/render/splat/ewa_splat.h"

namespace rc {

/// Array of trivially copyable T that grows but never shrinks, and never initialises its elements.
template <class T>
class ScratchBuffer {
  static_assert(std::is_trivially_copyable<T>::value && std::is_trivially_destructible<T>::value,
                "ScratchBuffer holds plain data only");

 public:
  /// Makes room for n elements; the contents are undefined afterwards.
  void reserve(size_t n) {
    if (n <= capacity_) return;
    data_.reset();  // free first: the old contents are not kept
    data_.reset(new T[n]);
    capacity_ = n;
  }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  T& operator[](size_t i) { return data_[i]; }
  const T& operator[](size_t i) const { return data_[i]; }

 private:
  std::unique_ptr<T[]> data_;
  size_t capacity_ = 0;
};

/// Per-splat attributes blended by the accumulation pass (beside the SplatRaster of the same index).
struct alignas(32) SplatShading {
  float normal[3];  ///< unit normal, world frame
  Rgba color;
  int32_t patch_id;
};

/// Per-frame buffers of SurfelRenderer::render().
struct SplatWorkspace {
  ScratchBuffer<SplatRaster> staged;  ///< set-up output, chunk c compacted at the start of its surfel range
  ScratchBuffer<SplatShading> staged_shading;  ///< same layout as `staged`
  ScratchBuffer<uint32_t> bin_items;    ///< indices into `staged` sorted by tile (surfel order within a tile)
  ScratchBuffer<uint32_t> clip_staged;  ///< surfels needing clipping, chunk-compacted like `staged`
  std::vector<uint32_t> chunk_tile_counts;  ///< [chunk * tiles + tile], then the write cursors
  std::vector<uint32_t> tile_offsets;       ///< tile t holds bin_items[tile_offsets[t], tile_offsets[t + 1])
  std::vector<uint32_t> clip_surfels;       ///< surfel of each clip slot
  std::vector<SplatGeometry> clip_geometry;
  std::vector<ClipProgram> clip_programs;  ///< per clip slot (grows only: keeps each program's memory)
  std::vector<uint8_t> clip_compiled;      ///< 1: clip_programs[slot] holds this frame's compiled test
};

/// A workspace owned by a renderer: copies of the renderer get their own, concurrent render() calls on one
/// renderer use it one at a time (the others fall back to a temporary workspace).
class SplatWorkspaceSlot {
 public:
  SplatWorkspaceSlot() = default;
  SplatWorkspaceSlot(const SplatWorkspaceSlot&) {}
  SplatWorkspaceSlot& operator=(const SplatWorkspaceSlot&) { return *this; }

  std::mutex mutex;
  SplatWorkspace workspace;
};

}  // namespace rc
