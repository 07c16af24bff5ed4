#include "relaxed_connectivity/render/splat/differential_renderer.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/render/splat/deferred_shader.h"
#include "relaxed_connectivity/render/splat/environment_map.h"
#include "relaxed_connectivity/render/splat/ewa_splat.h"
#include "relaxed_connectivity/render/splat/splat_rasterizer.h"
#include "relaxed_connectivity/render/splat/tile_passes_avx2.h"

namespace rc {

namespace {

using namespace splat_tile;
using Clock = std::chrono::steady_clock;
double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// One surfel of a delta, set up for this camera.
struct DeltaSplat {
  SplatRaster raster;
  SplatBlend blend;
  bool remove;
};

/// The set-up of surfel i exactly as SurfelRenderer draws it without a clipper (same functions, same
/// normal), so that un-splatting cancels what the full render splatted.
SplatSetup setupSurfel(const SurfelCloud& cloud, size_t i, const CameraFrame& frame, const EwaParams& params,
                       SplatRaster* raster, float unit_normal[3]) {
  if (!cloud.hasAxes())
    return setupCircularEwaSplat(cloud.positions[i], cloud.normals[i], cloud.radii[i], frame, params, raster,
                                 unit_normal);
  Vec3 normal, axis1, axis2;
  surfelFrame(cloud, i, &normal, &axis1, &axis2);
  const SplatSetup result =
      setupEwaSplat(cloud.positions[i], normal, axis1, axis2, frame, params, raster, nullptr);
  const Vec3 n = normal.normalized();
  for (int k = 0; k < 3; ++k) unit_normal[k] = float(n[k]);
  return result;
}

void checkDrawable(const SurfelCloud& cloud, const char* what) {
  cloud.validate();
  if (cloud.empty()) return;
  if (!cloud.hasAxes() && !(cloud.hasNormals() && cloud.hasRadii()))
    throw std::invalid_argument(std::string("DifferentialSurfelRenderer: ") + what +
                                " surfels need normals and radii, or tangent axes");
}

}  // namespace

void DifferentialRenderConfig::validate() const {
  if (splat.outputs & kOutputPatchId)
    throw std::invalid_argument("DifferentialRenderConfig: splat.outputs may not include the patch id image");
  if (max_tile_updates == 0)
    throw std::invalid_argument("DifferentialRenderConfig: max_tile_updates must be > 0");
  if (!(pose_tolerance >= 0) || !std::isfinite(pose_tolerance))
    throw std::invalid_argument("DifferentialRenderConfig: pose_tolerance must be >= 0");
}

const char* fullUpdateReasonName(FullUpdateReason reason) {
  switch (reason) {
    case FullUpdateReason::kNone:
      return "none";
    case FullUpdateReason::kFirstFrame:
      return "first_frame";
    case FullUpdateReason::kRequested:
      return "requested";
    case FullUpdateReason::kCameraMoved:
      return "camera_moved";
    case FullUpdateReason::kLargeDelta:
      return "large_delta";
    case FullUpdateReason::kPrecision:
      return "precision";
    case FullUpdateReason::kSettings:
      return "settings";
  }
  return "unknown";
}

DifferentialSurfelRenderer::DifferentialSurfelRenderer(const DifferentialRenderConfig& config)
    : config_(config), renderer_(config.splat) {
  config_.validate();
}

DifferentialSurfelRenderer::~DifferentialSurfelRenderer() = default;

void DifferentialSurfelRenderer::setSplatConfig(SplatConfig splat) {
  splat.outputs = config_.splat.outputs;
  splat.environment = config_.splat.environment;
  DifferentialRenderConfig changed = config_;
  changed.splat = splat;
  changed.validate();
  renderer_ = SurfelRenderer(splat);  // validates the splatting settings
  config_ = changed;
  valid_ = false;
  settings_changed_ = true;
}

void DifferentialSurfelRenderer::renderFull(const SurfelCloud& cloud, const Camera& camera,
                                            DifferentialStats* stats, FullUpdateReason reason) {
  const Clock::time_point start = Clock::now();
  valid_ = false;  // stays false if the render throws
  DifferentialStats local;
  renderer_.render(cloud, camera, &images_, nullptr, &local.full, &accumulation_);
  camera_ = camera;
  frame_ = std::make_unique<CameraFrame>(camera);
  tile_updates_.assign(size_t(accumulation_.tiles()), 0);
  valid_ = true;
  local.update = RenderUpdate::kFull;
  local.reason = reason;
  local.total_ms = millisecondsSince(start);
  if (stats) *stats = local;
}

bool DifferentialSurfelRenderer::cameraMoved(const Camera& camera) const {
  const Camera& c = camera_;
  if (camera.projection != c.projection || camera.width != c.width || camera.height != c.height ||
      camera.fx != c.fx || camera.fy != c.fy || camera.cx != c.cx || camera.cy != c.cy ||
      camera.ortho_scale != c.ortho_scale || camera.near_clip != c.near_clip || camera.far_clip != c.far_clip)
    return true;
  if (config_.pose_tolerance == 0) return !camera.world_T_camera.isApprox(c.world_T_camera, 0.0);
  const double translation = (camera.world_T_camera.translation() - c.world_T_camera.translation()).norm();
  const double angle =
      Eigen::AngleAxisd(camera.world_T_camera.linear().transpose() * c.world_T_camera.linear()).angle();
  return translation > config_.pose_tolerance || angle > config_.pose_tolerance;
}

void DifferentialSurfelRenderer::update(const SurfelCloud& cloud, const SurfelCloud& removed,
                                        const SurfelCloud& added, const Camera& camera,
                                        DifferentialStats* stats) {
  if (!valid_) {
    const FullUpdateReason reason =
        settings_changed_ ? FullUpdateReason::kSettings : FullUpdateReason::kFirstFrame;
    settings_changed_ = false;
    return renderFull(cloud, camera, stats, reason);
  }
  camera.validate();
  if (cameraMoved(camera)) return renderFull(cloud, camera, stats, FullUpdateReason::kCameraMoved);
  if (removed.size() + added.size() > config_.max_delta_surfels)
    return renderFull(cloud, camera, stats, FullUpdateReason::kLargeDelta);
  checkDrawable(removed, "removed");
  checkDrawable(added, "added");

  const Clock::time_point start = Clock::now();
  DifferentialStats local;
  local.update = RenderUpdate::kDifferential;
  const SplatConfig& sc = config_.splat;
  EwaParams params;
  params.ewa_filter = sc.ewa_filter;
  params.lowpass_variance = sc.lowpass_variance;
  params.cutoff_radius = sc.cutoff_radius;
  params.depth_tolerance_scale = sc.depth_tolerance_scale;
  params.backface_culling = sc.backface_culling;
  params.exact_footprint = sc.exact_footprint;

  // Set-up of the removed, then the added surfels (the order within a tile: un-splat first).
  const size_t n = removed.size() + added.size();
  std::vector<DeltaSplat> splats(n);
  std::vector<uint8_t> drawn(n, 0);
  const int threads = sc.threads > 0 ? sc.threads : omp_get_max_threads();
  const int setup_threads = n >= 2048 ? threads : 1;
  size_t invalid = 0;
  const Attribute* removed_reflectivity =
      sc.environment ? removed.attributes.find(kReflectivityAttribute) : nullptr;
  const Attribute* added_reflectivity =
      sc.environment ? added.attributes.find(kReflectivityAttribute) : nullptr;
#pragma omp parallel for num_threads(setup_threads) schedule(static) reduction(+ : invalid)
  for (size_t k = 0; k < n; ++k) {
    const bool remove = k < removed.size();
    const SurfelCloud& from = remove ? removed : added;
    const size_t i = remove ? k : k - removed.size();
    DeltaSplat& d = splats[k];
    d.remove = remove;
    const SplatSetup result = setupSurfel(from, i, *frame_, params, &d.raster, d.blend.normal);
    invalid += result == SplatSetup::kInvalid;
    if (result != SplatSetup::kDrawn && result != SplatSetup::kDrawnEdgeOn) continue;
    drawn[k] = 1;
    Rgba color = from.hasColors() ? from.colors[i] : sc.default_color;
    const Attribute* reflectivity = remove ? removed_reflectivity : added_reflectivity;
    if (reflectivity)  // as SurfelRenderer does it: the same camera gives the same colour
      color = reflectedColor(color, reflectivity->get(i), from.positions[i],
                             Vec3(d.blend.normal[0], d.blend.normal[1], d.blend.normal[2]), frame_->eye,
                             *sc.environment);
    for (int c = 0; c < 3; ++c) d.blend.color[c] = float(color[c]);
    d.blend.patch_id = 0;
  }
  local.invalid_surfels = invalid;

  // Binning into tiles, in splat order.
  const int tiles_x = accumulation_.tiles_x, tiles = accumulation_.tiles();
  std::vector<uint32_t> offsets(size_t(tiles) + 1, 0);
  auto forEachTile = [&](const SplatRaster& s, auto&& visit) {
    for (int ty = s.y0 / kTileSize; ty <= s.y1 / kTileSize; ++ty)
      for (int tx = s.x0 / kTileSize; tx <= s.x1 / kTileSize; ++tx) visit(ty * tiles_x + tx);
  };
  for (size_t k = 0; k < n; ++k) {
    if (!drawn[k]) continue;
    (splats[k].remove ? local.removed_splats : local.added_splats) += 1;
    forEachTile(splats[k].raster, [&](int tile) { ++offsets[size_t(tile) + 1]; });
  }
  std::vector<int> touched;
  for (int tile = 0; tile < tiles; ++tile) {
    if (offsets[size_t(tile) + 1] == 0) continue;
    touched.push_back(tile);
    if (tile_updates_[size_t(tile)] + offsets[size_t(tile) + 1] > config_.max_tile_updates)
      return renderFull(cloud, camera, stats, FullUpdateReason::kPrecision);
  }
  for (int tile = 0; tile < tiles; ++tile) offsets[size_t(tile) + 1] += offsets[size_t(tile)];
  std::vector<uint32_t> items(offsets.back());
  {
    std::vector<uint32_t> cursor(offsets.begin(), offsets.end() - 1);
    for (size_t k = 0; k < n; ++k)
      if (drawn[k])
        forEachTile(splats[k].raster, [&](int tile) { items[cursor[size_t(tile)]++] = uint32_t(k); });
  }
  local.setup_ms = millisecondsSince(start);

  // Un-splat and splat into the kept sums with the full render's visibility bounds, then normalise and shade
  // the touched tiles (Fig. 5.11, right).
  const Clock::time_point start_accumulate = Clock::now();
  const WeightTable add_table = makeWeightTable(sc.cutoff_radius, 1.0f);
  const WeightTable remove_table = makeWeightTable(sc.cutoff_radius, -1.0f);
  // What rounding leaves of a pixel's weight once all its fragments are gone: far below one fragment's.
  const float residual = 0.01f * add_table[kWeightTableSteps];
  const bool wide = sc.wide_simd && avx2TilePassesAvailable();
  // exact_silhouettes: the full render's test of fragments nearer than the front (a removed surfel takes
  // back what it added; an added one in front of the kept front shows where its own disc covers).
  const double cutoff_sigmas = sc.cutoff_radius / kKernelSigmaPerRadius;
  const double coverage_filter = cutoff_sigmas * cutoff_sigmas * sc.lowpass_variance;
  auto nearerFilter = [&](const SplatRaster& s) {
    return sc.exact_silhouettes ? conicFilterVariance(s, sc.ewa_filter, coverage_filter) : -1.0;
  };
  const DeferredShader shader(sc, *frame_);
  static const int32_t kNoPatch[kTileBufferSize] = {};
  SplatAccumulation& acc = accumulation_;
  size_t fragments = 0;
  const int tile_threads = touched.size() >= 4 ? threads : 1;
#pragma omp parallel num_threads(tile_threads) reduction(+ : fragments)
  {
#pragma omp for schedule(dynamic, 1)
    for (size_t t = 0; t < touched.size(); ++t) {
      const int tile = touched[t];
      const TileRect rect = acc.rect(tile);
      float* weight = acc.sum(tile, SplatAccumulation::kWeight);
      float* depth = acc.sum(tile, SplatAccumulation::kDepth);
      float *color[3], *normal[3];
      for (int c = 0; c < 3; ++c) {
        color[c] = acc.sum(tile, SplatAccumulation::Sum(SplatAccumulation::kColor0 + c));
        normal[c] = acc.sum(tile, SplatAccumulation::Sum(SplatAccumulation::kNormal0 + c));
      }
      const float* bound = acc.sum(tile, SplatAccumulation::kBound);
      const float* front = acc.sum(tile, SplatAccumulation::kFront);
      const TileSums sums{weight,
                          acc.has_depth ? depth : nullptr,
                          {acc.has_normal ? normal[0] : nullptr, normal[1], normal[2]},
                          {acc.has_color ? color[0] : nullptr, color[1], color[2]},
                          nullptr,
                          nullptr};
      for (uint32_t item = offsets[size_t(tile)]; item < offsets[size_t(tile) + 1]; ++item) {
        const DeltaSplat& d = splats[items[item]];
        const float* table = d.remove ? remove_table.data() : add_table.data();
        if (wide) {
          fragments += accumulateSplatAvx2(d.raster, rect, bound, front, d.blend, table, kWeightTableSteps,
                                           sums, nearerFilter(d.raster));
          continue;
        }
        const float tolerance = d.raster.depth_tolerance;
        NearerFragmentTest nearer(d.raster, nearerFilter(d.raster));
        rasterizeSplat(d.raster, rect, [&](int x, int y, float r2, float z) {
          const int i = (y - rect.y0) * kTileStride + x - rect.x0;
          if (z > bound[i] || z - tolerance > front[i]) return;
          if (nearer.active() && z + tolerance < front[i] && !nearer.covers(x, y)) return;
          const int step = std::min(kWeightTableSteps, int(std::max(r2, 0.0f) * kWeightTableSteps + 0.5f));
          const float w = table[step];
          weight[i] += w;
          if (acc.has_depth) depth[i] += w * z;
          for (int c = 0; c < 3 && acc.has_normal; ++c) normal[c][i] += w * d.blend.normal[c];
          for (int c = 0; c < 3 && acc.has_color; ++c) color[c][i] += w * d.blend.color[c];
          ++fragments;
        });
      }
      tile_updates_[size_t(tile)] += offsets[size_t(tile) + 1] - offsets[size_t(tile)];
      for (int y = rect.y0; y <= rect.y1; ++y) {
        const int row = (y - rect.y0) * kTileStride;
        for (int x = 0; x <= rect.x1 - rect.x0; ++x) {
          const int i = row + x;
          if (weight[i] >= residual) continue;
          weight[i] = 0;  // nothing left here: background, as in a full render
          if (acc.has_depth) depth[i] = 0;
          for (int c = 0; c < 3; ++c) {
            if (acc.has_color) color[c][i] = 0;
            if (acc.has_normal) normal[c][i] = 0;
          }
        }
        const AccumulatedSpan span = {weight + row,
                                      weight + row,
                                      depth + row,
                                      {color[0] + row, color[1] + row, color[2] + row},
                                      {normal[0] + row, normal[1] + row, normal[2] + row},
                                      kNoPatch + row};
        shader.shadeSpan(span, rect.x1 - rect.x0 + 1, rect.x0, y, &images_);
      }
    }
    shader.finish();
  }
  local.fragments = fragments;
  local.tiles = touched.size();
  local.accumulate_ms = millisecondsSince(start_accumulate);
  local.total_ms = millisecondsSince(start);
  if (stats) *stats = local;
}

}  // namespace rc
