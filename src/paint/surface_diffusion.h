// Surface diffusion of wet paint on the painted object (thesis 5.6.2, (5.14), (5.15)) as background work:
// every whole time step, the active surfels around the wet ones (a region of at most max_surfels, the wet
// originals taken in turn) go through PaintDiffusion and their paint is written back. The surface resamples
// itself under the brush, so the region is gathered again at every call; the work is bounded by max_surfels.
#pragma once

#include <cstddef>

#include "relaxed_connectivity/paint/paint_diffusion.h"
#include "relaxed_connectivity/paint/paint_surface.h"

namespace rc {

struct SurfaceDiffusionOptions {
  double neighbour_radii = 3.0;  ///< exchange partners within this many typical surfel radii
  double time_step = 0.05;       ///< simulated time of one sweep [s]
  size_t max_surfels = 4000;     ///< active surfels per call (the region around the wet ones)

  /// Throws std::invalid_argument naming the bad option.
  void validate() const;
};

struct SurfaceDiffusionStats {
  size_t sweeps = 0;       ///< whole time steps run
  size_t surfels = 0;      ///< active surfels in the region
  size_t wet_surfels = 0;  ///< of them, holding wet paint
  bool whole = true;       ///< false when the wet region was cut at max_surfels (the rest: next calls)
};

class SurfaceDiffusion {
 public:
  /// `diffusion`: D [m^2/s] of (5.14) (the paint type's); 0 switches it off.
  explicit SurfaceDiffusion(double diffusion, SurfaceDiffusionOptions options = {});

  /// Adds `seconds` of simulated time and runs the whole time steps pending on the surface's wet paint.
  /// Volume is conserved exactly (every exchange moves paint between two surfels).
  SurfaceDiffusionStats run(PaintSurface& surface, double seconds);

 private:
  double diffusion_;
  SurfaceDiffusionOptions options_;
  double pending_ = 0;
  size_t cursor_ = 0;  // next original to look at for wet paint when the region is cut
};

}  // namespace rc
