// Result type shared by the spatial indices.
#pragma once

#include <cstdint>

namespace rc {

/// A neighbour found by a spatial query. `sq_dist` is the SQUARED Euclidean distance to the query point.
struct Neighbor {
  uint32_t index;
  double sq_dist;
};

}  // namespace rc
