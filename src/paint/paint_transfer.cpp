#include "relaxed_connectivity/paint/paint_transfer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "relaxed_connectivity/paint/paint_buffer.h"

namespace rc {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

/// Where a splatted surface sample lives in the PaintSurface.
struct SurfaceRef {
  uint32_t original;
  int32_t child;  ///< -1: the original itself
};

/// The bristle pattern of viscous paint (5.6.3) for one buffer.
struct Imprint {
  bool active = false;
  Vec3 tip = Vec3::Zero(), across = Vec3::UnitX();  ///< pattern origin, unit direction across the stroke
  double depth = 0, spacing = 1;
};

/// Active while the device moves along the bristles' direction (both projected into the buffer plane).
Imprint imprintAt(const Brush& brush, const Vec3& tip, const Vec3& normal, const PaintType& paint,
                  const PaintTransferOptions& o) {
  Imprint imprint;
  if (!(paint.imprint_depth > 0)) return imprint;
  const BrushSkeleton& skeleton = brush.skeleton();
  Vec3 handle = Vec3::Zero(), velocity = Vec3::Zero();
  for (int i = 0; i < skeleton.handleCount(); ++i)
    handle += skeleton.positions()[size_t(i)], velocity += skeleton.velocities()[size_t(i)];
  handle /= skeleton.handleCount();
  velocity /= skeleton.handleCount();
  const auto in_plane = [&](const Vec3& v) -> Vec3 { return v - normal.dot(v) * normal; };
  const Vec3 bristles = in_plane(tip - handle), motion = in_plane(velocity);
  if (motion.norm() < o.imprint_min_speed || bristles.norm() < 1e-9) return imprint;
  if (std::abs(bristles.normalized().dot(motion.normalized())) < o.imprint_min_alignment) return imprint;
  imprint.active = true;
  imprint.tip = tip;
  imprint.across = normal.cross(bristles).normalized();
  imprint.depth = paint.imprint_depth;
  imprint.spacing = paint.imprint_spacing;
  return imprint;
}

/// Raises a new surfel above its father's tangent plane by the pattern (so that repeated events do not
/// accumulate) and tilts its normal by the pattern's slope.
void carve(const Imprint& imprint, const Vec3& father_position, const Vec3& father_normal,
           ChildSurfel& child) {
  const Vec3 on_plane = child.position - father_normal.dot(child.position - father_position) * father_normal;
  const double phase = 2 * M_PI * imprint.across.dot(on_plane - imprint.tip) / imprint.spacing;
  const double height = 0.5 * imprint.depth * (1 + std::cos(phase));
  const double slope = -0.5 * imprint.depth * (2 * M_PI / imprint.spacing) * std::sin(phase);
  child.position = on_plane + height * father_normal;
  child.normal = (father_normal - slope * imprint.across).normalized();
}

/// One tip's paint buffer: plane, extent, splats, exchange, resampling, gather.
void transferAtTip(const std::vector<int>& skin_samples, const Vec3& tip, const Vec3& tip_normal,
                   Brush& brush, PaintSurface& surface, const PaintType& paint, double dt,
                   const PaintTransferOptions& o, PaintEventStats* stats) {
  const Clock::time_point start = Clock::now();
  BrushSkin& skin = brush.skin();
  const double pixel = paintBufferPixel(o, brush.preset());
  const double reach = brush.preset().bristle_length;
  // (5.5) The least-squares plane of the object around the tip.
  std::vector<uint32_t> near;
  surface.originalsWithin(tip, 0.5 * reach, near);
  if (near.size() < 3) return;
  std::vector<Vec3> points;
  for (uint32_t i : near) points.push_back(surface.originals().positions[i]);
  Vec3 centre, normal;
  PaintBuffer::fitPlane(points, tip_normal, &centre, &normal);
  // The buffer covers the skin surfels of this tip that reach below the plane (plus a margin).
  Vec3 low_centre = Vec3::Zero();
  std::vector<int> low;
  for (int i : skin_samples) {
    const double h = normal.dot(skin.positions()[size_t(i)] - centre);
    if (h < skin.radius()) low.push_back(i), low_centre += skin.positions()[size_t(i)];
  }
  if (low.empty()) return;
  low_centre /= double(low.size());
  low_centre -= normal.dot(low_centre - centre) * normal;  // onto the plane
  double half = 0;
  for (int i : low) {
    const Vec3 d = skin.positions()[size_t(i)] - low_centre;
    half = std::max(half, (d - normal.dot(d) * normal).norm());
  }
  half = std::min(half + skin.radius() + o.margin_pixels * pixel, 0.5 * o.max_extent);
  const int side = std::max(1, int(std::ceil(2 * half / pixel)));
  PaintBuffer buffer(low_centre, normal, pixel, side, side);

  // The object's active surfels near the buffer (children lie near their fathers).
  std::vector<PaintSample> surface_samples;
  std::vector<SurfaceRef> refs;
  surface.originalsWithin(low_centre, half * std::sqrt(2.0) + 4 * surface.typicalRadius(), near);
  for (uint32_t i : near) {
    const SurfelCloud& originals = surface.originals();
    if (surface.enabled(i)) {
      PaintSample s;
      s.position = originals.positions[i];
      s.normal = originals.normals[i];
      s.radius = originals.hasRadii() ? originals.radii[i] : surface.typicalRadius();
      s.paint = std::as_const(surface).originalPaint(i);
      surface_samples.push_back(s);
      refs.push_back({i, -1});
    }
    const std::vector<ChildSurfel>& children = std::as_const(surface).children(i);
    for (size_t k = 0; k < children.size(); ++k) {
      surface_samples.push_back(
          {children[k].position, children[k].normal, children[k].radius, children[k].paint});
      refs.push_back({i, int32_t(k)});
    }
  }
  std::vector<PaintSample> brush_samples;
  for (int i : skin_samples)
    brush_samples.push_back(
        {skin.positions()[size_t(i)], skin.normals()[size_t(i)], skin.radius(), skin.paint[size_t(i)]});
  if (paint.eraser)  // deposits nothing, whatever rate the skin's surfels carry
    for (PaintSample& b : brush_samples) b.paint.transfer_rate = 0;

  buffer.splat(PaintBuffer::kSurface, surface_samples);
  buffer.splat(PaintBuffer::kBrush, brush_samples);
  const Clock::time_point splatted = Clock::now();
  stats->buffer_seconds += std::chrono::duration<double>(splatted - start).count();
  // The eraser deposits nothing; its transfer_to_surface restores the object's colour below.
  const PaintTransferStats t = buffer.transfer(paint.eraser ? 0.0 : paint.transfer_to_surface,
                                               paint.transfer_to_brush, o.pressure_per_depth, dt);
  const Clock::time_point exchanged = Clock::now();
  stats->exchange_seconds += std::chrono::duration<double>(exchanged - splatted).count();
  ++stats->buffers;
  stats->penetrated_pixels += t.penetrated_pixels;
  stats->moved_to_surface += t.moved_to_surface;
  stats->moved_to_brush += t.moved_to_brush;
  if (t.penetrated_pixels == 0) return;

  // Brush: gathered back (the brush is not resampled, 5.5).
  std::vector<PaintState> brush_states;
  for (const PaintSample& s : brush_samples) brush_states.push_back(s.paint);
  buffer.gather(PaintBuffer::kBrush, brush_states);
  for (size_t k = 0; k < skin_samples.size(); ++k) {
    PaintState& kept = skin.paint[size_t(skin_samples[k])];
    brush_states[k].transfer_rate = kept.transfer_rate;  // (the eraser's 0 was for this event only)
    kept = brush_states[k];
  }

  // Surface: kept samples take their paint back; the penetrated ones are replaced by pixel surfels.
  const std::vector<uint8_t> replace = buffer.penetratedSurfaceSamples();
  std::vector<PaintState> states;
  for (const PaintSample& s : surface_samples) states.push_back(s.paint);
  std::vector<PixelSurfel> pixels;
  buffer.resample(replace, states, pixels);
  for (size_t k = 0; k < refs.size(); ++k) {
    if (replace[k]) continue;
    if (refs[k].child < 0)
      surface.originalPaint(refs[k].original) = states[k];
    else
      surface.children(refs[k].original)[size_t(refs[k].child)].paint = states[k];
  }
  // Deleted children go from the back of each list so that the other indices stay valid.
  for (size_t k = refs.size(); k-- > 0;) {
    if (!replace[k]) continue;
    if (refs[k].child < 0) {
      surface.setEnabled(refs[k].original, false);
      ++stats->originals_disabled;
    } else {
      surface.removeChild(refs[k].original, size_t(refs[k].child));
      ++stats->children_removed;
    }
  }
  const Imprint imprint = imprintAt(brush, tip, normal, paint, o);
  for (const PixelSurfel& p : pixels) {
    ChildSurfel child{p.position, p.normal, p.radius, p.paint};
    const uint32_t father = surface.closestOriginal(p.position);
    surface.keepAsChild(father);           // a kept original next to the new surfels: its paint is not lost
    if (paint.eraser && p.pressure > 0) {  // (5.9)'s rate, towards the object's own colour
      const double f = 1.0 - std::exp(-paint.transfer_to_surface * p.pressure * dt);
      child.paint.dry = PaintColour::mix(child.paint.dry, 1.0 - f, surface.baseColour(father), f);
    }
    if (imprint.active && p.pressure > 0) {
      carve(imprint, surface.originals().positions[father], surface.originals().normals[father], child);
      ++stats->children_imprinted;
    }
    surface.addChild(father, child);
    ++stats->children_added;
  }
  stats->resample_seconds += secondsSince(exchanged);
}

}  // namespace

