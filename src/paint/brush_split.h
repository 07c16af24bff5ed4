// Brush splitting (thesis 5.4.3): a brush whose colliding active masses see surface normals more than a
// threshold apart (60 degrees) is split into tips, one paint buffer each (5.5.1).
#pragma once

#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

struct BrushSplit {
  bool split = false;
  /// Groups of colliding active masses (indices as given), one per tip; one group when not split, none when
  /// nothing collides.
  std::vector<std::vector<int>> tips;
  std::vector<Vec3> tip_normals;  ///< mean surface normal of each tip (unit)
};

/// `actives[i]` collides with surface normal `normals[i]` (unit). Tips grow by farthest-normal seeding: a new
/// tip starts at the mass whose normal is farthest from every tip's seed while that angle exceeds the
/// threshold; each mass joins the tip with the closest seed normal.
BrushSplit splitBrush(const std::vector<int>& actives, const std::vector<Vec3>& normals,
                      double threshold_deg);

}  // namespace rc
