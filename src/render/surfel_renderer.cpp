#include "render/surfel_renderer.h"

#include <omp.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "render/ewa_splat.h"

namespace rc {

namespace {

constexpr int kTileSize = 32;
constexpr int kTilePixels = kTileSize * kTileSize;
constexpr int kWeightTableSteps = 1024;    ///< Gaussian weight table over r2 in [0, 1]
constexpr size_t kSurfelsPerChunk = 4096;  ///< set-up/binning work unit (at most 8 per thread)
/// Splats whose box is at least this wide inside a tile solve each row's span; narrower ones test the
/// conic at every pixel of their box (no square root or division per row).
constexpr int kSpanMinWidth = 8;
#if defined(__SSE2__)
constexpr bool kSimd = true;  ///< unclipped splats are rasterized four pixels at a time
#else
constexpr bool kSimd = false;
#endif

using Clock = std::chrono::steady_clock;
double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

constexpr int kTileStride = kTileSize + 8;  ///< row stride of the tile buffers: room for a 4-wide overrun
constexpr int kTileBufferSize = kTileSize * kTileStride;
constexpr int kBlockSize = 8;  ///< occlusion culling granularity inside a tile
constexpr int kBlocksPerTile = kTileSize / kBlockSize;

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

  void clear() {
    std::fill_n(bound, kTileBufferSize, std::numeric_limits<float>::infinity());
    std::fill_n(front, kTileBufferSize, std::numeric_limits<float>::infinity());
    for (float* buffer : {weight, color_weight, depth, color[0], color[1], color[2], normal[0], normal[1],
                          normal[2], max_weight})
      std::fill_n(buffer, kTileBufferSize, 0.0f);
    std::fill_n(patch_id, kTileBufferSize, -1);
    std::fill_n(front_patch, kTileBufferSize, -1);
    for (float* buffer : front_normal) std::fill_n(buffer, kTileBufferSize, 0.0f);
  }
};

struct TileRect {
  int x0, y0, x1, y1;  ///< inclusive pixel range
};

struct ChunkCounts {
  size_t begin, end;  ///< surfel range
  uint32_t drawn = 0, edge_on = 0, invalid = 0, culled = 0, clipped = 0;
  uint32_t clip_offset = 0;  ///< first clip slot of this chunk
};

/// Calls visit(x, y, r2, z) for every pixel of the tile inside the cut-off ellipse of `s` (r2 <= 1), with
/// the clamped plane depth z. Coverage depends only on the splat and the tile, so both passes agree.
template <class Visit>
inline void rasterizeSplat(const SplatRaster& s, const TileRect& tile, Visit&& visit) {
  const int xb = std::max(int(s.x0), tile.x0), xe = std::min(int(s.x1), tile.x1);
  const int yb = std::max(int(s.y0), tile.y0), ye = std::min(int(s.y1), tile.y1);
  const float a = s.conic_a, b = s.conic_b, c = s.conic_c;
  const float n1 = s.depth_num[1], d1 = s.depth_den[0];
  const float z_lo = s.z_lo, z_hi = s.z_hi;
  const bool solve_span = xe - xb + 1 >= kSpanMinWidth;
  for (int y = yb; y <= ye; ++y) {
    const float dv = float(y) - s.center_v;
    const float r2_row = c * dv * dv, r2_cross = 2.0f * b * dv;
    int x_begin = xb, x_end = xe;
    if (solve_span) {  // roots of a du^2 + 2 b dv du + c dv^2 = 1, widened by a pixel (the r2 test decides)
      const float b_dv = b * dv;
      const float discriminant = b_dv * b_dv - a * (r2_row - 1.0f);
      if (!(discriminant >= 0)) continue;
      const float root = std::sqrt(discriminant), inv_a = 1.0f / a;
      const float u_lo = s.center_u + (-b_dv - root) * inv_a, u_hi = s.center_u + (-b_dv + root) * inv_a;
      x_begin = std::max(xb, int(std::max(u_lo, float(xb))) - 1);
      x_end = std::min(xe, int(std::min(u_hi, float(xe))) + 1);
    }
    const float num_row = s.depth_num[0] + s.depth_num[2] * dv;
    const float den_row = 1.0f + s.depth_den[1] * dv;
    for (int x = x_begin; x <= x_end; ++x) {
      const float du = float(x) - s.center_u;
      const float r2 = (a * du + r2_cross) * du + r2_row;
      if (r2 > 1.0f) continue;
      float z = (num_row + n1 * du) / (den_row + d1 * du);
      z = z > z_lo ? z : z_lo;  // also maps +-inf and NaN into the range
      z = z < z_hi ? z : z_hi;
      visit(x, y, r2, z);
    }
  }
}

#if defined(__SSE2__)
inline __m128 select(__m128 mask, __m128 if_true, __m128 if_false) {
  return _mm_or_ps(_mm_and_ps(mask, if_true), _mm_andnot_ps(mask, if_false));
}

/// rasterizeSplat four pixels at a time: visit(index, r2, z, mask) for each group of four pixels of a row
/// with at least one inside the cut-off (mask), index = tile buffer index of the first. Same arithmetic as
/// rasterizeSplat, so both give the same coverage, r2 and z.
template <class Visit>
inline void rasterizeSplat4(const SplatRaster& s, const TileRect& tile, Visit&& visit) {
  const int xb = std::max(int(s.x0), tile.x0), xe = std::min(int(s.x1), tile.x1);
  const int yb = std::max(int(s.y0), tile.y0), ye = std::min(int(s.y1), tile.y1);
  const float b = s.conic_b, c = s.conic_c;
  const __m128 lane = _mm_setr_ps(0, 1, 2, 3), one = _mm_set1_ps(1.0f);
  const __m128 a = _mm_set1_ps(s.conic_a), center_u = _mm_set1_ps(s.center_u);
  const __m128 n1 = _mm_set1_ps(s.depth_num[1]), d1 = _mm_set1_ps(s.depth_den[0]);
  const __m128 z_lo = _mm_set1_ps(s.z_lo), z_hi = _mm_set1_ps(s.z_hi);
  const bool solve_span = xe - xb + 1 >= kSpanMinWidth;
  for (int y = yb; y <= ye; ++y) {
    const float dv = float(y) - s.center_v;
    const float r2_row = c * dv * dv, r2_cross = 2.0f * b * dv;
    int x_begin = xb, x_end = xe;
    if (solve_span) {
      const float b_dv = b * dv;
      const float discriminant = b_dv * b_dv - s.conic_a * (r2_row - 1.0f);
      if (!(discriminant >= 0)) continue;
      const float root = std::sqrt(discriminant), inv_a = 1.0f / s.conic_a;
      const float u_lo = s.center_u + (-b_dv - root) * inv_a, u_hi = s.center_u + (-b_dv + root) * inv_a;
      x_begin = std::max(xb, int(std::max(u_lo, float(xb))) - 1);
      x_end = std::min(xe, int(std::min(u_hi, float(xe))) + 1);
    }
    const __m128 row = _mm_set1_ps(r2_row), cross = _mm_set1_ps(r2_cross);
    const __m128 num_row = _mm_set1_ps(s.depth_num[0] + s.depth_num[2] * dv);
    const __m128 den_row = _mm_set1_ps(1.0f + s.depth_den[1] * dv);
    const __m128 last = _mm_set1_ps(float(x_end));
    const int base = (y - tile.y0) * kTileStride - tile.x0;
    for (int x = x_begin; x <= x_end; x += 4) {
      const __m128 xs = _mm_add_ps(_mm_set1_ps(float(x)), lane);
      const __m128 du = _mm_sub_ps(xs, center_u);
      const __m128 r2 = _mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_mul_ps(a, du), cross), du), row);
      const __m128 mask = _mm_and_ps(_mm_cmple_ps(r2, one), _mm_cmple_ps(xs, last));
      if (!_mm_movemask_ps(mask)) continue;
      __m128 z = _mm_div_ps(_mm_add_ps(num_row, _mm_mul_ps(n1, du)), _mm_add_ps(den_row, _mm_mul_ps(d1, du)));
      z = _mm_min_ps(_mm_max_ps(z, z_lo), z_hi);  // max(NaN, lo) = lo
      visit(base + x, r2, z, mask);
    }
  }
}
#endif

