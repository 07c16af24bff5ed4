#include "relaxed_connectivity/render/splat/surfel_renderer.h"

#include <omp.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/core/surfel_attributes.h"
#include "relaxed_connectivity/render/splat/circular_setup_avx2.h"
#include "relaxed_connectivity/render/splat/deferred_shader.h"
#include "relaxed_connectivity/render/splat/environment_map.h"
#include "relaxed_connectivity/render/splat/ewa_splat.h"
#include "relaxed_connectivity/render/splat/splat_rasterizer.h"
#include "relaxed_connectivity/render/splat/tile_passes_avx2.h"

namespace rc {

namespace {

using namespace splat_tile;
constexpr size_t kSurfelsPerChunk = 4096;  ///< set-up/binning work unit (at most 8 per thread)
#if defined(__SSE2__)
constexpr bool kSimd = true;  ///< unclipped splats are rasterized four pixels at a time
#else
constexpr bool kSimd = false;
#endif

using Clock = std::chrono::steady_clock;
double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

constexpr int kBlockSize = 8;  ///< occlusion culling granularity inside a tile
constexpr int kBlocksPerTile = kTileSize / kBlockSize;
/// Pass 1 tests splats with a box of at least this many pixels against the block bounds so far.
constexpr int kOcclusionTestArea = 256;
/// Tiles with at most this many splats (large splats: few per tile) are drawn front to back.
constexpr uint32_t kSortMaxSplats = 64;

/// The pass-2 sums a frame needs (besides the weight): the requested images decide.
struct AccumulatedSums {
  bool color_weight, depth, color, normal, patch;
};

/// Tile-local buffers of the two passes (structure of arrays), pixel (x, y) of the tile at (x0, y0) at
/// (y - y0) * kTileStride + x - x0.
struct TileBuffers {
  alignas(16) float bound[kTileBufferSize];            ///< pass 1: smallest z + eps_z
  alignas(16) float front[kTileBufferSize];            ///< pass 1: smallest z
  alignas(16) int32_t front_patch[kTileBufferSize];    ///< pass 1: patch of the fragment at the smallest z
  alignas(16) float front_normal[3][kTileBufferSize];  ///< pass 1: its unit normal (shading normal)
  alignas(16) float weight[kTileBufferSize];
  alignas(16) float color_weight[kTileBufferSize];
  alignas(16) float depth[kTileBufferSize];
  alignas(16) float color[3][kTileBufferSize];
  alignas(16) float normal[3][kTileBufferSize];
  alignas(16) float max_weight[kTileBufferSize];
  alignas(16) int32_t patch_id[kTileBufferSize];

  /// Pass 1 state. front_patch / front_normal are read only where front was written.
  void clearVisibility() {
    fillInfinity(bound);
    fillInfinity(front);
  }
  /// Pass 2 sums (those the frame accumulates). patch_id is read only where a fragment with positive
  /// weight wrote it.
  void clearAccumulation(const AccumulatedSums& sums) {
    auto clear = [](float* buffer) { std::memset(buffer, 0, sizeof(float) * kTileBufferSize); };
    clear(weight);
    if (sums.color_weight) clear(color_weight);
    if (sums.depth) clear(depth);
    if (sums.color) std::memset(color, 0, sizeof(color));
    if (sums.normal) std::memset(normal, 0, sizeof(normal));
    if (sums.patch) clear(max_weight);
  }

 private:
  static void fillInfinity(float* buffer) {
    constexpr float kInfinity = std::numeric_limits<float>::infinity();
    for (int i = 0; i < kTileBufferSize; ++i) buffer[i] = kInfinity;
  }
};

struct ChunkCounts {
  size_t begin, end;  ///< surfel range
  uint32_t drawn = 0, edge_on = 0, invalid = 0, culled = 0, clipped = 0;
  uint32_t clip_offset = 0;  ///< first clip slot of this chunk
};

/// With CSG clipping, a fragment of another patch than the pixel's front fragment blends only if its normal
/// is within acos(kCrossPatchBlendCosine) (about 25 deg) of the front normal: patches meet at sharp edges or
/// lie behind each other (a face behind a silhouette), but texture patches of one sheet (4.3) still blend.
constexpr float kCrossPatchBlendCosine = 0.9f;

#if defined(__SSE2__)
/// All-ones lanes for the set bits of a 4-bit mask.
inline __m128 laneMask(int bits) {
  const __m128i lane_bits = _mm_setr_epi32(1, 2, 4, 8);
  return _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(_mm_set1_epi32(bits), lane_bits), lane_bits));
}

/// Of the lanes `candidates`, those where the front fragment has the same patch or a normal within
/// acos(kCrossPatchBlendCosine) (the normals are read only where the patches differ).
inline __m128 blendsWithFront(__m128 candidates, __m128 patch, const float normal[3], const TileBuffers& tb,
                              int i) {
  const __m128i front = _mm_loadu_si128(reinterpret_cast<const __m128i*>(tb.front_patch + i));
  const __m128 same = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_castps_si128(patch), front));
  if (!(_mm_movemask_ps(_mm_andnot_ps(same, candidates)))) return candidates;
  const __m128 cosine =
      _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(normal[0]), _mm_loadu_ps(tb.front_normal[0] + i)),
                            _mm_mul_ps(_mm_set1_ps(normal[1]), _mm_loadu_ps(tb.front_normal[1] + i))),
                 _mm_mul_ps(_mm_set1_ps(normal[2]), _mm_loadu_ps(tb.front_normal[2] + i)));
  return _mm_and_ps(candidates, _mm_or_ps(same, _mm_cmpge_ps(cosine, _mm_set1_ps(kCrossPatchBlendCosine))));
}
#endif

/// Records read ahead in the tile passes (bins index the set-up records, which lie in surfel order).
constexpr uint32_t kPrefetchDistance = 16;

/// Set bits of a 4-bit lane mask.
constexpr uint8_t kBitCount[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};

template <class Visit>
inline void forEachTileOfSplat(const SplatRaster& s, int tiles_x, Visit&& visit) {
  const int tx0 = s.x0 / kTileSize, tx1 = s.x1 / kTileSize;
  for (int ty = s.y0 / kTileSize, ty1 = s.y1 / kTileSize; ty <= ty1; ++ty)
    for (int tx = tx0; tx <= tx1; ++tx) visit(ty * tiles_x + tx);
}

void validateConfig(const SplatConfig& config) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("SplatConfig: " + what); };
  if (!(config.lowpass_variance > 0) || !std::isfinite(config.lowpass_variance))
    fail("lowpass_variance must be positive");
  if (!(config.cutoff_radius > 0) || !std::isfinite(config.cutoff_radius))
    fail("cutoff_radius must be positive");
  if (!(config.depth_tolerance_scale >= 0) || !std::isfinite(config.depth_tolerance_scale))
    fail("depth_tolerance_scale must be non-negative");
  if (config.threads < 0) fail("threads must be >= 0");
  if (config.outputs & ~uint32_t(kOutputAll)) fail("outputs has unknown RenderOutput bits");
  if (!(config.light_direction_camera.norm() > 0)) fail("light_direction_camera must be non-zero");
}

