// Background drying of the painted object (thesis 5.6.1): visits the originals round the object, a bounded
// number per call, and dries the paint of each visited original and its children for the time since its last
// visit ((5.12), (5.13), exact over any split of the time).
#pragma once

#include <vector>

#include "relaxed_connectivity/paint/paint_drying.h"
#include "relaxed_connectivity/paint/paint_surface.h"

namespace rc {

class PaintDryer {
 public:
  /// `kappa` [1/s] and G of the paint type; `start` is the session clock at which the object was loaded.
  PaintDryer(double kappa, DryingFunction drying, double start = 0);

  /// Dries up to `max_visits` originals (with their children), continuing where the last call stopped, for
  /// the time since each was last visited. Returns the wet volume that dried. `now` must not go back.
  double run(PaintSurface& surface, double now, size_t max_visits);

 private:
  double kappa_;
  DryingFunction drying_;
  double start_;
  std::vector<double> last_visit_;
  size_t cursor_ = 0;
  std::vector<ChildSurfel> dried_children_;  // scratch
};

}  // namespace rc