/// With CSG clipping, a fragment of another patch than the pixel's front fragment blends only if its normal
/// is within acos(kCrossPatchBlendCosine) (about 25 deg) of the front normal: patches meet at sharp edges or
/// lie behind each other (a face behind a silhouette), but texture patches of one sheet (4.3) still blend.
constexpr float kCrossPatchBlendCosine = 0.9f;

#if defined(__SSE2__)
/// Lanes where `all` is set, `patch` equals the front patch, or the normals agree (kCrossPatchBlendCosine).
inline __m128 blendsWithFront(__m128 all, __m128 patch, const float normal[3], const TileBuffers& tb, int i) {
  const __m128i front = _mm_loadu_si128(reinterpret_cast<const __m128i*>(tb.front_patch + i));
  const float* const front_normal[3] = {tb.front_normal[0] + i, tb.front_normal[1] + i,
                                        tb.front_normal[2] + i};
  const __m128 same = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_castps_si128(patch), front));
  const __m128 cosine =
      _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(normal[0]), _mm_loadu_ps(front_normal[0])),
                            _mm_mul_ps(_mm_set1_ps(normal[1]), _mm_loadu_ps(front_normal[1]))),
                 _mm_mul_ps(_mm_set1_ps(normal[2]), _mm_loadu_ps(front_normal[2])));
  return _mm_or_ps(_mm_or_ps(all, same), _mm_cmpge_ps(cosine, _mm_set1_ps(kCrossPatchBlendCosine)));
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

