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
    // Only surfels with wet paint are touched, and reported as changed only where a viewer sees it (drying
    // under opaque wet paint is unseen until the paint thins): deltas carry what the image needs.
    const PaintSurface& view = surface;
    if (view.originalPaint(i).wet_volume > 0) {
      PaintState paint = view.originalPaint(i);
      dried += dryPaint(paint, kappa_, dt, drying_);  // (5.12), (5.13)
      (lookAlike(paint, view.originalPaint(i)) ? surface.originalPaintUnseen(i) : surface.originalPaint(i)) =
          paint;
    }
    const std::vector<ChildSurfel>& children = view.children(i);
    if (std::any_of(children.begin(), children.end(),
                    [](const ChildSurfel& c) { return c.paint.wet_volume > 0; })) {
      dried_children_.assign(children.begin(), children.end());
      bool seen = false;
      for (size_t k = 0; k < dried_children_.size(); ++k) {
        dried += dryPaint(dried_children_[k].paint, kappa_, dt, drying_);
        seen = seen || !lookAlike(dried_children_[k].paint, children[k].paint);
      }
      (seen ? surface.children(i) : surface.childrenUnseen(i)).swap(dried_children_);
    }
  }
  return dried;
}

}  // namespace rc
