#include "relaxed_connectivity/convert/texture_patches.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/render/splat/ewa_splat.h"
#include "relaxed_connectivity/render/splat/splat_rasterizer.h"

namespace rc {
namespace {

constexpr float kUnset = std::numeric_limits<float>::infinity();

/// Per-thread scratch of the patch splatter.
struct PatchScratch {
  std::vector<Neighbor> neighbors;
  std::vector<uint32_t> candidates;  // surfels that may reach the triangle's patch
  std::vector<SplatRaster> rasters;
  std::vector<uint32_t> raster_surfel;
  std::vector<float> bound, weight;
  std::vector<Eigen::Vector3f> sum;
  std::vector<unsigned char> filled;
};

struct SurfelData {
  const SurfelCloud* cloud;
  std::vector<Eigen::Vector3f> colors;   // [0, 1]
  std::vector<Eigen::Vector3f> normals;  // unit
  std::vector<float> area;               // of the disc [m^2]
  std::vector<float> spacing;            // distance to the nearest other surfel [m]
  double max_radius = 0;
  double depth_unit = 1;  // the median surfel radius [m]: the depth error's unit
};

/// The attribute a texture of this kind interpolates, of surfel j's fragment at `height` above the triangle
/// (depth: the height of the splat's disc there, not of its centre, so that curved surfaces keep their
/// shape between centres).
Eigen::Vector3f fragmentValue(TextureKind kind, const SurfelData& data, uint32_t j, float height) {
  switch (kind) {
    case TextureKind::kColor:
      return data.colors[j];
    case TextureKind::kNormal:
      return data.normals[j];
    case TextureKind::kDepth:
      break;
  }
  return Eigen::Vector3f(height, 0, 0);
}

bool insideTriangle2d(double x, double y, const PatchFrame& f) {
  // Base from (0, 0) to (base, 0), apex (apex_x, height); a small tolerance for centres on an edge.
  const double eps = 1e-9 * f.base;
  if (y < -eps || y > f.height + eps) return false;
  const double left = (f.apex_x * y - f.height * x),
               right = (f.height * (x - f.base) + (f.base - f.apex_x) * y);
  return left <= eps * f.height && right <= eps * f.height;
}

Eigen::Vector2d closestPointOnTriangle(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                                       const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
    return u.x() * v.y() - u.y() * v.x();
  };
  if (cross(b - a, p - a) >= 0 && cross(c - b, p - b) >= 0 && cross(a - c, p - c) >= 0)
    return p;  // (a, b, c ccw)
  Eigen::Vector2d best = a;
  double best_sq = std::numeric_limits<double>::infinity();
  for (const auto& [u, v] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
    const Eigen::Vector2d d = v - u;
    const double t = std::clamp((p - u).dot(d) / std::max(d.squaredNorm(), 1e-300), 0.0, 1.0);
    const Eigen::Vector2d q = u + t * d;
    if ((p - q).squaredNorm() < best_sq) best_sq = (p - q).squaredNorm(), best = q;
  }
  return best;
}

/// Calls use(k, raster, r2, z) for every splat whose cut-off ellipse covers the image point (u, v).
template <class Use>
void splatsAt(double u, double v, const PatchScratch& s, Use&& use) {
  for (size_t k = 0; k < s.rasters.size(); ++k) {
    const SplatRaster& r = s.rasters[k];
    if (u < r.x0 - 1.0 || u > r.x1 + 1.0 || v < r.y0 - 1.0 || v > r.y1 + 1.0) continue;
    const float du = float(u - r.center_u), dv = float(v - r.center_v);
    const float r2 = (r.conic_a * du + 2 * r.conic_b * dv) * du + r.conic_c * dv * dv;
    if (!(r2 <= 1.0f)) continue;
    use(k, r, r2, r.depthAt(du, dv));
  }
}

/// The visibility bound (nearest depth plus tolerance) at an image point; +inf where no splat covers it.
float depthBoundAt(double u, double v, const PatchScratch& s) {
  float bound = kUnset;
  splatsAt(u, v, s, [&](size_t, const SplatRaster& r, float, float z) {
    bound = std::min(bound, z + r.depth_tolerance);
  });
  return bound;
}

/// The weight-normalised reconstruction with visibility at one image point (u, v) (pixel coordinates):
/// adds the weights and weighted values of the visible splats there.
/// `depth`: the camera's height above the triangle (a fragment at depth z lies depth - z above it).
void reconstructAt(double u, double v, TextureKind kind, const SurfelData& data, double depth,
                   const splat_tile::WeightTable& weights, const PatchScratch& s, float* weight,
                   Eigen::Vector3f* sum) {
  const float bound = depthBoundAt(u, v, s);
  splatsAt(u, v, s, [&](size_t k, const SplatRaster&, float r2, float z) {
    if (z > bound) return;
    const uint32_t j = s.raster_surfel[k];
    const float w = weights[size_t(r2 * splat_tile::kWeightTableSteps)];
    *weight += w;
    *sum += w * fragmentValue(kind, data, j, float(depth - z));
  });
}

/// Splats the candidates into the patch raster at `texels_per_unit` and returns the patch with its error.
TexturePatch renderPatch(const PatchFrame& frame, double texels_per_unit, TextureKind kind, double depth,
                         const SurfelData& data, const TextureOptions& options,
                         const splat_tile::WeightTable& weights, PatchScratch& s) {
  const SurfelCloud& cloud = *data.cloud;
  TexturePatch patch;
  patch.texels_per_unit = texels_per_unit;
  patch.shape.base = frame.base * texels_per_unit;
  patch.shape.apex_x = frame.apex_x * texels_per_unit;
  patch.shape.height = frame.height * texels_per_unit;
  patch.origin = patchMaskOrigin(options.border);  // the packing mask's raster
  patch.width = int(std::ceil(patch.shape.base + 2 * patch.origin));
  patch.height = int(std::ceil(patch.shape.height + 2 * patch.origin));
  const int W = patch.width, H = patch.height;
  const size_t n = size_t(W) * size_t(H);

  // Orthographic view onto the triangle's plane from `depth` above it: camera x = the base, camera y = -the
  // frame's y (image row r is raster row H - 1 - r), camera z = -normal (the outer surface is in front).
  Camera camera;
  camera.projection = Camera::Projection::kOrthographic;
  camera.width = uint32_t(W);
  camera.height = uint32_t(H);
  camera.ortho_scale = texels_per_unit;
  camera.cx = patch.origin - 0.5;
  camera.cy = H - 0.5 - patch.origin;
  camera.near_clip = 0;
  camera.far_clip = 2 * depth;
  Eigen::Matrix3d rotation;
  rotation.col(0) = frame.x_axis;
  rotation.col(1) = -frame.y_axis;
  rotation.col(2) = -frame.normal;
  camera.world_T_camera.linear() = rotation;
  camera.world_T_camera.translation() = frame.origin + depth * frame.normal;
  const CameraFrame view(camera);
  // Texels sample the reconstructed function at their centres (no screen-space low-pass): the texture is
  // read back by bilinear interpolation, which (6.1) measures; a low-pass as wide as a coarse texel would
  // blend colours from beyond the triangle's edges into it.
  EwaParams params;
  params.ewa_filter = false;

  s.rasters.clear();
  s.raster_surfel.clear();
  // The raster's extent on the triangle's plane [m], grown by the largest splat: candidates outside it (the
  // candidate set serves the coarsest, widest raster) need no set-up.
  const double reach = data.max_radius;
  const double x_lo = -patch.origin / texels_per_unit - reach,
               x_hi = (W - patch.origin) / texels_per_unit + reach;
  const double y_lo = -patch.origin / texels_per_unit - reach,
               y_hi = (H - patch.origin) / texels_per_unit + reach;
  for (uint32_t j : s.candidates) {
    const Vec3 d = cloud.positions[j] - frame.origin;
    const double X = d.dot(frame.x_axis), Y = d.dot(frame.y_axis);
    if (X < x_lo || X > x_hi || Y < y_lo || Y > y_hi) continue;
    SplatRaster raster;
    SplatSetup setup;
    if (cloud.hasAxes()) {
      Vec3 normal, axis1, axis2;
      surfelFrame(cloud, j, &normal, &axis1, &axis2);
      setup = setupEwaSplat(cloud.positions[j], normal, axis1, axis2, view, params, &raster, nullptr);
    } else {
      setup =
          setupCircularEwaSplat(cloud.positions[j], cloud.normals[j], cloud.radii[j], view, params, &raster);
    }
    if (setup != SplatSetup::kDrawn && setup != SplatSetup::kDrawnEdgeOn) continue;
    s.rasters.push_back(raster);
    s.raster_surfel.push_back(j);
  }
  const splat_tile::TileRect rect{0, 0, W - 1, H - 1};
  // Pass 1, visibility splatting: the nearest depth (plus the surfel's tolerance) per pixel.
  s.bound.assign(n, kUnset);
  for (const SplatRaster& r : s.rasters)
    splat_tile::rasterizeSplat(r, rect, [&](int x, int y, float, float z) {
      float& b = s.bound[size_t(y) * W + x];
      b = std::min(b, z + r.depth_tolerance);
    });
  // Pass 2: weight-normalised accumulation of the fragments within the bound.
  s.weight.assign(n, 0.0f);
  s.sum.assign(n, Eigen::Vector3f::Zero());
  for (size_t k = 0; k < s.rasters.size(); ++k) {
    const SplatRaster& r = s.rasters[k];
    const uint32_t j = s.raster_surfel[k];
    splat_tile::rasterizeSplat(r, rect, [&](int x, int y, float r2, float z) {
      const size_t i = size_t(y) * W + x;
      if (z > s.bound[i]) return;
      const float w = weights[size_t(r2 * splat_tile::kWeightTableSteps)];
      s.weight[i] += w;
      s.sum[i] += w * fragmentValue(kind, data, j, float(depth - z));
    });
  }
  // Normalise into raster order (row 0 at the base). A texel whose centre lies outside the triangle takes
  // the reconstruction at the nearest point of the triangle (edge padding): bilinear filtering inside the
  // triangle then blends only colours of the triangle, however coarse the texels.
  patch.texels.assign(n, Eigen::Vector3f::Zero());
  s.filled.assign(n, 0);
  size_t covered = 0;
  const Eigen::Vector2d ta(patch.origin, patch.origin), tb(patch.origin + patch.shape.base, patch.origin),
      tc(patch.origin + patch.shape.apex_x, patch.origin + patch.shape.height);
  for (int r = 0; r < H; ++r)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(r) * W + x, o = size_t(H - 1 - r) * W + x;
      const Eigen::Vector2d centre(x + 0.5, H - r - 0.5);
      const Eigen::Vector2d q = closestPointOnTriangle(centre, ta, tb, tc);
      float weight = s.weight[i];
      Eigen::Vector3f sum = s.sum[i];
      if ((q - centre).squaredNorm() > 1e-12) {
        weight = 0;
        sum.setZero();
        reconstructAt(q.x() - 0.5, H - 0.5 - q.y(), kind, data, depth, weights, s, &weight, &sum);
      }
      if (weight > 0) {
        patch.texels[o] = sum / weight;
        if (kind == TextureKind::kNormal) patch.texels[o].normalize();
        s.filled[o] = 1;
        ++covered;
      }
    }
  patch.filled_texels = uint32_t(n - covered);
  if (covered == 0) {
    // No texel centre met a splat (texels coarser than the splats): refine, unless nothing reaches the
    // triangle at all (the caller then fills the patch from the nearest surfel).
    if (!s.rasters.empty()) patch.error = std::numeric_limits<double>::infinity();
    return patch;
  }
  for (size_t left = n - covered; left > 0;) {
    std::vector<std::pair<size_t, Eigen::Vector3f>> ring;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const size_t i = size_t(y) * W + x;
        if (s.filled[i]) continue;
        Eigen::Vector3f acc = Eigen::Vector3f::Zero();
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= W || yy >= H || !s.filled[size_t(yy) * W + xx]) continue;
            acc += patch.texels[size_t(yy) * W + xx];
            ++count;
          }
        if (count) ring.emplace_back(i, acc / float(count));
      }
    for (auto& [i, value] : ring) {
      patch.texels[i] = kind == TextureKind::kNormal ? value.normalized() : value;
      s.filled[i] = 1;
    }
    left -= ring.size();
  }

  // The error (6.1) over P_t: visible surfels whose centres lie on the triangle, weighted by their area. A
  // surfel is hidden when a splat in front (beyond its tolerance) covers its centre.
  double error_sum = 0, area_sum = 0;
  uint32_t members = 0;
  size_t next_raster = 0;
  for (uint32_t j : s.candidates) {
    const bool rasterized = next_raster < s.raster_surfel.size() && s.raster_surfel[next_raster] == j;
    const size_t k = rasterized ? next_raster++ : 0;
    const Vec3 d = cloud.positions[j] - frame.origin;
    const double X = d.dot(frame.x_axis), Y = d.dot(frame.y_axis);
    if (!insideTriangle2d(X, Y, frame)) continue;
    const double u = camera.cx + texels_per_unit * X, v = camera.cy - texels_per_unit * Y;
    float z_own, bound;
    if (rasterized) {  // its own splat covers the pixel nearest its centre: the bound there
      z_own = s.rasters[k].depth_num[0];
      const int x = std::clamp(int(std::lround(u)), 0, W - 1), y = std::clamp(int(std::lround(v)), 0, H - 1);
      bound = s.bound[size_t(y) * W + x];
    } else {  // a splat between texel centres: the splats covering its centre decide
      z_own = float(depth - d.dot(frame.normal));
      bound = depthBoundAt(u, v, s);
    }
    if (z_own > bound) continue;
    const Eigen::Vector3f t =
        sampleBilinear(patch, patch.origin + X * texels_per_unit, patch.origin + Y * texels_per_unit);
    double e;
    if (kind == TextureKind::kColor) {
      e = (data.colors[j] - t).norm();  // L2 in RGB (6.1)
    } else if (kind == TextureKind::kNormal) {
      const float length = t.norm();
      e = length > 0 ? 1.0 - double(data.normals[j].dot(t / length)) : 1.0;  // (6.2)
    } else {
      e = std::abs(d.dot(frame.normal) - double(t.x())) / data.depth_unit;  // the centre's height
    }
    error_sum += data.area[j] * e;
    area_sum += data.area[j];
    ++members;
  }
  patch.surfels = members;
  patch.error = area_sum > 0 ? error_sum / area_sum : 0.0;
  return patch;
}

