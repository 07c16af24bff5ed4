// A planar cut of an FEM body from a polygon (thesis 9.3): the polygon a user or a tool draws, checked and
// turned into the cut plane and region that FemSimulation::applyCut and applyPolygonCuts take.
#pragma once

#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/fem/fem_scene.h"

namespace rc {

/// The cut of a polygon given in the scene frame: plane through its centroid with its (Newell) normal, region
/// = the points projected onto that plane. Throws std::invalid_argument naming the problem: fewer than 3
/// points, a non-finite point, zero area (coincident or collinear points), a point farther than
/// planarity_tolerance * diameter from the plane, or a polygon that is not convex.
FemSceneCut femCutFromPolygon(const std::vector<Vec3>& polygon, double planarity_tolerance);

/// The polygons of a blade sweep: the blade segment (blade[0], blade[1]) translated by path[k] and path[k +
/// 1] spans quad k (path.size() - 1 quads, planar by construction). Throws std::invalid_argument for fewer
/// than 2 path points, a zero-length blade or a path step parallel to the blade.
std::vector<std::vector<Vec3>> bladeSweepPolygons(const Vec3& blade_start, const Vec3& blade_end,
                                                  const std::vector<Vec3>& path);

}  // namespace rc
