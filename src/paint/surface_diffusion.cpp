#include "relaxed_connectivity/paint/surface_diffusion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace rc {

void SurfaceDiffusionOptions::validate() const {
  if (!(neighbour_radii > 0) || !std::isfinite(neighbour_radii))
    throw std::invalid_argument("surface diffusion: neighbour_radii must be positive");
  if (!(time_step > 0) || !std::isfinite(time_step))
    throw std::invalid_argument("surface diffusion: time_step must be positive");
  if (max_surfels == 0) throw std::invalid_argument("surface diffusion: max_surfels must be positive");
}

SurfaceDiffusion::SurfaceDiffusion(double diffusion, SurfaceDiffusionOptions options)
    : diffusion_(diffusion), options_(options) {
  if (!(diffusion >= 0) || !std::isfinite(diffusion))
    throw std::invalid_argument("SurfaceDiffusion: diffusion must be >= 0");
  options_.validate();
}

namespace {

bool holdsWetPaint(const PaintSurface& s, size_t i) {
  if (s.enabled(i) && s.originalPaint(i).wet_volume > 0) return true;
  for (const ChildSurfel& c : s.children(i))
    if (c.paint.wet_volume > 0) return true;
  return false;
}

size_t activeCountOf(const PaintSurface& s, size_t i) {
  return (s.enabled(i) ? 1 : 0) + s.children(i).size();
}

}  // namespace

SurfaceDiffusionStats SurfaceDiffusion::run(PaintSurface& surface, double seconds) {
  if (!(seconds >= 0)) throw std::invalid_argument("SurfaceDiffusion::run: seconds must be >= 0");
  SurfaceDiffusionStats stats;
  if (diffusion_ == 0) return stats;  // off: costs nothing
  pending_ += seconds;
  const size_t sweeps = size_t(std::floor(pending_ / options_.time_step));
  if (sweeps == 0) return stats;
  pending_ -= double(sweeps) * options_.time_step;
  const PaintSurface& view = surface;
  const size_t n = view.originalCount();
  if (cursor_ >= n) cursor_ = 0;
  // The region: wet originals from the cursor on, with the originals around them, up to max_surfels.
  const double radius = options_.neighbour_radii * view.typicalRadius();
  std::vector<uint8_t> in_region(n, 0);
  std::vector<uint32_t> region, near;
  size_t active = 0;
  size_t scanned = 0;
  for (; scanned < n; ++scanned) {
    const size_t i = (cursor_ + scanned) % n;
    if (!holdsWetPaint(view, i)) continue;
    view.originalsWithin(view.originals().positions[i], 2 * radius, near);
    size_t added = 0;
    for (uint32_t j : near)
      if (!in_region[j]) added += activeCountOf(view, j);
    if (active > 0 && active + added > options_.max_surfels) {
      stats.whole = false;
      break;
    }
    for (uint32_t j : near)
      if (!in_region[j]) in_region[j] = 1, region.push_back(j);
    active += added;
  }
  cursor_ = stats.whole ? 0 : (cursor_ + scanned) % n;
  if (region.empty()) return stats;
  std::sort(region.begin(), region.end());  // a deterministic order whatever the scan found first
  // Snapshot of the region's active surfels.
  struct Ref {
    uint32_t original;
    int32_t child;  // -1: the original itself
  };
  std::vector<Vec3> positions;
  std::vector<PaintState> paint;
  std::vector<Ref> refs;
  for (uint32_t i : region) {
    if (view.enabled(i)) {
      positions.push_back(view.originals().positions[i]);
      paint.push_back(view.originalPaint(i));
      refs.push_back({i, -1});
    }
    const std::vector<ChildSurfel>& children = view.children(i);
    for (size_t k = 0; k < children.size(); ++k) {
      positions.push_back(children[k].position);
      paint.push_back(children[k].paint);
      refs.push_back({i, int32_t(k)});
    }
  }
  PaintDiffusionOptions o;
  o.diffusion = diffusion_;
  o.neighbour_radius = radius;
  o.time_step = options_.time_step;
  PaintDiffusion diffusion(positions, o);
  for (size_t k = 0; k < paint.size(); ++k)
    if (paint[k].wet_volume > 0) diffusion.markWet(k), ++stats.wet_surfels;
  diffusion.addTime(double(sweeps) * options_.time_step);
  while (diffusion.run(paint, paint.size() * 64) > 0) {
  }
  // Write back what changed (through the mutable accessors: reported as changed).
  for (size_t k = 0; k < refs.size(); ++k) {
    const Ref& r = refs[k];
    const PaintState& before =
        r.child < 0 ? view.originalPaint(r.original) : view.children(r.original)[size_t(r.child)].paint;
    if (before == paint[k]) continue;
    if (r.child < 0)
      surface.originalPaint(r.original) = paint[k];
    else
      surface.children(r.original)[size_t(r.child)].paint = paint[k];
  }
  stats.sweeps = sweeps;
  stats.surfels = positions.size();
  return stats;
}

}  // namespace rc