double minSpacingOnTriangle(const PatchFrame& frame, const SurfelData& data, const PatchScratch& s) {
  double d_min = std::numeric_limits<double>::infinity();
  for (uint32_t j : s.candidates) {
    const Vec3 d = data.cloud->positions[j] - frame.origin;
    if (insideTriangle2d(d.dot(frame.x_axis), d.dot(frame.y_axis), frame))
      d_min = std::min(d_min, double(data.spacing[j]));
  }
  return d_min;
}

/// The refinement loop of 6.2.1 for one texture of one triangle, from `start_tpu` texels per unit (0: the
/// coarsest patch).
TexturePatch refinePatch(const PatchFrame& frame, TextureKind kind, double threshold, double depth,
                         const SurfelData& data, const TextureOptions& options,
                         const splat_tile::WeightTable& weights, PatchScratch& s, double start_tpu = 0) {
  const double d_min = minSpacingOnTriangle(frame, data, s);
  const double finest = std::min(options.max_base_texels / frame.base,
                                 std::isfinite(d_min) && d_min > 0 ? 2 * std::sqrt(2.0) / d_min
                                                                   : std::numeric_limits<double>::infinity());
  double tpu = std::min(start_tpu > 0 ? start_tpu : options.start_base_texels / frame.base, finest);
  for (int step = 1;; ++step) {
    TexturePatch patch = renderPatch(frame, tpu, kind, depth, data, options, weights, s);
    patch.steps = step;
    patch.refined_texels_per_unit = tpu;
    if (patch.error <= threshold) return patch;
    const double next = std::min(tpu * options.refinement_factor, finest);
    if (!(next > tpu * (1 + 1e-9))) {
      patch.at_resolution_limit = true;
      return patch;
    }
    tpu = next;
  }
}