/// Throws std::invalid_argument for what render() cannot draw.
void checkRenderInputs(const SplatConfig& config, const SurfelCloud& cloud, const Camera& camera,
                       const RenderImages* out, const FragmentClipper* clipper) {
  if (!out) throw std::invalid_argument("SurfelRenderer::render: output images are null");
  validateConfig(config);
  camera.validate();
  cloud.validate();
  if (!cloud.hasAxes() && !cloud.hasNormals())
    throw std::invalid_argument("SurfelRenderer::render: cloud has neither normals nor tangent axes");
  if (!cloud.hasAxes() && !cloud.hasRadii())
    throw std::invalid_argument("SurfelRenderer::render: cloud has neither radii nor tangent axes");
  if (camera.width > SplatRaster::kMaxImageSize || camera.height > SplatRaster::kMaxImageSize)
    throw std::invalid_argument("SurfelRenderer::render: image " + std::to_string(camera.width) + "x" +
                                std::to_string(camera.height) + " is larger than " +
                                std::to_string(SplatRaster::kMaxImageSize) + " pixels on a side");
  if (clipper && cloud.size() > SplatRaster::kClipSlotMask)
    throw std::invalid_argument("SurfelRenderer::render: too many surfels for clipping (" +
                                std::to_string(cloud.size()) + ")");
}

/// Per-frame state of SurfelRenderer::render(), shared by its phases.
struct RenderFrameState {
  RenderFrameState(const SplatConfig& config, const SurfelCloud& cloud, const Camera& camera,
                   const FragmentClipper* clipper, SplatWorkspace& ws)
      : config(config),
        cloud(cloud),
        clipper(clipper),
        ws(ws),
        threads(config.threads > 0 ? config.threads : omp_get_max_threads()),
        frame(camera),
        width(int(camera.width)),
        height(int(camera.height)),
        pixels(size_t(width) * height),
        tiles_x((width + kTileSize - 1) / kTileSize),
        tiles_y((height + kTileSize - 1) / kTileSize),
        tiles(tiles_x * tiles_y) {
    params.ewa_filter = config.ewa_filter;
    params.lowpass_variance = config.lowpass_variance;
    params.cutoff_radius = config.cutoff_radius;
    params.depth_tolerance_scale = config.depth_tolerance_scale;
    params.backface_culling = config.backface_culling;
    params.exact_footprint = config.exact_footprint;
  }

  const SplatConfig& config;
  const SurfelCloud& cloud;
  const FragmentClipper* clipper;
  SplatWorkspace& ws;
  const int threads;
  const CameraFrame frame;
  EwaParams params;
  const int width, height;
  const size_t pixels;
  const int tiles_x, tiles_y, tiles;
  std::vector<ChunkCounts> chunk_counts;  ///< set-up work units
  RenderStats stats;
};

/// Set-up of the surfels of one chunk into its compacted records, with the chunk's tile counts.
ChunkCounts setupChunk(RenderFrameState& f, size_t chunk, bool circular, bool wide_setup,
                       const Attribute* patch_attribute) {
  SplatWorkspace& ws = f.ws;
  const SurfelCloud& cloud = f.cloud;
  const FragmentClipper* clipper = f.clipper;
  ChunkCounts counts = f.chunk_counts[chunk];  // local copy: no false sharing between threads
  SplatRaster* staged = ws.staged.data() + counts.begin;
  SplatShading* staged_shading = ws.staged_shading.data() + counts.begin;
  uint32_t* clip_staged = clipper ? ws.clip_staged.data() + counts.begin : nullptr;
  uint32_t* tile_counts = ws.chunk_tile_counts.data() + chunk * size_t(f.tiles);
  const Attribute* reflectivity =
      f.config.environment ? cloud.attributes.find(kReflectivityAttribute) : nullptr;
  // Records the set-up of surfel i, whose record and normal are in staged[counts.drawn].
  auto account = [&](size_t i, SplatSetup result) {
    if (result == SplatSetup::kInvalid) {
      ++counts.invalid;
      return;
    }
    if (result == SplatSetup::kCulled) {
      ++counts.culled;
      return;
    }
    SplatRaster& raster = staged[counts.drawn];
    SplatShading& shading = staged_shading[counts.drawn];
    counts.edge_on += result == SplatSetup::kDrawnEdgeOn;
    shading.color = cloud.hasColors() ? cloud.colors[i] : f.config.default_color;
    if (reflectivity)  // (5.7) per surfel, seen from this camera
      shading.color = reflectedColor(shading.color, reflectivity->get(i), cloud.positions[i],
                                     Vec3(shading.normal[0], shading.normal[1], shading.normal[2]),
                                     f.frame.eye, *f.config.environment);
    shading.patch_id = patch_attribute ? int32_t(patch_attribute->get(i)) : 0;
    if (clipper && clipper->needsClipping(uint32_t(i))) {
      raster.flags |= clipper->clipsColorOnly(uint32_t(i)) ? SplatRaster::kClipColorOnly : SplatRaster::kClip;
      raster.flags |= counts.clipped;  // clip slot, chunk-local until binned
      clip_staged[counts.clipped++] = uint32_t(i);
    }
    forEachTileOfSplat(raster, f.tiles_x, [&](int tile) { ++tile_counts[tile]; });
    ++counts.drawn;
  };
  size_t first = counts.begin;
  if (wide_setup) {  // four circular surfels at a time (bitwise the scalar set-up), culled ones first
    constexpr size_t kBlock = 1024;
    uint32_t kept[kBlock];
    for (size_t block = counts.begin; block < counts.end; block += kBlock) {
      const size_t size = std::min(kBlock, counts.end - block);
      const size_t n = unculledCircularSurfels(&cloud.positions[block], &cloud.normals[block],
                                               &cloud.radii[block], size, f.frame, f.params, kept);
      counts.culled += uint32_t(size - n);
      size_t j = 0;
      for (; j + 4 <= n; j += 4) {
        Vec3 centers[4], normals[4];
        double radii[4];
        for (int k = 0; k < 4; ++k) {
          const size_t i = block + kept[j + k];
          centers[k] = cloud.positions[i], normals[k] = cloud.normals[i], radii[k] = cloud.radii[i];
        }
        SplatRaster rasters[4];
        float unit_normals[4][3];
        SplatSetup results[4];
        setupCircularEwaSplats4(centers, normals, radii, f.frame, f.params, rasters, unit_normals, results);
        for (int k = 0; k < 4; ++k) {
          if (results[k] == SplatSetup::kDrawn || results[k] == SplatSetup::kDrawnEdgeOn) {
            staged[counts.drawn] = rasters[k];
            std::copy_n(unit_normals[k], 3, staged_shading[counts.drawn].normal);
          }
          account(block + kept[j + k], results[k]);
        }
      }
      for (; j < n; ++j) {  // the last few: the scalar set-up
        const size_t i = block + kept[j];
        account(i,
                setupCircularEwaSplat(cloud.positions[i], cloud.normals[i], cloud.radii[i], f.frame, f.params,
                                      &staged[counts.drawn], staged_shading[counts.drawn].normal));
      }
    }
    first = counts.end;
  }
  for (size_t i = first; i < counts.end; ++i) {
    if (clipper && !clipper->isVisible(uint32_t(i))) {
      ++counts.culled;
      continue;
    }
    SplatRaster& raster = staged[counts.drawn];
    SplatShading& shading = staged_shading[counts.drawn];
    // Cavity walls of complemented patches face the other way (4.2): shading and back-face culling use
    // the reversed normal (the footprint does not depend on its sign).
    const double orientation = clipper && clipper->flipsNormal(uint32_t(i)) ? -1.0 : 1.0;
    SplatSetup result;
    if (circular) {
      result = setupCircularEwaSplat(cloud.positions[i], orientation * cloud.normals[i], cloud.radii[i],
                                     f.frame, f.params, &raster, shading.normal);
    } else {
      Vec3 normal, axis1, axis2;
      surfelFrame(cloud, i, &normal, &axis1, &axis2);
      normal *= orientation;
      result = setupEwaSplat(cloud.positions[i], normal, axis1, axis2, f.frame, f.params, &raster, nullptr);
      const Vec3 unit_normal = normal.normalized();
      for (int k = 0; k < 3; ++k) shading.normal[k] = float(unit_normal[k]);
    }
    account(i, result);
  }
  return counts;
}