void PaintTransferOptions::validate() const {
  if (!(pixel_size >= 0) || !std::isfinite(pixel_size))
    throw std::invalid_argument("paint transfer: pixel_size must be >= 0 (0: the brush's surfel spacing)");
  if (!(pressure_per_depth >= 0) || !std::isfinite(pressure_per_depth))
    throw std::invalid_argument("paint transfer: pressure_per_depth must be >= 0");
  if (margin_pixels < 0 || margin_pixels > 64)
    throw std::invalid_argument("paint transfer: margin_pixels must lie in 0..64");
  if (!(max_extent > 0) || !std::isfinite(max_extent))
    throw std::invalid_argument("paint transfer: max_extent must be positive");
  if (!(imprint_min_alignment >= 0 && imprint_min_alignment <= 1))
    throw std::invalid_argument("paint transfer: imprint_min_alignment must lie in 0..1");
  if (!(imprint_min_speed >= 0) || !std::isfinite(imprint_min_speed))
    throw std::invalid_argument("paint transfer: imprint_min_speed must be >= 0");
}

double paintBufferPixel(const PaintTransferOptions& options, const BrushPreset& brush) {
  return options.pixel_size > 0 ? options.pixel_size : brush.surfel_spacing;
}

bool imprintAliases(const PaintType& paint, double pixel) {
  return paint.imprint_depth > 0 && !(paint.imprint_spacing >= 2 * pixel);
}

