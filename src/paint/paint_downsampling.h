// Downsampling (thesis 5.5.2): a background process that visits the originals replaced by children and, where
// the children's colours and normals hardly vary (a uniformly painted region), removes the children and
// re-enables their father with the children's paint merged. Bounded work per call.
#pragma once

#include <cstddef>

#include "relaxed_connectivity/paint/paint_surface.h"

namespace rc {

struct DownsamplingOptions {
  double colour_variance = 1e-4;  ///< largest variance of the children's visible RGB (summed over channels)
  double normal_variance = 1e-3;  ///< largest 1 - |mean of the children's unit normals|
};

struct DownsamplingStats {
  size_t visited = 0;  ///< originals looked at
  size_t merged = 0;   ///< originals re-enabled
  size_t children_removed = 0;
};

class PaintDownsampler {
 public:
  explicit PaintDownsampler(DownsamplingOptions options = {});

  /// Visits up to `max_visits` originals (continuing round the object where the last call stopped; only
  /// those with children count). A father whose children pass both thresholds takes their paint: the sum of
  /// their wet volumes (conserved), the volume-weighted wet colour and optical density, the mean dry paint.
  DownsamplingStats run(PaintSurface& surface, size_t max_visits);

 private:
  DownsamplingOptions options_;
  size_t cursor_ = 0;
};

}  // namespace rc