/// Set-up: per-surfel screen-space ellipse (double), stored as float raster records, compacted per chunk of
/// surfels, with per-chunk tile counts. Returns the number of surfels whose fragments are clipped.
uint32_t setupSplats(RenderFrameState& f) {
  SplatWorkspace& ws = f.ws;
  const size_t n = f.cloud.size();
  const size_t chunks =
      n == 0 ? 0 : std::min((n + kSurfelsPerChunk - 1) / kSurfelsPerChunk, size_t(8) * size_t(f.threads));
  f.chunk_counts.resize(chunks);
  for (size_t chunk = 0; chunk < chunks; ++chunk) {
    f.chunk_counts[chunk].begin = n * chunk / chunks;
    f.chunk_counts[chunk].end = n * (chunk + 1) / chunks;
  }
  ws.staged.reserve(n);
  ws.staged_shading.reserve(n);
  if (f.clipper) ws.clip_staged.reserve(n);
  ws.chunk_tile_counts.assign(chunks * size_t(f.tiles), 0);
  const bool circular = !f.cloud.hasAxes();
  const bool wide_setup =
      circular && !f.clipper && f.frame.perspective && f.config.wide_simd && circularSetupAvx2Available();
  const Attribute* patch_attribute = f.cloud.attributes.find(kPatchIdAttribute);

#pragma omp parallel for num_threads(f.threads) schedule(dynamic, 1)
  for (size_t chunk = 0; chunk < chunks; ++chunk)
    f.chunk_counts[chunk] = setupChunk(f, chunk, circular, wide_setup, patch_attribute);

  f.stats.surfels = n;
  uint32_t clip_count = 0;
  for (ChunkCounts& counts : f.chunk_counts) {
    f.stats.splats += counts.drawn;
    f.stats.edge_on_surfels += counts.edge_on;
    f.stats.invalid_surfels += counts.invalid;
    f.stats.culled_surfels += counts.culled;
    counts.clip_offset = clip_count;
    clip_count += counts.clipped;
  }
  return clip_count;
}

/// Surfels whose fragments are clipped keep their double-precision geometry (4.2.2) and, where the clipper
/// can, a per-frame compiled fragment test (clip_program.h).
void setupClipSurfels(RenderFrameState& f, uint32_t clip_count) {
  SplatWorkspace& ws = f.ws;
  ws.clip_surfels.resize(clip_count);
  for (const ChunkCounts& counts : f.chunk_counts)
    std::copy_n(ws.clip_staged.data() + counts.begin, counts.clipped,
                ws.clip_surfels.data() + counts.clip_offset);
  ws.clip_geometry.resize(clip_count);
  if (ws.clip_programs.size() < clip_count) ws.clip_programs.resize(clip_count);
  ws.clip_compiled.assign(clip_count, 0);
#pragma omp parallel for num_threads(f.threads) schedule(dynamic, 64)
  for (size_t k = 0; k < clip_count; ++k) {
    const size_t i = ws.clip_surfels[k];
    Vec3 normal, axis1, axis2;
    surfelFrame(f.cloud, i, &normal, &axis1, &axis2);
    SplatRaster box;
    setupEwaSplat(f.cloud.positions[i], normal, axis1, axis2, f.frame, f.params, &box, &ws.clip_geometry[k]);
    ClipFrame clip_frame;  // over the box widened by a pixel (the drawn record may round differently)
    if (makeClipFrame(ws.clip_geometry[k], f.frame, int(box.x0) - 1, int(box.y0) - 1, int(box.x1) + 1,
                      int(box.y1) + 1, &clip_frame))
      ws.clip_compiled[k] = f.clipper->compileClip(uint32_t(i), clip_frame, &ws.clip_programs[k]);
  }
  for (uint8_t compiled : ws.clip_compiled) f.stats.compiled_clip_surfels += compiled;
}

/// Binning: record indices sorted by tile; chunk c of tile t follows chunks 0..c-1 of tile t, so every tile
/// lists its splats in ascending surfel order whatever the thread count.
void binSplats(RenderFrameState& f) {
  SplatWorkspace& ws = f.ws;
  const int tiles = f.tiles;
  const size_t chunks = f.chunk_counts.size();
  ws.tile_offsets.resize(size_t(tiles) + 1);
  uint32_t running = 0;
  for (int tile = 0; tile < tiles; ++tile) {
    ws.tile_offsets[tile] = running;
    for (size_t chunk = 0; chunk < chunks; ++chunk) {
      uint32_t& count = ws.chunk_tile_counts[chunk * size_t(tiles) + tile];
      const uint32_t chunk_count = count;
      count = running;  // now the write cursor
      running += chunk_count;
    }
  }
  ws.tile_offsets[tiles] = running;
  ws.bin_items.reserve(running);
#pragma omp parallel for num_threads(f.threads) schedule(dynamic, 1)
  for (size_t chunk = 0; chunk < chunks; ++chunk) {
    const ChunkCounts& counts = f.chunk_counts[chunk];
    SplatRaster* staged = ws.staged.data();
    uint32_t* cursor = ws.chunk_tile_counts.data() + chunk * size_t(tiles);
    uint32_t* items = ws.bin_items.data();
    for (uint32_t k = uint32_t(counts.begin); k < counts.begin + counts.drawn; ++k) {
      SplatRaster& raster = staged[k];
      if (raster.flags & (SplatRaster::kClip | SplatRaster::kClipColorOnly))
        raster.flags += counts.clip_offset;
      forEachTileOfSplat(raster, f.tiles_x, [&](int tile) { items[cursor[tile]++] = k; });
    }
  }
}

/// Sizes the requested images and empties the others.
void prepareImages(const SplatConfig& config, const Camera& camera, size_t pixels, RenderImages* out) {
  out->width = camera.width;
  out->height = camera.height;
  auto prepareImage = [&](auto& image, RenderOutput output) {
    if (config.outputs & output) {
      image.resize(pixels);
    } else {
      image.clear();
    }
  };
  prepareImage(out->color, kOutputColor);
  prepareImage(out->depth, kOutputDepth);
  prepareImage(out->normal, kOutputNormal);
  prepareImage(out->weight, kOutputWeight);
  prepareImage(out->patch_id, kOutputPatchId);
}

/// What the tile passes of a frame accumulate, and which code paths they take.
struct TilePassOptions {
  /// With CSG clipping, a fragment blends only with the patch of the pixel's front fragment.
  bool separate_patches;
  bool accumulate_depth, accumulate_patch, accumulate_color, accumulate_normal;
  bool separate_color_weight;  ///< colour-only clipping: the colour weight differs from the weight
  AccumulatedSums sums_needed;
  bool wide;  ///< AVX2 passes for unclipped splats
  /// SplatConfig::exact_silhouettes: pass 1 counts only fragments inside a splat's unfiltered footprint.
  bool exact_silhouettes;
  bool ewa_filter;
  double coverage_filter;  ///< the low-pass variance in the conic's cut-off units (cutoff_sigmas^2 v)
};

