// An indexed triangle mesh: the vertices are a surfel cloud (so vertex normals, colours and extra attributes
// travel with them) and faces are index triples.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

using Triangle = std::array<uint32_t, 3>;

struct TriangleMesh {
  SurfelCloud vertices;
  std::vector<Triangle> triangles;
};

}  // namespace rc