void fillEmpty(TexturePatch* patch, const Eigen::Vector3f& value) {
  patch->texels.assign(size_t(patch->width) * size_t(patch->height), value);
  patch->filled_texels = uint32_t(patch->texels.size());
}

}  // namespace

PatchFrame patchFrame(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const std::array<Eigen::Vector3d, 3> v = {a, b, c};
  const int k = longestEdge(v);  // the base, as PatchShape::ofTriangle takes it
  const double longest = (v[(k + 1) % 3] - v[k]).norm();
  PatchFrame f;
  f.corner = {k, (k + 1) % 3, (k + 2) % 3};
  f.origin = v[k];
  f.base = longest;
  f.x_axis = (v[(k + 1) % 3] - v[k]) / longest;
  f.normal = (b - a).cross(c - a).normalized();
  f.y_axis = f.normal.cross(f.x_axis);
  const Eigen::Vector3d apex = v[(k + 2) % 3] - f.origin;
  f.apex_x = std::clamp(apex.dot(f.x_axis), 0.0, longest);
  f.height = apex.dot(f.y_axis);
  return f;
}

Eigen::Vector3f sampleBilinear(const TexturePatch& patch, double x, double y) {
  return bilinear(patch.width, patch.height, x, y,
                  [&](int i, int j) { return patch.texels[size_t(j) * size_t(patch.width) + size_t(i)]; });
}