TilePassOptions tilePassOptions(const RenderFrameState& f) {
  const SplatConfig& config = f.config;
  TilePassOptions o;
  o.separate_patches = f.clipper != nullptr;
  // Sums that no requested image needs are not accumulated (SIMD path); the colour weight differs from the
  // weight only with colour-only clipping (texture discontinuities, 4.3).
  o.accumulate_depth = (config.outputs & kOutputDepth) != 0;
  o.accumulate_patch = (config.outputs & kOutputPatchId) != 0;
  o.accumulate_color = (config.outputs & kOutputColor) != 0;
  o.accumulate_normal = (config.outputs & kOutputNormal) != 0 || (o.accumulate_color && config.shading);
  o.separate_color_weight = !kSimd;
  for (const uint32_t surfel : f.ws.clip_surfels)
    o.separate_color_weight |= f.clipper->clipsColorOnly(surfel);
  o.sums_needed = kSimd ? AccumulatedSums{o.separate_color_weight, o.accumulate_depth, o.accumulate_color,
                                          o.accumulate_normal, o.accumulate_patch}
                        : AccumulatedSums{true, true, true, true, true};
  // Eight pixels at a time (AVX2) for unclipped splats where the CPU has it: bitwise the same images.
  o.wide = kSimd && config.wide_simd && !o.separate_color_weight && avx2TilePassesAvailable();
  o.exact_silhouettes = config.exact_silhouettes;
  o.ewa_filter = config.ewa_filter;
  const double cutoff_sigmas = config.cutoff_radius / kKernelSigmaPerRadius;
  o.coverage_filter = cutoff_sigmas * cutoff_sigmas * config.lowpass_variance;
  return o;
}

/// One thread's tile passes (3.2.2): pass 1 (visibility) finds per pixel the smallest z and the smallest
/// z + eps_z over all (unclipped) fragments; pass 2 (accumulation) blends the fragments with z <= that bound
/// and z - eps_z <= the smallest z (a large front surfel does not pull in small ones behind it); then the
/// tile is normalised and shaded (deferred Phong, two-sided: the normal is turned towards the viewer).
/// Clipped splats are tested once, in pass 1; their keep bits (per row, bit x - x0) are reused by pass 2.
class TileRenderer {
 public:
  TileRenderer(const RenderFrameState& f, const TilePassOptions& o, const WeightTable& weight_table,
               const DeferredShader& shader, RenderImages* out, SplatAccumulation* keep)
      : keep_(keep),
        ws_(f.ws),
        clipper_(f.clipper),
        frame_(f.frame),
        o_(o),
        weight_table_(weight_table),
        shader_(shader),
        out_(out),
        width_(f.width),
        height_(f.height),
        tiles_x_(f.tiles_x),
        buffers_(new TileBuffers()),
        tb_(*buffers_),
        wide_sums_{tb_.weight,
                   o.accumulate_depth ? tb_.depth : nullptr,
                   {o.accumulate_normal ? tb_.normal[0] : nullptr, tb_.normal[1], tb_.normal[2]},
                   {o.accumulate_color ? tb_.color[0] : nullptr, tb_.color[1], tb_.color[2]},
                   tb_.max_weight,
                   o.accumulate_patch ? tb_.patch_id : nullptr},
        candidate_rows_(kTileSize) {}

  void renderTile(int tile);

  size_t fragments = 0, clipped_fragments = 0;
  double visibility_ms = 0, accumulate_ms = 0, shade_ms = 0;

 private:
  struct ClipItem {
    float z_lo;
    uint32_t item, rows;  ///< index in the tile's list, offset of its rows in keep_rows_
  };

  int index(int x, int y) const { return (y - rect_.y0) * kTileStride + x - rect_.x0; }
  /// True if the clipper keeps fragment (x, y) of a splat flagged kClip* (per-fragment path, 4.2.2).
  bool keeps(const SplatRaster& s, int x, int y) const {
    const uint32_t slot = s.clipSlot();
    return clipper_->keepFragment(ws_.clip_surfels[slot],
                                  fragmentWorldPoint(ws_.clip_geometry[slot], frame_, x, y));
  }
  void selectTile(int tile);
  void visibilityPass();
  /// Pass 1's footprint of s: its unfiltered one with exact_silhouettes, else s itself. False: it covers
  /// no pixel centre.
  bool coverage(const SplatRaster& s, SplatRaster* footprint) const;
  /// NearerFragmentTest's filter variance for s (-1 without exact_silhouettes).
  double nearerFilter(const SplatRaster& s) const {
    return o_.exact_silhouettes ? conicFilterVariance(s, o_.ewa_filter, o_.coverage_filter) : -1.0;
  }
  void visibilitySplat(uint32_t k, uint64_t* rows);
  void visibilitySplatScalar(const SplatRaster& s, const SplatRaster* covering,
                             const SplatShading& front_shading, uint64_t* rows);
  /// exact_silhouettes: pixels no fragment covers get bound -inf (pass 2 draws nothing there).
  void markUncovered();
  void updateBlockMax();
  bool occluded(const SplatRaster& s) const;
  void accumulationPass();
  void accumulateSplatScalar(const SplatRaster& s, const SplatBlend& shading, const uint64_t* rows, int row0);
#if defined(__SSE2__)
  void visibilityUpdate4(int i, __m128 z, __m128 mask, __m128 tolerance4, const SplatShading& front_shading);
  void visibilitySplatClipped4(const SplatRaster& s, const SplatRaster* covering,
                               const SplatShading& front_shading, uint64_t* rows);
  int colorKeep4(const SplatRaster& s, const ClipProgram* color_program, int x, int y, int lanes) const;
  void accumulateSplat4(const SplatRaster& s, const SplatBlend& shading, const uint64_t* rows, int row0);
#endif
  void shadeTile();
  /// Copies the tile's bounds and sums into keep_ (an empty tile: no coverage).
  void keepTile(int tile, bool empty);

  SplatAccumulation* keep_;
  const SplatWorkspace& ws_;
  const FragmentClipper* clipper_;
  const CameraFrame& frame_;
  const TilePassOptions& o_;
  const WeightTable& weight_table_;
  const DeferredShader& shader_;
  RenderImages* out_;
  const int width_, height_, tiles_x_;
  std::unique_ptr<TileBuffers> buffers_;
  TileBuffers& tb_;
  const TileSums wide_sums_;
  std::vector<uint64_t> keep_rows_;  ///< keep bits of the tile's clipped splats, row by row (bit x - x0)
  std::vector<ClipItem> clip_items_, sorted_clip_items_;
  std::vector<uint64_t> candidate_rows_;
  std::vector<uint32_t> sorted_items_;
  alignas(16) float clip_depth_[kTileSize * kTileStride];  ///< depth of the candidate fragments
  // The current tile.
  TileRect rect_;
  const SplatRaster* staged_;
  const SplatShading* staged_shading_;
  const uint32_t* items_;
  uint32_t splat_count_;
  /// Largest bound per block: a splat whose nearest depth lies behind it everywhere in its box has no
  /// visible fragment there (occlusion culling; exact, z >= z_lo; clipping only removes fragments).
  float block_max_[kBlocksPerTile * kBlocksPerTile];
};