Rgba toRgba(float r, float g, float b, uint8_t alpha) {
  auto channel = [](float value) { return uint8_t(std::clamp(std::lround(value), 0L, 255L)); };
  return {channel(r), channel(g), channel(b), alpha};
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
  if (!(config.light_direction_camera.norm() > 0)) fail("light_direction_camera must be non-zero");
}

/// Normal and tangent axes of surfel i as the renderer draws it (axes if present, else normal and radius).
void surfelFrame(const SurfelCloud& cloud, size_t i, Vec3* normal, Vec3* axis1, Vec3* axis2) {
  if (cloud.hasAxes()) {
    *axis1 = cloud.axes1[i];
    *axis2 = cloud.axes2[i];
    *normal = cloud.hasNormals() ? cloud.normals[i] : Vec3(axis1->cross(*axis2));
  } else {
    *normal = cloud.normals[i];
    const double length = normal->norm();
    if (length > 0 && std::isfinite(length)) {
      tangentAxes(*normal / length, cloud.radii[i], axis1, axis2);
    } else {
      *axis1 = *axis2 = Vec3::Zero();
    }
  }
}

}  // namespace

SurfelRenderer::SurfelRenderer(const SplatConfig& config) : config_(config) {
  validateConfig(config_);
}

void SurfelRenderer::render(const SurfelCloud& cloud, const Camera& camera, RenderImages* out,
                            const FragmentClipper* clipper, RenderStats* stats) const {
  const Clock::time_point start_total = Clock::now();
  if (!out) throw std::invalid_argument("SurfelRenderer::render: output images are null");
  validateConfig(config_);
  camera.validate();
  cloud.validate();
  if (!cloud.hasAxes() && !cloud.hasNormals())
    throw std::invalid_argument("SurfelRenderer::render: cloud has neither normals nor tangent axes");
  if (!cloud.hasAxes() && !cloud.hasRadii())
    throw std::invalid_argument("SurfelRenderer::render: cloud has neither radii nor tangent axes");
  const Attribute* patch_attribute = cloud.attributes.find("patch_id");
  if (camera.width > SplatRaster::kMaxImageSize || camera.height > SplatRaster::kMaxImageSize)
    throw std::invalid_argument("SurfelRenderer::render: image " + std::to_string(camera.width) + "x" +
                                std::to_string(camera.height) + " is larger than " +
                                std::to_string(SplatRaster::kMaxImageSize) + " pixels on a side");
  if (clipper && cloud.size() > SplatRaster::kClipSlotMask)
    throw std::invalid_argument("SurfelRenderer::render: too many surfels for clipping (" +
                                std::to_string(cloud.size()) + ")");

  // The renderer's scratch memory, or a temporary one while another thread renders with this renderer.
  std::unique_lock<std::mutex> workspace_lock(workspace_.mutex, std::try_to_lock);
  std::unique_ptr<SplatWorkspace> temporary_workspace;
  if (!workspace_lock.owns_lock()) temporary_workspace = std::make_unique<SplatWorkspace>();
  SplatWorkspace& ws = temporary_workspace ? *temporary_workspace : workspace_.workspace;

  const int threads = config_.threads > 0 ? config_.threads : omp_get_max_threads();
  const CameraFrame frame(camera);
  EwaParams params;
  params.ewa_filter = config_.ewa_filter;
  params.lowpass_variance = config_.lowpass_variance;
  params.cutoff_radius = config_.cutoff_radius;
  params.depth_tolerance_scale = config_.depth_tolerance_scale;
  params.backface_culling = config_.backface_culling;
  const int width = int(camera.width), height = int(camera.height);
  const size_t pixels = size_t(width) * height;
  const int tiles_x = (width + kTileSize - 1) / kTileSize, tiles_y = (height + kTileSize - 1) / kTileSize;
  const int tiles = tiles_x * tiles_y;

  // --- Set-up: per-surfel screen-space ellipse (double), stored as float raster records, compacted per
  // chunk of surfels, with per-chunk tile counts. ---
  const Clock::time_point start_setup = Clock::now();
  const size_t n = cloud.size();
  const size_t chunks =
      n == 0 ? 0 : std::min((n + kSurfelsPerChunk - 1) / kSurfelsPerChunk, size_t(8) * size_t(threads));
  std::vector<ChunkCounts> chunk_counts(chunks);
  for (size_t chunk = 0; chunk < chunks; ++chunk) {
    chunk_counts[chunk].begin = n * chunk / chunks;
    chunk_counts[chunk].end = n * (chunk + 1) / chunks;
  }
  ws.staged.reserve(n);
  ws.staged_shading.reserve(n);
  if (clipper) ws.clip_staged.reserve(n);
  ws.chunk_tile_counts.assign(chunks * size_t(tiles), 0);
  const bool circular = !cloud.hasAxes();

#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (size_t chunk = 0; chunk < chunks; ++chunk) {
    ChunkCounts counts = chunk_counts[chunk];  // local copy: no false sharing between threads
    SplatRaster* staged = ws.staged.data() + counts.begin;
    SplatShading* staged_shading = ws.staged_shading.data() + counts.begin;
    uint32_t* clip_staged = clipper ? ws.clip_staged.data() + counts.begin : nullptr;
    uint32_t* tile_counts = ws.chunk_tile_counts.data() + chunk * size_t(tiles);
    for (size_t i = counts.begin; i < counts.end; ++i) {
      if (clipper && !clipper->isVisible(uint32_t(i))) {
        ++counts.culled;
        continue;
      }
      SplatRaster& raster = staged[counts.drawn];
      SplatShading& shading = staged_shading[counts.drawn];
      SplatSetup result;
      if (circular) {
        result = setupCircularEwaSplat(cloud.positions[i], cloud.normals[i], cloud.radii[i], frame, params,
                                       &raster, shading.normal);
      } else {
        Vec3 normal, axis1, axis2;
        surfelFrame(cloud, i, &normal, &axis1, &axis2);
        result = setupEwaSplat(cloud.positions[i], normal, axis1, axis2, frame, params, &raster, nullptr);
        const Vec3 unit_normal = normal.normalized();
        for (int k = 0; k < 3; ++k) shading.normal[k] = float(unit_normal[k]);
      }
      if (clipper && clipper->flipsNormal(uint32_t(i)))  // cavity wall of a complemented patch (4.2)
        for (float& component : shading.normal) component = -component;
      if (result == SplatSetup::kInvalid) {
        ++counts.invalid;
        continue;
      }
      if (result == SplatSetup::kCulled) {
        ++counts.culled;
        continue;
      }
      counts.edge_on += result == SplatSetup::kDrawnEdgeOn;
      shading.color = cloud.hasColors() ? cloud.colors[i] : config_.default_color;
      shading.patch_id = patch_attribute ? int32_t(patch_attribute->get(i)) : 0;
      if (clipper && clipper->needsClipping(uint32_t(i))) {
        raster.flags |=
            clipper->clipsColorOnly(uint32_t(i)) ? SplatRaster::kClipColorOnly : SplatRaster::kClip;
        raster.flags |= counts.clipped;  // clip slot, chunk-local until binned
        clip_staged[counts.clipped++] = uint32_t(i);
      }
      forEachTileOfSplat(raster, tiles_x, [&](int tile) { ++tile_counts[tile]; });
      ++counts.drawn;
    }
    chunk_counts[chunk] = counts;
  }

  RenderStats local_stats;
  local_stats.surfels = n;
  uint32_t clip_count = 0;
  for (ChunkCounts& counts : chunk_counts) {
    local_stats.splats += counts.drawn;
    local_stats.edge_on_surfels += counts.edge_on;
    local_stats.invalid_surfels += counts.invalid;
    local_stats.culled_surfels += counts.culled;
    counts.clip_offset = clip_count;
    clip_count += counts.clipped;
  }

  // Surfels whose fragments are clipped keep their double-precision geometry (4.2.2).
  ws.clip_surfels.resize(clip_count);
  for (const ChunkCounts& counts : chunk_counts)
    std::copy_n(ws.clip_staged.data() + counts.begin, counts.clipped,
                ws.clip_surfels.data() + counts.clip_offset);
  ws.clip_geometry.resize(clip_count);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (size_t k = 0; k < clip_count; ++k) {
    const size_t i = ws.clip_surfels[k];
    Vec3 normal, axis1, axis2;
    surfelFrame(cloud, i, &normal, &axis1, &axis2);
    SplatRaster scratch;
    setupEwaSplat(cloud.positions[i], normal, axis1, axis2, frame, params, &scratch, &ws.clip_geometry[k]);
  }
  local_stats.setup_ms = millisecondsSince(start_setup);

  // --- Binning: record indices sorted by tile; chunk c of tile t follows chunks 0..c-1 of tile t, so every
  // tile lists its splats in ascending surfel order whatever the thread count. ---
  const Clock::time_point start_bin = Clock::now();
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
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (size_t chunk = 0; chunk < chunks; ++chunk) {
    const ChunkCounts& counts = chunk_counts[chunk];
    SplatRaster* staged = ws.staged.data();
    uint32_t* cursor = ws.chunk_tile_counts.data() + chunk * size_t(tiles);
    uint32_t* items = ws.bin_items.data();
    for (uint32_t k = uint32_t(counts.begin); k < counts.begin + counts.drawn; ++k) {
      SplatRaster& raster = staged[k];
      if (raster.flags & (SplatRaster::kClip | SplatRaster::kClipColorOnly))
        raster.flags += counts.clip_offset;
      forEachTileOfSplat(raster, tiles_x, [&](int tile) { items[cursor[tile]++] = k; });
    }
  }
  local_stats.bin_ms = millisecondsSince(start_bin);

  // True if the clipper keeps fragment (x, y) of a splat flagged kClip*.
  auto keeps = [&](const SplatRaster& s, int x, int y) {
    const uint32_t slot = s.clipSlot();
    return clipper->keepFragment(ws.clip_surfels[slot],
                                 fragmentWorldPoint(ws.clip_geometry[slot], frame, x, y));
  };

  std::array<float, kWeightTableSteps + 1> weight_table;
  const double cutoff_sigmas = config_.cutoff_radius / kKernelSigmaPerRadius;
  for (int k = 0; k <= kWeightTableSteps; ++k)
    weight_table[k] = float(std::exp(-0.5 * cutoff_sigmas * cutoff_sigmas * k / kWeightTableSteps));

  out->width = camera.width;
  out->height = camera.height;
  out->color.resize(pixels);
  out->depth.resize(pixels);
  out->normal.resize(pixels);
  out->weight.resize(pixels);
  out->patch_id.resize(pixels);

  const Eigen::Matrix3f camera_R_world = frame.camera_R_world.cast<float>();
  const Eigen::Vector3f to_light = (-config_.light_direction_camera.normalized()).cast<float>();
  const float ambient = float(config_.ambient), diffuse = float(config_.diffuse);
  const float specular = float(config_.specular), shininess = float(config_.shininess);
  const uint8_t alpha = config_.default_color[3];
  const float infinity = std::numeric_limits<float>::infinity();

  // --- Per tile: pass 1 (visibility, 3.2.2) finds per pixel the smallest z and the smallest z + eps_z over
  // all (unclipped) fragments; pass 2 (accumulation) blends the fragments with z <= that bound and
  // z - eps_z <= the smallest z (a large front surfel does not pull in small ones behind it); then the tile
  // is normalised and shaded (deferred Phong, two-sided: the normal is turned towards the viewer). --- With
  // CSG clipping, fragments of different patches meet only at (sharp) edges: a fragment blends only with the
  // patch of the pixel's front fragment, so a face behind a silhouette does not bleed in.
  const bool separate_patches = clipper != nullptr;
  size_t fragments = 0, clipped_fragments = 0;
  double visibility_ms = 0, accumulate_ms = 0, shade_ms = 0;
