// Procedural paint for uncoloured scans (the bench, the tests and rc_convert --paint-cells): cells of two
// colours with a gradient across them and thin dark stripes, so that a conversion has both uniform regions
// and detail, like the thesis' painted models (6.4).
#pragma once

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// Sets every surfel's colour from its position: cells of size diagonal / cells_per_diagonal alternating
/// between an orange and a blue family, a gradient along z, and dark stripes three per cell along x.
void paintCells(SurfelCloud& cloud, double cells_per_diagonal = 10);

}  // namespace rc