void TileRenderer::renderTile(int tile) {
  const Clock::time_point start_tile = Clock::now();
  selectTile(tile);
  if (splat_count_ == 0) {
    for (int y = rect_.y0; y <= rect_.y1; ++y) shader_.clearSpan(rect_.x1 - rect_.x0 + 1, rect_.x0, y, out_);
    if (keep_) keepTile(tile, true);
    shade_ms += millisecondsSince(start_tile);
    return;
  }
  visibilityPass();
  const Clock::time_point start_accumulate = Clock::now();
  visibility_ms += std::chrono::duration<double, std::milli>(start_accumulate - start_tile).count();
  accumulationPass();
  if (keep_) keepTile(tile, false);
  const Clock::time_point start_shade = Clock::now();
  accumulate_ms += std::chrono::duration<double, std::milli>(start_shade - start_accumulate).count();
  shadeTile();
  shade_ms += millisecondsSince(start_shade);
}

/// The tile's rectangle and splat list.
void TileRenderer::selectTile(int tile) {
  rect_.x0 = (tile % tiles_x_) * kTileSize;
  rect_.y0 = (tile / tiles_x_) * kTileSize;
  rect_.x1 = std::min(width_, rect_.x0 + kTileSize) - 1;
  rect_.y1 = std::min(height_, rect_.y0 + kTileSize) - 1;
  staged_ = ws_.staged.data();
  staged_shading_ = ws_.staged_shading.data();
  items_ = ws_.bin_items.data() + ws_.tile_offsets[tile];
  splat_count_ = ws_.tile_offsets[tile + 1] - ws_.tile_offsets[tile];
  if (splat_count_ > 1 && splat_count_ <= kSortMaxSplats) {
    // Few (large) splats: front to back (nearest depth, ties by surfel order), so that the occlusion
    // test of pass 1 rejects the hidden ones. Both passes give order-independent results up to the
    // rounding of the sums; the order is the same for any thread count.
    sorted_items_.assign(items_, items_ + splat_count_);
    std::sort(sorted_items_.begin(), sorted_items_.end(), [&](uint32_t a, uint32_t b) {
      const float za = ws_.staged[a].z_lo, zb = ws_.staged[b].z_lo;
      return za != zb ? za < zb : a < b;
    });
    items_ = sorted_items_.data();
  }
}

/// Pass 1. Its result (per-pixel minima) does not depend on the order of the splats: unclipped splats go
/// first, then the clipped ones front to back, so that most of their hidden fragments are rejected by depth
/// before the (costlier) clip test. Splats facing the camera go first; those facing away (drawn two-sided,
/// mostly hidden behind the front of closed surfaces) follow, each tested against the bounds the front left.
void TileRenderer::visibilityPass() {
  tb_.clearVisibility();
  keep_rows_.clear();
  clip_items_.clear();
  bool block_max_stale = true;
  uint32_t back_facing = 0;
  for (uint32_t k = 0; k < splat_count_; ++k) {
    if (k + kPrefetchDistance < splat_count_) {
      __builtin_prefetch(staged_ + items_[k + kPrefetchDistance]);
      if (o_.separate_patches) __builtin_prefetch(staged_shading_ + items_[k + kPrefetchDistance]);
    }
    const SplatRaster& s = staged_[items_[k]];
    if (s.flags & SplatRaster::kClip) {
      const uint32_t rows = uint32_t(std::min(int(s.y1), rect_.y1) - std::max(int(s.y0), rect_.y0) + 1);
      clip_items_.push_back({s.z_lo, k, uint32_t(keep_rows_.size())});
      keep_rows_.resize(keep_rows_.size() + rows, 0);
      continue;
    }
    if (s.flags & SplatRaster::kBackFacing) {
      ++back_facing;
      continue;
    }
    // A large splat is first tested against the bounds so far (they only decrease: a splat hidden now
    // stays hidden); small ones are not worth the refresh.
    if (int(s.x1 - s.x0 + 1) * int(s.y1 - s.y0 + 1) >= kOcclusionTestArea) {
      if (block_max_stale) updateBlockMax();
      block_max_stale = false;
      if (occluded(s)) continue;
    }
    visibilitySplat(k, nullptr);
    block_max_stale = true;
  }
  if (back_facing) {
    updateBlockMax();
    for (uint32_t k = 0; k < splat_count_; ++k) {
      const SplatRaster& s = staged_[items_[k]];
      if ((s.flags & (SplatRaster::kBackFacing | SplatRaster::kClip)) != SplatRaster::kBackFacing ||
          occluded(s))
        continue;
      visibilitySplat(k, nullptr);
    }
  }
  if (!clip_items_.empty()) {
    sorted_clip_items_ = clip_items_;
    std::sort(sorted_clip_items_.begin(), sorted_clip_items_.end(), [](const ClipItem& a, const ClipItem& b) {
      return a.z_lo != b.z_lo ? a.z_lo < b.z_lo : a.item < b.item;
    });
    updateBlockMax();
    for (const ClipItem& clip_item : sorted_clip_items_)
      if (!occluded(staged_[items_[clip_item.item]]))
        visibilitySplat(clip_item.item, keep_rows_.data() + clip_item.rows);
  }
  if (o_.exact_silhouettes) markUncovered();
  updateBlockMax();
}

void TileRenderer::markUncovered() {
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  for (int i = 0; i < kTileBufferSize; ++i)
    if (tb_.bound[i] == kInfinity) tb_.bound[i] = -kInfinity;
}

bool TileRenderer::coverage(const SplatRaster& s, SplatRaster* footprint) const {
  return unfilteredFootprint(s, nearerFilter(s), footprint);  // (without exact_silhouettes: s itself)
}

/// Pass 1 of splat k. Clipped splats: the clip test runs only on fragments not behind the current bound
/// (the others cannot pass the final depth test either), and records its keep bits in `rows`.
void TileRenderer::visibilitySplat(uint32_t k, uint64_t* rows) {
  const SplatRaster& s = staged_[items_[k]];
  const SplatShading& front_shading = staged_shading_[items_[k]];  // read only with separate patches
  const bool clip_any = rows != nullptr;
  SplatRaster footprint;
  const bool covers = coverage(s, &footprint);
  if (!covers && !clip_any) return;  // (clipped: its keep bits are still needed by pass 2)
  const SplatRaster* covering = covers ? &footprint : nullptr;
  if (!kSimd) {
    visibilitySplatScalar(s, covering, front_shading, rows);
    return;
  }
#if defined(__SSE2__)
  if (!clip_any && o_.wide && !o_.separate_patches) {
    visibilitySplatAvx2(footprint, rect_, tb_.bound, tb_.front);
    return;
  }
  if (!clip_any) {
    const __m128 tolerance4 = _mm_set1_ps(s.depth_tolerance);
    rasterizeSplat4(footprint, rect_, [&](int i, int, int, __m128, __m128 z, __m128 mask) {
      visibilityUpdate4(i, z, mask, tolerance4, front_shading);
    });
    return;
  }
  visibilitySplatClipped4(s, covering, front_shading, rows);
#endif
}

void TileRenderer::visibilitySplatScalar(const SplatRaster& s, const SplatRaster* covering,
                                         const SplatShading& front_shading, uint64_t* rows) {
  const float tolerance = s.depth_tolerance;
  const bool clip_any = rows != nullptr;
  const bool clip_geometry = (s.flags & SplatRaster::kClip) != 0;
  const int row0 = std::max(int(s.y0), rect_.y0);
  // Clipped splats: keep bits over the filtered footprint (pass 2 blends it), updates where it covers.
  rasterizeSplat(clip_any ? s : *covering, rect_, [&](int x, int y, float, float z) {
    const int i = index(x, y);
    if (clip_any && z <= tb_.bound[i]) {
      const bool kept = keeps(s, x, y);
      clipped_fragments += !kept;
      rows[y - row0] |= uint64_t(kept) << (x - rect_.x0);
      if (clip_geometry && !kept) return;
    }
    if (clip_any && !(covering && coversPixel(*covering, x, y))) return;
    tb_.bound[i] = std::min(tb_.bound[i], z + tolerance);
    if (z < tb_.front[i]) {
      tb_.front[i] = z;
      tb_.front_patch[i] = front_shading.patch_id;
      for (int c = 0; c < 3; ++c) tb_.front_normal[c][i] = front_shading.normal[c];
    }
  });
}

