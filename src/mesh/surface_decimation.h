// Quadric error edge-collapse decimation of a closed triangle surface (Garland and Heckbert, SIGGRAPH 1997),
// used to bring a dense scan (the 35,947-vertex Stanford bunny) to the resolution of the thesis' Fig. 9.10
// TetGen mesh. Collapses keep the surface a closed 2-manifold (link condition) and never flip or flatten a
// triangle.
#pragma once

#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

struct DecimationOptions {
  int target_vertices = 2000;
  /// A collapse is refused when a surrounding triangle's normal turns by more than this (cosine bound) or
  /// its area shrinks below min_relative_area times the mean triangle area.
  double min_normal_cosine = 0.3;
  double min_relative_area = 1e-3;
};

/// The decimated surface (unused vertices removed; only positions are kept). Throws std::invalid_argument for
/// an open or non-manifold surface (an edge not used exactly once in each direction) or target_vertices < 4.
/// Stops early (above the target) when no admissible collapse is left.
TriangleMesh decimateSurface(const TriangleMesh& surface, const DecimationOptions& options = {});

}  // namespace rc