PaintEventStats transferPaint(Brush& brush, PaintSurface& surface, const PaintType& paint, double dt,
                              const PaintTransferOptions& options) {
  options.validate();
  if (!(dt >= 0)) throw std::invalid_argument("transferPaint: dt must be >= 0");
  PaintType effective = paint;
  const bool aliased = imprintAliases(paint, paintBufferPixel(options, brush.preset()));
  if (aliased) effective.imprint_depth = 0;  // the pattern cannot be sampled by these pixels
  PaintEventStats stats;
  stats.imprint_aliased = aliased;
  const BrushSplit& split = brush.split();
  if (split.tips.empty()) return stats;
  const BrushSkeleton& skeleton = brush.skeleton();
  BrushSkin& skin = brush.skin();
  // Tip centres: the mean of each tip's colliding active masses.
  std::vector<Vec3> tips;
  for (const std::vector<int>& tip : split.tips) {
    Vec3 c = Vec3::Zero();
    for (int a : tip) c += skeleton.positions()[size_t(skeleton.handleCount() + a)];
    tips.push_back(c / double(tip.size()));
  }
  // Each skin surfel goes to the buffer of its nearest tip (one buffer when the brush is not split).
  std::vector<std::vector<int>> samples(tips.size());
  for (size_t i = 0; i < skin.size(); ++i) {
    size_t best = 0;
    for (size_t t = 1; t < tips.size(); ++t)
      if ((skin.positions()[i] - tips[t]).squaredNorm() < (skin.positions()[i] - tips[best]).squaredNorm())
        best = t;
    samples[best].push_back(int(i));
  }
  for (size_t t = 0; t < tips.size(); ++t)
    transferAtTip(samples[t], tips[t], split.tip_normals[t], brush, surface, effective, dt, options, &stats);
  return stats;
}

double surfaceWetVolume(const PaintSurface& surface) {
  double sum = 0;
  for (size_t i = 0; i < surface.originalCount(); ++i) {
    if (surface.enabled(i)) sum += surface.originalPaint(i).wet_volume;
    for (const ChildSurfel& c : surface.children(i)) sum += c.paint.wet_volume;
  }
  return sum;
}

}  // namespace rc