#if defined(__SSE2__)
/// Pass 1 at the four pixels from i where mask is set.
void TileRenderer::visibilityUpdate4(int i, __m128 z, __m128 mask, __m128 tolerance4,
                                     const SplatShading& front_shading) {
  const __m128 b = _mm_loadu_ps(tb_.bound + i), f = _mm_loadu_ps(tb_.front + i);
  _mm_storeu_ps(tb_.bound + i, select(mask, _mm_min_ps(b, _mm_add_ps(z, tolerance4)), b));
  const __m128 nearer = _mm_and_ps(mask, _mm_cmplt_ps(z, f));
  _mm_storeu_ps(tb_.front + i, select(nearer, z, f));
  if (!o_.separate_patches) return;
  float* front_patches = reinterpret_cast<float*>(tb_.front_patch + i);
  const __m128 patch4 = _mm_castsi128_ps(_mm_set1_epi32(front_shading.patch_id));
  _mm_storeu_ps(front_patches, select(nearer, patch4, _mm_loadu_ps(front_patches)));
  for (int c = 0; c < 3; ++c) {
    float* front_normal = tb_.front_normal[c] + i;
    _mm_storeu_ps(front_normal,
                  select(nearer, _mm_set1_ps(front_shading.normal[c]), _mm_loadu_ps(front_normal)));
  }
}

/// Clipped: collect per row the fragments not behind the current bound (bit x - x0) and their depth, test
/// them a row at a time, then update with the kept ones.
void TileRenderer::visibilitySplatClipped4(const SplatRaster& s, const SplatRaster* covering,
                                           const SplatShading& front_shading, uint64_t* rows) {
  const __m128 tolerance4 = _mm_set1_ps(s.depth_tolerance);
  const bool clip_geometry = (s.flags & SplatRaster::kClip) != 0;
  const int row0 = std::max(int(s.y0), rect_.y0);
  const int rows_count = std::min(int(s.y1), rect_.y1) - row0 + 1;
  uint64_t* candidates = candidate_rows_.data();
  std::fill_n(candidates, rows_count, 0);
  rasterizeSplat4(s, rect_, [&](int i, int x, int y, __m128, __m128 z, __m128 mask) {
    const int lanes = _mm_movemask_ps(_mm_and_ps(mask, _mm_cmple_ps(z, _mm_loadu_ps(tb_.bound + i))));
    if (!lanes) return;
    candidates[y - row0] |= uint64_t(lanes) << (x - rect_.x0);
    _mm_storeu_ps(clip_depth_ + i, z);
  });
  const uint32_t slot = s.clipSlot();
  const ClipProgram* program = ws_.clip_compiled[slot] ? &ws_.clip_programs[slot] : nullptr;
  for (int r = 0; r < rows_count; ++r) {
    const uint64_t candidate = candidates[r];
    if (!candidate) continue;
    const int y = row0 + r;
    uint64_t keep = 0;
    if (program) {
      keep = program->keepRow(y - program->v0(), rect_.x0 - program->u0(), candidate);
    } else {
      for (uint64_t bits = candidate; bits; bits &= bits - 1) {
        const int b = __builtin_ctzll(bits);
        if (keeps(s, rect_.x0 + b, y)) keep |= uint64_t(1) << b;
      }
    }
    clipped_fragments += size_t(__builtin_popcountll(candidate & ~keep));
    rows[r] = keep;
    if (!covering) continue;
    const uint64_t drawn = clip_geometry ? keep : candidate;
    const int base = (y - rect_.y0) * kTileStride;
    for (uint64_t bits = drawn; bits;) {
      const int b = __builtin_ctzll(bits);
      const __m128 lanes =
          _mm_and_ps(laneMask(int((bits >> b) & 0xF)), coversPixels4(*covering, rect_.x0 + b, y));
      visibilityUpdate4(base + b, _mm_loadu_ps(clip_depth_ + base + b), lanes, tolerance4, front_shading);
      bits &= ~(uint64_t(0xF) << b);
    }
  }
}
#endif

void TileRenderer::updateBlockMax() {
  const float infinity = std::numeric_limits<float>::infinity();
#if defined(__SSE2__)
  // Whole blocks (pixels outside a partial tile keep bound = +inf: conservative).
  for (int by = 0; by < kBlocksPerTile; ++by) {
    for (int bx = 0; bx < kBlocksPerTile; ++bx) {
      __m128 largest = _mm_set1_ps(-infinity);
      for (int r = 0; r < kBlockSize; ++r) {
        const float* row = tb_.bound + (by * kBlockSize + r) * kTileStride + bx * kBlockSize;
        largest = _mm_max_ps(largest, _mm_max_ps(_mm_loadu_ps(row), _mm_loadu_ps(row + 4)));
      }
      alignas(16) float lanes[4];
      _mm_store_ps(lanes, largest);
      block_max_[by * kBlocksPerTile + bx] =
          std::max(std::max(lanes[0], lanes[1]), std::max(lanes[2], lanes[3]));
    }
  }
#else
  for (int by = 0; by < kBlocksPerTile; ++by) {
    for (int bx = 0; bx < kBlocksPerTile; ++bx) {
      float largest = -infinity;
      for (int y = rect_.y0 + by * kBlockSize;
           y <= std::min(rect_.y1, rect_.y0 + by * kBlockSize + kBlockSize - 1); ++y)
        for (int x = rect_.x0 + bx * kBlockSize;
             x <= std::min(rect_.x1, rect_.x0 + bx * kBlockSize + kBlockSize - 1); ++x)
          largest = std::max(largest, tb_.bound[index(x, y)]);
      block_max_[by * kBlocksPerTile + bx] = largest;
    }
  }
#endif
}

bool TileRenderer::occluded(const SplatRaster& s) const {
  const int bx0 = (std::max(int(s.x0), rect_.x0) - rect_.x0) / kBlockSize;
  const int bx1 = (std::min(int(s.x1), rect_.x1) - rect_.x0) / kBlockSize;
  const int by0 = (std::max(int(s.y0), rect_.y0) - rect_.y0) / kBlockSize;
  const int by1 = (std::min(int(s.y1), rect_.y1) - rect_.y0) / kBlockSize;
  for (int by = by0; by <= by1; ++by)
    for (int bx = bx0; bx <= bx1; ++bx)
      if (!(s.z_lo > block_max_[by * kBlocksPerTile + bx])) return false;
  return true;
}

