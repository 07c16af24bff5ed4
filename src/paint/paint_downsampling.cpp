#include "relaxed_connectivity/paint/paint_downsampling.h"

#include <stdexcept>
#include <utility>

namespace rc {

PaintDownsampler::PaintDownsampler(DownsamplingOptions options) : options_(options) {
  if (!(options_.colour_variance >= 0) || !(options_.normal_variance >= 0))
    throw std::invalid_argument("PaintDownsampler: variance thresholds must be >= 0");
}

DownsamplingStats PaintDownsampler::run(PaintSurface& surface, size_t max_visits) {
  DownsamplingStats stats;
  const size_t n = surface.originalCount();
  for (size_t scanned = 0; scanned < n && stats.visited < max_visits; ++scanned) {
    const size_t i = cursor_;
    cursor_ = (cursor_ + 1) % n;
    const std::vector<ChildSurfel>& children = std::as_const(surface).children(i);
    if (children.empty()) continue;
    ++stats.visited;
    // Colour variance (of what is seen, 5.8) and normal spread of the children (5.5.2).
    Vec3 mean = Vec3::Zero(), normal = Vec3::Zero();
    for (const ChildSurfel& c : children) mean += visibleColour(c.paint).rgb, normal += c.normal.normalized();
    mean /= double(children.size());
    double variance = 0;
    for (const ChildSurfel& c : children) variance += (visibleColour(c.paint).rgb - mean).squaredNorm();
    variance /= double(children.size());
    const double spread = 1.0 - normal.norm() / double(children.size());
    if (variance > options_.colour_variance || spread > options_.normal_variance) continue;
    // Merge into the father: the children's wet paint added up (5.11), their dry paint averaged.
    PaintState merged = std::as_const(surface).originalPaint(i);
    merged.wet_volume = 0;
    merged.dry = PaintColour();
    merged.dry_volume = 0;
    double count = 0;
    for (const ChildSurfel& c : children) {
      addWetPaint(merged, c.paint, c.paint.wet_volume);
      count += 1;
      merged.dry = PaintColour::mix(merged.dry, count - 1, c.paint.dry, 1.0);
      merged.dry_volume += (c.paint.dry_volume - merged.dry_volume) / count;
    }
    surface.originalPaint(i) = merged;
    stats.children_removed += children.size();
    surface.clearChildren(i);  // re-enables the father
    ++stats.merged;
  }
  return stats;
}

}  // namespace rc