Eigen::Vector2d rasterCoordinates(const TexturePatch& patch, const PatchFrame& frame,
                                  const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - frame.origin;
  return Eigen::Vector2d(patch.origin + d.dot(frame.x_axis) * patch.texels_per_unit,
                         patch.origin + d.dot(frame.y_axis) * patch.texels_per_unit);
}

std::vector<TrianglePatches> computeTexturePatches(const TriangleMesh& mesh, const SurfelCloud& surfels,
                                                   const TextureOptions& options, TextureStats* stats,
                                                   const StageProgress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  if (surfels.empty()) throw std::invalid_argument("computeTexturePatches: no surfels");
  if (!surfels.hasNormals() || (!surfels.hasRadii() && !surfels.hasAxes()))
    throw std::invalid_argument("computeTexturePatches: the surfels need normals and radii (or axes)");
  if (!(options.color_error >= 0) || !(options.normal_error >= 0) || !(options.depth_error >= 0) ||
      !(options.start_base_texels > 0) || !(options.refinement_factor > 1) ||
      !(options.max_base_texels >= options.start_base_texels) || options.border < 0 ||
      !(options.projection_depth >= 0))
    throw std::invalid_argument(
        "computeTexturePatches: bad options (errors >= 0, start_base_texels > 0, refinement_factor > 1, "
        "max_base_texels >= start_base_texels, border >= 0, projection_depth >= 0)");
  const size_t N = surfels.size();
  SurfelData data;
  data.cloud = &surfels;
  data.colors.resize(N, Eigen::Vector3f::Ones());
  data.area.resize(N);
  data.normals.resize(N);
  std::vector<double> radii(N);
  for (size_t i = 0; i < N; ++i) {
    if (!surfels.positions[i].allFinite() || !surfels.normals[i].allFinite() ||
        !(surfels.normals[i].norm() > 0))
      throw std::invalid_argument("computeTexturePatches: surfel " + std::to_string(i) +
                                  " has a non-finite position or a zero or non-finite normal");
    data.normals[i] = surfels.normals[i].normalized().cast<float>();
    double r1, r2;
    if (surfels.hasAxes()) {
      r1 = surfels.axes1[i].norm();
      r2 = surfels.axes2[i].norm();
    } else {
      r1 = r2 = surfels.radii[i];
    }
    if (!std::isfinite(r1) || !std::isfinite(r2) || r1 < 0 || r2 < 0)
      throw std::invalid_argument("computeTexturePatches: surfel " + std::to_string(i) + " has a bad radius");
    data.area[i] = float(M_PI * r1 * r2);
    radii[i] = std::max(r1, r2);
    data.max_radius = std::max(data.max_radius, radii[i]);
    if (surfels.hasColors())
      data.colors[i] =
          Eigen::Vector3f(surfels.colors[i][0], surfels.colors[i][1], surfels.colors[i][2]) / 255.0f;
  }
  const KdTree tree(surfels.positions);
  const std::vector<double> spacing = tree.kthNeighborDistances(1);
  data.spacing.assign(spacing.begin(), spacing.end());
  std::vector<double> sorted = radii;
  std::nth_element(sorted.begin(), sorted.begin() + long(N / 2), sorted.end());
  const double median_radius = sorted[N / 2];
  data.depth_unit = median_radius > 0 ? median_radius : 1.0;
  double depth = options.projection_depth;
  if (depth == 0) {
    Vec3 lo, hi;
    surfels.bounds(&lo, &hi);
    depth = std::max(4 * median_radius, 0.01 * (hi - lo).norm());
  }

  const size_t T = mesh.triangles.size();
  std::vector<PatchFrame> frames(T);
  for (size_t t = 0; t < T; ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (uint32_t k : tri)
      if (k >= mesh.vertices.size())
        throw std::invalid_argument("computeTexturePatches: triangle " + std::to_string(t) +
                                    " indexes a vertex that does not exist");
    frames[t] = patchFrame(mesh.vertices.positions[tri[0]], mesh.vertices.positions[tri[1]],
                           mesh.vertices.positions[tri[2]]);
    if (!(frames[t].height > 0) || !(frames[t].base > 0) || !frames[t].normal.allFinite())
      throw std::invalid_argument("computeTexturePatches: triangle " + std::to_string(t) +
                                  " is degenerate (zero area) or not finite");
  }

  const splat_tile::WeightTable weights = splat_tile::makeWeightTable(EwaParams().cutoff_radius);
  std::vector<TrianglePatches> out(T);
  std::atomic<size_t> done{0};
  std::atomic<bool> cancelled{false};
  size_t reported = 0;
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
#pragma omp parallel num_threads(threads)
  {
    PatchScratch s;
#pragma omp for schedule(dynamic, 8)
    for (size_t t = 0; t < T; ++t) {
      if (cancelled.load(std::memory_order_relaxed)) continue;
      const PatchFrame& f = frames[t];
      // Candidates: surfels whose discs can reach the coarsest raster, near the plane, facing its side.
      const Vec3 centroid = f.origin + (f.base / 3 + f.apex_x / 3) * f.x_axis + f.height / 3 * f.y_axis;
      const double reach =
          std::max({(f.origin - centroid).norm(), (f.origin + f.base * f.x_axis - centroid).norm(),
                    (f.origin + f.apex_x * f.x_axis + f.height * f.y_axis - centroid).norm()});
      const double margin = (options.border + 2.0) * f.base / options.start_base_texels;
      tree.radius(centroid, reach + margin + data.max_radius + depth, s.neighbors);
      s.candidates.clear();
      for (const Neighbor& nb : s.neighbors) {
        const Vec3 d = surfels.positions[nb.index] - f.origin;
        if (std::abs(d.dot(f.normal)) <= depth && surfels.normals[nb.index].dot(f.normal) > 0)
          s.candidates.push_back(nb.index);
      }
      std::sort(s.candidates.begin(), s.candidates.end());  // deterministic splat order
      TrianglePatches& p = out[t];
      p.frame = f;
      p.color = refinePatch(f, TextureKind::kColor, options.color_error, depth, data, options, weights, s);
      // One layout for all textures (one set of texture coordinates): the finest resolution of them. The
      // error is not monotone in the resolution (6.1 compares with a reconstruction that does not
      // interpolate), so a texture taken to a finer resolution is refined on from there when it exceeds its
      // threshold, and the others follow, until all agree.
      struct Texture {
        TexturePatch* patch;
        TextureKind kind;
        double threshold;
      };
      std::vector<Texture> textures = {{&p.color, TextureKind::kColor, options.color_error}};
      if (options.normal_texture) textures.push_back({&p.normal, TextureKind::kNormal, options.normal_error});
      if (options.depth_texture) textures.push_back({&p.depth, TextureKind::kDepth, options.depth_error});
      for (size_t k = 1; k < textures.size(); ++k)
        *textures[k].patch =
            refinePatch(f, textures[k].kind, textures[k].threshold, depth, data, options, weights, s);
      auto finest = [&] {
        double tpu = 0;
        for (const Texture& x : textures) tpu = std::max(tpu, x.patch->texels_per_unit);
        return tpu;
      };
      for (int round = 0; round < 4; ++round) {
        const double finer_tpu = finest();
        bool agreed = true;
        for (const Texture& x : textures) {
          TexturePatch& coarser = *x.patch;
          if (coarser.texels_per_unit == finer_tpu) continue;
          agreed = false;
          const int steps = coarser.steps;
          const double refined = coarser.refined_texels_per_unit;
          coarser = refinePatch(f, x.kind, x.threshold, depth, data, options, weights, s, finer_tpu);
          coarser.steps += steps;
          if (coarser.texels_per_unit == finer_tpu) coarser.refined_texels_per_unit = refined;
        }
        if (agreed) break;
      }
      const double layout_tpu = finest();
      for (const Texture& x : textures) {  // (rounds exhausted: the coarser ones resampled as they are)
        TexturePatch& coarser = *x.patch;
        if (coarser.texels_per_unit == layout_tpu) continue;
        TexturePatch resampled = renderPatch(f, layout_tpu, x.kind, depth, data, options, weights, s);
        resampled.steps = coarser.steps;
        resampled.refined_texels_per_unit = coarser.refined_texels_per_unit;
        resampled.at_resolution_limit = coarser.at_resolution_limit;
        coarser = std::move(resampled);
      }
      // A patch no splat reached: the nearest surfel's colour, the triangle's normal, its plane.
      if (p.color.filled_texels == p.color.texels.size()) {
        Neighbor nb;
        tree.knn(centroid, 1, &nb);
        fillEmpty(&p.color, data.colors[nb.index]);
      }
      if (options.normal_texture && p.normal.filled_texels == p.normal.texels.size())
        fillEmpty(&p.normal, f.normal.cast<float>());
      if (options.depth_texture && p.depth.filled_texels == p.depth.texels.size())
        fillEmpty(&p.depth, Eigen::Vector3f::Zero());
      const size_t finished = ++done;
      if (progress && omp_get_thread_num() == 0 && finished >= reported + std::max<size_t>(1, T / 100)) {
        reported = finished;
        if (!progress(double(finished) / double(T))) cancelled = true;
      }
    }
  }
  if (cancelled || (progress && !progress(1.0))) throw ConversionCancelled("textures");
  if (stats) {
    *stats = TextureStats();
    stats->triangles = T;
    stats->projection_depth = depth;
    stats->depth_unit = data.depth_unit;
    for (const TrianglePatches& p : out) {
      stats->texels += p.color.texels.size();
      auto refinedTexels = [&](const TexturePatch& t) {
        const double o = t.origin, tpu = t.refined_texels_per_unit;
        return t.texels.empty()
                   ? 0.0
                   : std::ceil(p.frame.base * tpu + 2 * o) * std::ceil(p.frame.height * tpu + 2 * o);
      };
      stats->color_refined_texels += size_t(refinedTexels(p.color));
      stats->normal_refined_texels += size_t(refinedTexels(p.normal));
      stats->depth_refined_texels += size_t(refinedTexels(p.depth));
      stats->at_resolution_limit += p.color.at_resolution_limit;
      stats->empty_patches += p.color.filled_texels == p.color.texels.size();
    }
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return out;
}

}  // namespace rc