/// Pass 2. With CSG clipping, fragments of different patches meet only at (sharp) edges: a fragment blends
/// only with the patch of the pixel's front fragment, so a face behind a silhouette does not bleed in.
void TileRenderer::accumulationPass() {
  tb_.clearAccumulation(o_.sums_needed);
  size_t next_clip_item = 0;
  for (uint32_t k = 0; k < splat_count_; ++k) {
    if (k + kPrefetchDistance < splat_count_) {  // pass 1 brought the raster records into the caches
      __builtin_prefetch(staged_shading_ + items_[k + kPrefetchDistance]);
    }
    const SplatRaster& s = staged_[items_[k]];
    const bool clip_geometry = (s.flags & SplatRaster::kClip) != 0;
    const bool clip_color = (s.flags & SplatRaster::kClipColorOnly) != 0;
    const uint64_t* rows = nullptr;
    int row0 = 0;
    if (clip_geometry) {  // this splat's keep bits from pass 1
      row0 = std::max(int(s.y0), rect_.y0);
      rows = keep_rows_.data() + clip_items_[next_clip_item++].rows;
    }
    if (occluded(s)) continue;
    const SplatShading& attributes = staged_shading_[items_[k]];
    const SplatBlend shading = {
        {attributes.normal[0], attributes.normal[1], attributes.normal[2]},
        {float(attributes.color[0]), float(attributes.color[1]), float(attributes.color[2])},
        attributes.patch_id};
    if (o_.wide && !clip_geometry && !clip_color && !o_.separate_patches) {
      fragments += accumulateSplatAvx2(s, rect_, tb_.bound, tb_.front, shading, weight_table_.data(),
                                       kWeightTableSteps, wide_sums_, nearerFilter(s));
      continue;
    }
    if (!kSimd) {
      accumulateSplatScalar(s, shading, rows, row0);
      continue;
    }
#if defined(__SSE2__)
    accumulateSplat4(s, shading, rows, row0);
#endif
  }
}

void TileRenderer::accumulateSplatScalar(const SplatRaster& s, const SplatBlend& shading,
                                         const uint64_t* rows, int row0) {
  const bool clip_geometry = (s.flags & SplatRaster::kClip) != 0;
  const bool clip_color = (s.flags & SplatRaster::kClipColorOnly) != 0;
  const float tolerance = s.depth_tolerance;
  NearerFragmentTest nearer(s, nearerFilter(s));
  rasterizeSplat(s, rect_, [&](int x, int y, float r2, float z) {
    if (clip_geometry && !((rows[y - row0] >> (x - rect_.x0)) & 1)) return;
    const int i = index(x, y);
    // Blend iff within the tolerance of the front surfel AND within this surfel's own tolerance of
    // the front depth: eps_z from both the pixel's and the incoming surfel (3.2.1).
    if (z > tb_.bound[i] || z - tolerance > tb_.front[i]) return;
    if (nearer.active() && z + tolerance < tb_.front[i] && !nearer.covers(x, y)) return;
    if (o_.separate_patches && shading.patch_id != tb_.front_patch[i] &&
        shading.normal[0] * tb_.front_normal[0][i] + shading.normal[1] * tb_.front_normal[1][i] +
                shading.normal[2] * tb_.front_normal[2][i] <
            kCrossPatchBlendCosine)
      return;
    const bool add_color = !clip_color || keeps(s, x, y);
    clipped_fragments += !add_color;
    const int step = std::min(kWeightTableSteps, int(std::max(r2, 0.0f) * kWeightTableSteps + 0.5f));
    const float w = weight_table_[step];
    tb_.weight[i] += w;
    tb_.depth[i] += w * z;
    for (int c = 0; c < 3; ++c) tb_.normal[c][i] += w * shading.normal[c];
    if (add_color) {
      tb_.color_weight[i] += w;
      for (int c = 0; c < 3; ++c) tb_.color[c][i] += w * shading.color[c];
    }
    if (w > tb_.max_weight[i]) {
      tb_.max_weight[i] = w;
      tb_.patch_id[i] = shading.patch_id;
    }
    ++fragments;
  });
}

#if defined(__SSE2__)
/// Colour-only clipping (texture discontinuities, 4.3) does not change visibility: it is tested in pass 2, on
/// the fragments that blend, only. Keep bits of the lanes of (x, y).
int TileRenderer::colorKeep4(const SplatRaster& s, const ClipProgram* color_program, int x, int y,
                             int lanes) const {
  if (color_program)
    return int(color_program->keepRow(y - color_program->v0(), x - color_program->u0(), uint64_t(lanes)));
  int keep = 0;
  for (int lane = 0; lane < 4; ++lane)
    if ((lanes >> lane & 1) && keeps(s, x + lane, y)) keep |= 1 << lane;
  return keep;
}

void TileRenderer::accumulateSplat4(const SplatRaster& s, const SplatBlend& shading, const uint64_t* rows,
                                    int row0) {
  const bool clip_geometry = (s.flags & SplatRaster::kClip) != 0;
  const bool clip_color = (s.flags & SplatRaster::kClipColorOnly) != 0;
  const ClipProgram* color_program =
      clip_color && ws_.clip_compiled[s.clipSlot()] ? &ws_.clip_programs[s.clipSlot()] : nullptr;
  const __m128 normal0 = _mm_set1_ps(shading.normal[0]), normal1 = _mm_set1_ps(shading.normal[1]),
               normal2 = _mm_set1_ps(shading.normal[2]);
  const __m128 color0 = _mm_set1_ps(shading.color[0]), color1 = _mm_set1_ps(shading.color[1]),
               color2 = _mm_set1_ps(shading.color[2]);
  const __m128 patch = _mm_castsi128_ps(_mm_set1_epi32(shading.patch_id));
  const __m128 steps = _mm_set1_ps(float(kWeightTableSteps)), half = _mm_set1_ps(0.5f);
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
  const __m128 tolerance4 = _mm_set1_ps(s.depth_tolerance);
  const __m128 all_lanes = _mm_castsi128_ps(_mm_set1_epi32(-1));
  NearerFragmentTest nearer(s, nearerFilter(s));
  rasterizeSplat4(s, rect_, [&](int i, int x, int y, __m128 r2, __m128 z, __m128 mask) {
    if (clip_geometry) mask = _mm_and_ps(mask, laneMask(int(rows[y - row0] >> (x - rect_.x0)) & 0xF));
    const __m128 front = _mm_loadu_ps(tb_.front + i);
    __m128 pass = _mm_and_ps(_mm_and_ps(mask, _mm_cmple_ps(z, _mm_loadu_ps(tb_.bound + i))),
                             _mm_cmple_ps(_mm_sub_ps(z, tolerance4), front));
    if (nearer.active()) {
      const __m128 closer = _mm_and_ps(pass, _mm_cmplt_ps(_mm_add_ps(z, tolerance4), front));
      if (_mm_movemask_ps(closer)) {
        const SplatRaster* own = nearer.footprint();
        const __m128 covered = own ? coversPixels4(*own, x, y) : _mm_setzero_ps();
        pass = _mm_andnot_ps(_mm_andnot_ps(covered, closer), pass);
      }
    }
    if (!_mm_movemask_ps(pass)) return;
    if (o_.separate_patches) pass = blendsWithFront(pass, patch, shading.normal, tb_, i);
    const int bits = _mm_movemask_ps(pass);
    if (!bits) return;
    fragments += kBitCount[bits];
    __m128 color_lanes = all_lanes;
    if (clip_color) {  // texture discontinuity: only the colour is clipped (4.3)
      const int keep = colorKeep4(s, color_program, x, y, bits);
      clipped_fragments += kBitCount[bits & ~keep];
      color_lanes = laneMask(keep);
    }
    alignas(16) int32_t step[4];
    const __m128 clamped = _mm_min_ps(_mm_max_ps(r2, zero), one);
    _mm_store_si128(reinterpret_cast<__m128i*>(step),
                    _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(clamped, steps), half)));
    const __m128 w = _mm_and_ps(pass, _mm_setr_ps(weight_table_[step[0]], weight_table_[step[1]],
                                                  weight_table_[step[2]], weight_table_[step[3]]));
    const __m128 color_w = _mm_and_ps(w, color_lanes);
    auto add = [&](float* buffer, __m128 value) {
      _mm_storeu_ps(buffer + i, _mm_add_ps(_mm_loadu_ps(buffer + i), value));
    };
    add(tb_.weight, w);
    if (o_.accumulate_depth) add(tb_.depth, _mm_mul_ps(w, z));
    if (o_.accumulate_normal) {
      add(tb_.normal[0], _mm_mul_ps(w, normal0));
      add(tb_.normal[1], _mm_mul_ps(w, normal1));
      add(tb_.normal[2], _mm_mul_ps(w, normal2));
    }
    if (o_.accumulate_color) {
      if (o_.separate_color_weight) add(tb_.color_weight, color_w);
      add(tb_.color[0], _mm_mul_ps(color_w, color0));
      add(tb_.color[1], _mm_mul_ps(color_w, color1));
      add(tb_.color[2], _mm_mul_ps(color_w, color2));
    }
    if (!o_.accumulate_patch) return;
    const __m128 max_weight = _mm_loadu_ps(tb_.max_weight + i);
    const __m128 larger = _mm_cmpgt_ps(w, max_weight);
    _mm_storeu_ps(tb_.max_weight + i, select(larger, w, max_weight));
    float* patch_ids = reinterpret_cast<float*>(tb_.patch_id + i);
    _mm_storeu_ps(patch_ids, select(larger, patch, _mm_loadu_ps(patch_ids)));
  });
}
#endif