#pragma omp parallel num_threads(threads) reduction(+ : fragments, clipped_fragments, visibility_ms, \
                                                        accumulate_ms, shade_ms)
  {
    std::unique_ptr<TileBuffers> buffers(new TileBuffers);
    TileBuffers& tb = *buffers;
#pragma omp for schedule(dynamic, 1)
    for (int tile = 0; tile < tiles; ++tile) {
      const Clock::time_point start_tile = Clock::now();
      TileRect rect;
      rect.x0 = (tile % tiles_x) * kTileSize;
      rect.y0 = (tile / tiles_x) * kTileSize;
      rect.x1 = std::min(width, rect.x0 + kTileSize) - 1;
      rect.y1 = std::min(height, rect.y0 + kTileSize) - 1;
      const SplatRaster* staged = ws.staged.data();
      const SplatShading* staged_shading = ws.staged_shading.data();
      const uint32_t* items = ws.bin_items.data() + ws.tile_offsets[tile];
      const uint32_t splat_count = ws.tile_offsets[tile + 1] - ws.tile_offsets[tile];
      auto index = [&](int x, int y) { return (y - rect.y0) * kTileStride + x - rect.x0; };
      tb.clear();

      for (uint32_t k = 0; k < splat_count; ++k) {
        if (k + kPrefetchDistance < splat_count) __builtin_prefetch(staged + items[k + kPrefetchDistance]);
        const SplatRaster& s = staged[items[k]];
        const float tolerance = s.depth_tolerance;
        const SplatShading& front_shading = staged_shading[items[k]];
        const int32_t patch = front_shading.patch_id;
        const bool clip = (s.flags & SplatRaster::kClip) != 0;
        if (clip || !kSimd) {
          rasterizeSplat(s, rect, [&](int x, int y, float, float z) {
            if (clip && !keeps(s, x, y)) return;
            const int i = index(x, y);
            tb.bound[i] = std::min(tb.bound[i], z + tolerance);
            if (z < tb.front[i]) {
              tb.front[i] = z;
              tb.front_patch[i] = patch;
              for (int c = 0; c < 3; ++c) tb.front_normal[c][i] = front_shading.normal[c];
            }
          });
          continue;
        }
#if defined(__SSE2__)
        const __m128 tolerance4 = _mm_set1_ps(tolerance);
        const __m128 patch4 = _mm_castsi128_ps(_mm_set1_epi32(patch));
        rasterizeSplat4(s, rect, [&](int i, __m128, __m128 z, __m128 mask) {
          const __m128 b = _mm_loadu_ps(tb.bound + i), f = _mm_loadu_ps(tb.front + i);
          _mm_storeu_ps(tb.bound + i, select(mask, _mm_min_ps(b, _mm_add_ps(z, tolerance4)), b));
          const __m128 nearer = _mm_and_ps(mask, _mm_cmplt_ps(z, f));
          _mm_storeu_ps(tb.front + i, select(nearer, z, f));
          float* front_patches = reinterpret_cast<float*>(tb.front_patch + i);
          _mm_storeu_ps(front_patches, select(nearer, patch4, _mm_loadu_ps(front_patches)));
          for (int c = 0; c < 3; ++c) {
            float* front_normal = tb.front_normal[c] + i;
            _mm_storeu_ps(front_normal,
                          select(nearer, _mm_set1_ps(front_shading.normal[c]), _mm_loadu_ps(front_normal)));
          }
        });
#endif
      }
      // Largest bound per block: an unclipped splat whose nearest depth lies behind it everywhere in its box
      // has no visible fragment there (occlusion culling; exact, z >= z_lo).
      float block_max[kBlocksPerTile * kBlocksPerTile];
      for (int by = 0; by < kBlocksPerTile; ++by) {
        for (int bx = 0; bx < kBlocksPerTile; ++bx) {
          float largest = -infinity;
          for (int y = rect.y0 + by * kBlockSize;
               y <= std::min(rect.y1, rect.y0 + by * kBlockSize + kBlockSize - 1); ++y)
            for (int x = rect.x0 + bx * kBlockSize;
                 x <= std::min(rect.x1, rect.x0 + bx * kBlockSize + kBlockSize - 1); ++x)
              largest = std::max(largest, tb.bound[index(x, y)]);
          block_max[by * kBlocksPerTile + bx] = largest;
        }
      }
      auto occluded = [&](const SplatRaster& s) {
        const int bx0 = (std::max(int(s.x0), rect.x0) - rect.x0) / kBlockSize;
        const int bx1 = (std::min(int(s.x1), rect.x1) - rect.x0) / kBlockSize;
        const int by0 = (std::max(int(s.y0), rect.y0) - rect.y0) / kBlockSize;
        const int by1 = (std::min(int(s.y1), rect.y1) - rect.y0) / kBlockSize;
        for (int by = by0; by <= by1; ++by)
          for (int bx = bx0; bx <= bx1; ++bx)
            if (!(s.z_lo > block_max[by * kBlocksPerTile + bx])) return false;
        return true;
      };

      const Clock::time_point start_accumulate = Clock::now();
      visibility_ms += std::chrono::duration<double, std::milli>(start_accumulate - start_tile).count();

      for (uint32_t k = 0; k < splat_count; ++k) {
        if (k + kPrefetchDistance < splat_count)
          __builtin_prefetch(staged_shading + items[k + kPrefetchDistance]);
        const SplatRaster& s = staged[items[k]];
        if (!(s.flags & (SplatRaster::kClip | SplatRaster::kClipColorOnly)) && occluded(s)) continue;
        const SplatShading& attributes = staged_shading[items[k]];
        const struct {
          float normal[3], color[3];
          int32_t patch_id;
        } shading = {{attributes.normal[0], attributes.normal[1], attributes.normal[2]},
                     {float(attributes.color[0]), float(attributes.color[1]), float(attributes.color[2])},
                     attributes.patch_id};
        const bool clip = (s.flags & (SplatRaster::kClip | SplatRaster::kClipColorOnly)) != 0;
        const float tolerance = s.depth_tolerance;
        if (clip || !kSimd) {
          const bool color_only = (s.flags & SplatRaster::kClipColorOnly) != 0;
          rasterizeSplat(s, rect, [&](int x, int y, float r2, float z) {
            bool add_color = true;
            if (clip && !keeps(s, x, y)) {
              ++clipped_fragments;
              if (!color_only) return;
              add_color = false;
            }
            const int i = index(x, y);
            // Blend iff within the tolerance of the front surfel AND within this surfel's own tolerance of
            // the front depth: eps_z from both the pixel's and the incoming surfel (3.2.1).
            if (z > tb.bound[i] || z - tolerance > tb.front[i]) return;
            if (separate_patches && shading.patch_id != tb.front_patch[i] &&
                shading.normal[0] * tb.front_normal[0][i] + shading.normal[1] * tb.front_normal[1][i] +
                        shading.normal[2] * tb.front_normal[2][i] <
                    kCrossPatchBlendCosine)
              return;
            const int step = std::min(kWeightTableSteps, int(std::max(r2, 0.0f) * kWeightTableSteps + 0.5f));
            const float w = weight_table[step];
            tb.weight[i] += w;
            tb.depth[i] += w * z;
            for (int c = 0; c < 3; ++c) tb.normal[c][i] += w * shading.normal[c];
            if (add_color) {
              tb.color_weight[i] += w;
              for (int c = 0; c < 3; ++c) tb.color[c][i] += w * shading.color[c];
            }
            if (w > tb.max_weight[i]) {
              tb.max_weight[i] = w;
              tb.patch_id[i] = shading.patch_id;
            }
            ++fragments;
          });
          continue;
        }
#if defined(__SSE2__)
        const __m128 normal0 = _mm_set1_ps(shading.normal[0]), normal1 = _mm_set1_ps(shading.normal[1]),
                     normal2 = _mm_set1_ps(shading.normal[2]);
        const __m128 color0 = _mm_set1_ps(shading.color[0]), color1 = _mm_set1_ps(shading.color[1]),
                     color2 = _mm_set1_ps(shading.color[2]);
        const __m128 patch = _mm_castsi128_ps(_mm_set1_epi32(shading.patch_id));
        const __m128 steps = _mm_set1_ps(float(kWeightTableSteps)), half = _mm_set1_ps(0.5f);
        const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
        const __m128 tolerance4 = _mm_set1_ps(tolerance);
        const __m128 all_patches = separate_patches ? _mm_setzero_ps() : _mm_castsi128_ps(_mm_set1_epi32(-1));
        rasterizeSplat4(s, rect, [&](int i, __m128 r2, __m128 z, __m128 mask) {
          const __m128 pass =
              _mm_and_ps(_mm_and_ps(mask, _mm_cmple_ps(z, _mm_loadu_ps(tb.bound + i))),
                         _mm_and_ps(_mm_cmple_ps(_mm_sub_ps(z, tolerance4), _mm_loadu_ps(tb.front + i)),
                                    blendsWithFront(all_patches, patch, shading.normal, tb, i)));
          const int bits = _mm_movemask_ps(pass);
          if (!bits) return;
          fragments += kBitCount[bits];
          alignas(16) int32_t step[4];
          const __m128 clamped = _mm_min_ps(_mm_max_ps(r2, zero), one);
          _mm_store_si128(reinterpret_cast<__m128i*>(step),
                          _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(clamped, steps), half)));
          const __m128 w = _mm_and_ps(pass, _mm_setr_ps(weight_table[step[0]], weight_table[step[1]],
                                                        weight_table[step[2]], weight_table[step[3]]));
          auto add = [&](float* buffer, __m128 value) {
            _mm_storeu_ps(buffer + i, _mm_add_ps(_mm_loadu_ps(buffer + i), value));
          };
          add(tb.weight, w);
          add(tb.depth, _mm_mul_ps(w, z));
          add(tb.normal[0], _mm_mul_ps(w, normal0));
          add(tb.normal[1], _mm_mul_ps(w, normal1));
          add(tb.normal[2], _mm_mul_ps(w, normal2));
          add(tb.color_weight, w);
          add(tb.color[0], _mm_mul_ps(w, color0));
          add(tb.color[1], _mm_mul_ps(w, color1));
          add(tb.color[2], _mm_mul_ps(w, color2));
          const __m128 max_weight = _mm_loadu_ps(tb.max_weight + i);
          const __m128 larger = _mm_cmpgt_ps(w, max_weight);
          _mm_storeu_ps(tb.max_weight + i, select(larger, w, max_weight));
          float* patch_ids = reinterpret_cast<float*>(tb.patch_id + i);
          _mm_storeu_ps(patch_ids, select(larger, patch, _mm_loadu_ps(patch_ids)));
        });
#endif
      }
      const Clock::time_point start_shade = Clock::now();
      accumulate_ms += std::chrono::duration<double, std::milli>(start_shade - start_accumulate).count();

      // Normalise by the accumulated weights and shade.
      float view_x[kTileSize];  // view ray slope per column (perspective)
      for (int x = rect.x0; x <= rect.x1; ++x) view_x[x - rect.x0] = -float((x - frame.cx) / frame.fx);
      for (int y = rect.y0; y <= rect.y1; ++y) {
        const float view_y = -float((y - frame.cy) / frame.fy);
        for (int x = rect.x0; x <= rect.x1; ++x) {
          const int i = index(x, y);
          const size_t p = size_t(y) * width + x;
          const float weight = tb.weight[i];
          if (!(weight > 0)) {
            out->weight[p] = 0;
            out->depth[p] = infinity;
            out->normal[p].setZero();
            out->patch_id[p] = -1;
            out->color[p] = config_.background;
            continue;
          }
          out->weight[p] = weight;
          out->depth[p] = tb.depth[i] / weight;
          const Eigen::Vector3f blended(tb.normal[0][i], tb.normal[1][i], tb.normal[2][i]);
          const float length = blended.norm();
          out->normal[p] = length > 1e-20f ? Eigen::Vector3f(blended / length) : Eigen::Vector3f::Zero();
          out->patch_id[p] = tb.patch_id[i];
          const float color_weight = tb.color_weight[i];
          float base[3];
          for (int k = 0; k < 3; ++k)
            base[k] = color_weight > 0 ? tb.color[k][i] / color_weight : float(config_.default_color[k]);
          if (!config_.shading) {
            out->color[p] = toRgba(base[0], base[1], base[2], alpha);
            continue;
          }
          const Eigen::Vector3f to_eye =
              frame.perspective ? Eigen::Vector3f(view_x[x - rect.x0], view_y, -1.0f).normalized()
                                : Eigen::Vector3f(0, 0, -1);
          Eigen::Vector3f shading_normal = camera_R_world * out->normal[p];
          if (shading_normal.dot(to_eye) < 0) shading_normal = -shading_normal;
          const float lambert = std::max(0.0f, shading_normal.dot(to_light));
          float highlight = 0;
          if (lambert > 0) {
            const Eigen::Vector3f reflected = 2.0f * lambert * shading_normal - to_light;
            highlight = std::pow(std::max(0.0f, reflected.dot(to_eye)), shininess);
          }
          const float intensity = ambient + diffuse * lambert;
          const float added = 255.0f * specular * highlight;
          out->color[p] = toRgba(base[0] * intensity + added, base[1] * intensity + added,
                                 base[2] * intensity + added, alpha);
        }
      }
      shade_ms += millisecondsSince(start_shade);
    }
  }
  local_stats.fragments = fragments;
  local_stats.clipped_fragments = clipped_fragments;
  local_stats.visibility_ms = visibility_ms / threads;
  local_stats.accumulate_ms = accumulate_ms / threads;
  local_stats.shade_ms = shade_ms / threads;
  local_stats.total_ms = millisecondsSince(start_total);
  if (stats) *stats = local_stats;
}

}  // namespace rc
