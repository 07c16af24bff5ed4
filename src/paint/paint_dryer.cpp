#include "relaxed_connectivity/paint/paint_dryer.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rc {

PaintDryer::PaintDryer(double kappa, DryingFunction drying, double start)
    : kappa_(kappa), drying_(drying), start_(start) {
  if (!(kappa >= 0)) throw std::invalid_argument("PaintDryer: kappa must be >= 0");
}

double PaintDryer::run(PaintSurface& surface, double now, size_t max_visits) {
  const size_t n = surface.originalCount();
  if (last_visit_.size() != n) last_visit_.assign(n, start_), cursor_ = 0;  // a new object
  double dried = 0;
  for (size_t visit = 0; visit < max_visits && visit < n; ++visit) {
    const size_t i = cursor_;
    cursor_ = (cursor_ + 1) % n;
    const double dt = now - last_visit_[i];
    if (dt < 0)
      throw std::invalid_argument("PaintDryer::run: time went back by " + std::to_string(-dt) + " s");
    last_visit_[i] = now;
    // Only surfels with wet paint are touched (the others would be reported as changed for nothing).
    const PaintSurface& view = surface;
    if (view.originalPaint(i).wet_volume > 0)
      dried += dryPaint(surface.originalPaint(i), kappa_, dt, drying_);  // (5.12), (5.13)
    if (std::any_of(view.children(i).begin(), view.children(i).end(),
                    [](const ChildSurfel& c) { return c.paint.wet_volume > 0; }))
      for (ChildSurfel& c : surface.children(i)) dried += dryPaint(c.paint, kappa_, dt, drying_);
  }
  return dried;
}

}  // namespace rc