void TileRenderer::keepTile(int tile, bool empty) {
  constexpr size_t kBytes = sizeof(float) * kTileBufferSize;
  auto copy = [&](SplatAccumulation::Sum sum, const float* from) {
    if (empty) {
      if (sum == SplatAccumulation::kBound || sum == SplatAccumulation::kFront) {
        std::fill_n(keep_->sum(tile, sum), kTileBufferSize, std::numeric_limits<float>::infinity());
      } else {
        std::memset(keep_->sum(tile, sum), 0, kBytes);
      }
    } else {
#if defined(__SSE2__)
      // Streaming stores: the kept sums are read again only by later deltas, not by this frame.
      float* to = keep_->sum(tile, sum);
      for (int i = 0; i < kTileBufferSize; i += 4) _mm_stream_ps(to + i, _mm_load_ps(from + i));
#else
      std::memcpy(keep_->sum(tile, sum), from, kBytes);
#endif
    }
  };
  copy(SplatAccumulation::kBound, tb_.bound);
  copy(SplatAccumulation::kFront, tb_.front);
  copy(SplatAccumulation::kWeight, tb_.weight);
  if (keep_->has_depth) copy(SplatAccumulation::kDepth, tb_.depth);
  for (int c = 0; c < 3 && keep_->has_color; ++c)
    copy(SplatAccumulation::Sum(SplatAccumulation::kColor0 + c), tb_.color[c]);
  for (int c = 0; c < 3 && keep_->has_normal; ++c)
    copy(SplatAccumulation::Sum(SplatAccumulation::kNormal0 + c), tb_.normal[c]);
#if defined(__SSE2__)
  _mm_sfence();
#endif
}

/// Normalise by the accumulated weights and shade.
void TileRenderer::shadeTile() {
  for (int y = rect_.y0; y <= rect_.y1; ++y) {
    const int i = index(rect_.x0, y);
    const AccumulatedSpan span = {tb_.weight + i,
                                  (o_.separate_color_weight ? tb_.color_weight : tb_.weight) + i,
                                  tb_.depth + i,
                                  {tb_.color[0] + i, tb_.color[1] + i, tb_.color[2] + i},
                                  {tb_.normal[0] + i, tb_.normal[1] + i, tb_.normal[2] + i},
                                  tb_.patch_id + i};
    shader_.shadeSpan(span, rect_.x1 - rect_.x0 + 1, rect_.x0, y, out_);
  }
}

}  // namespace

SurfelRenderer::SurfelRenderer(const SplatConfig& config) : config_(config) {
  validateConfig(config_);
}

void SurfelRenderer::render(const SurfelCloud& cloud, const Camera& camera, RenderImages* out,
                            const FragmentClipper* clipper, RenderStats* stats,
                            SplatAccumulation* keep) const {
  const Clock::time_point start_total = Clock::now();
  checkRenderInputs(config_, cloud, camera, out, clipper);
  if (config_.backface_culling && clipper && clipper->flipsAnyNormal())
    throw std::invalid_argument(
        "SurfelRenderer::render: backface_culling with complemented CSG patches (a difference or complement) "
        "is not supported: culling leaves the rims of subtracted solids wrong; render two-sided "
        "(backface_culling false)");
  if (keep && (clipper || (config_.outputs & kOutputPatchId)))
    throw std::invalid_argument(
        "SurfelRenderer::render: the accumulation is kept only without clipping and without the patch id "
        "image");

  // The renderer's scratch memory, or a temporary one while another thread renders with this renderer.
  std::unique_lock<std::mutex> workspace_lock(workspace_.mutex, std::try_to_lock);
  std::unique_ptr<SplatWorkspace> temporary_workspace;
  if (!workspace_lock.owns_lock()) temporary_workspace = std::make_unique<SplatWorkspace>();
  SplatWorkspace& ws = temporary_workspace ? *temporary_workspace : workspace_.workspace;
  RenderFrameState f(config_, cloud, camera, clipper, ws);

  const Clock::time_point start_setup = Clock::now();
  const uint32_t clip_count = setupSplats(f);
  setupClipSurfels(f, clip_count);
  f.stats.setup_ms = millisecondsSince(start_setup);

  const Clock::time_point start_bin = Clock::now();
  binSplats(f);
  f.stats.bin_ms = millisecondsSince(start_bin);

  const WeightTable weight_table = makeWeightTable(config_.cutoff_radius);
  prepareImages(config_, camera, f.pixels, out);
  const DeferredShader shader(config_, f.frame);
  const TilePassOptions options = tilePassOptions(f);
  f.stats.simd_width = options.wide ? 8 : kSimd ? 4 : 1;
  if (keep) {
    keep->resize(camera.width, camera.height);
    keep->has_depth = options.sums_needed.depth;
    keep->has_color = options.sums_needed.color;
    keep->has_normal = options.sums_needed.normal;
  }
  size_t fragments = 0, clipped_fragments = 0;
  double visibility_ms = 0, accumulate_ms = 0, shade_ms = 0;
#pragma omp parallel num_threads(f.threads) reduction(+ : fragments, clipped_fragments, visibility_ms, \
                                                          accumulate_ms, shade_ms)
  {
    TileRenderer tiles(f, options, weight_table, shader, out, keep);
#pragma omp for schedule(dynamic, 1)
    for (int tile = 0; tile < f.tiles; ++tile) tiles.renderTile(tile);
    shader.finish();
    fragments += tiles.fragments;
    clipped_fragments += tiles.clipped_fragments;
    visibility_ms += tiles.visibility_ms;
    accumulate_ms += tiles.accumulate_ms;
    shade_ms += tiles.shade_ms;
  }
  RenderStats& local_stats = f.stats;
  local_stats.fragments = fragments;
  local_stats.clipped_fragments = clipped_fragments;
  local_stats.visibility_ms = visibility_ms / f.threads;
  local_stats.accumulate_ms = accumulate_ms / f.threads;
  local_stats.shade_ms = shade_ms / f.threads;
  local_stats.total_ms = millisecondsSince(start_total);
  if (stats) *stats = local_stats;
}

}  // namespace rc
