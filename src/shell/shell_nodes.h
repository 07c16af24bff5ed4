// Simulation nodes of a point-sampled thin shell (thesis 7.2): nodes chosen from a surfel cloud by
// clustering, with rest normals, rest neighbourhoods (fan-ordered around the normal) and rest areas.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

struct ShellNodeOptions {
  /// Target node spacing (> 0), or 0 to derive it from `target_count`.
  double spacing = 0.0;
  /// Wanted number of nodes when `spacing` is 0 (the spacing is bisected until the count is within 2 %).
  size_t target_count = 0;
  /// Lloyd-type relaxation sweeps after the greedy pick: every surfel joins its nearest node, each node moves
  /// to the surfel of its cluster nearest to the cluster centroid.
  int relax_iterations = 3;
  /// Size of the rest neighbourhood N_i (nearest nodes, 7.2.1).
  size_t neighbor_count = 8;
  /// Highly irregular sampling (7.6: fibers follow the sampling, so the material turns anisotropic) is
  /// reported when more than `irregular_fraction` of the nodes have a sampling anisotropy (ShellNodes) above
  /// `anisotropy_threshold`.
  double anisotropy_threshold = 3.0;
  double irregular_fraction = 0.02;
};

/// Summary of the per-node sampling anisotropy (see ShellNodes::sampling_anisotropy).
struct ShellSamplingStats {
  double median = 0.0;
  double worst = 0.0;           ///< infinite if a node's neighbours are collinear
  double fraction_above = 0.0;  ///< of the nodes, anisotropy > threshold
  double threshold = 0.0;
  /// Empty, or "highly irregular sampling: ..." with the measured values when fraction_above exceeds the
  /// allowed fraction.
  std::string warning;
};

/// Nodes in their rest state. Neighbourhoods are CSR lists sorted counter-clockwise around the rest normal;
/// `fan_pairs` are consecutive (a, b) neighbour pairs, as local indices into the node's list, spanning less
/// than 120 degrees (at a boundary the fan stays open). They define the deformed node normal (fanNormal).
struct ShellNodes {
  std::vector<Vec3> rest_positions;
  std::vector<Vec3> rest_normals;  ///< unit, from the surfel normals
  std::vector<double>
      rest_areas;  ///< a_i^0: from surfels, the summed tangent Voronoi areas of the node's cluster; from
                   ///< points, the node's tangent Voronoi area (sums to the surface area)
  std::vector<uint32_t> source_surfel;   ///< surfel the node sits on (empty if built from plain points)
  std::vector<uint32_t> surfel_cluster;  ///< node each input surfel belongs to (empty if built from points)
  std::vector<size_t> neighbor_offsets;  ///< size() + 1 entries
  std::vector<uint32_t> neighbors;
  std::vector<size_t> fan_offsets;  ///< size() + 1 entries
  std::vector<std::pair<uint8_t, uint8_t>> fan_pairs;
  double spacing = 0.0;  ///< mean distance to the nearest neighbour
  /// Per node: sqrt(lambda_max / lambda_min) of M = sum_j e_j e_j^T / |e_j|^4 over the rest neighbours j,
  /// e_j the tangent-plane offset x_j - x_i. Each neighbour adds its direction weighted by 1 / |e_j|^2, so
  /// M ~ diag(1/a^2, 1/b^2) for a lattice of spacings a, b and the value estimates the spacing ratio b / a:
  /// 1 for square and hexagonal grids, about 1.3 at a straight grid edge, infinite for collinear neighbours.
  std::vector<double> sampling_anisotropy;
  ShellSamplingStats sampling;  ///< summary with the thresholds of ShellNodeOptions

  size_t size() const { return rest_positions.size(); }
  size_t neighborCount(size_t i) const { return neighbor_offsets[i + 1] - neighbor_offsets[i]; }
  const uint32_t* neighborsOf(size_t i) const { return neighbors.data() + neighbor_offsets[i]; }
};

/// Chooses nodes from `cloud` (positions and normals required) by greedy Poisson-disc picking in index order
/// followed by Lloyd relaxation (deterministic), then builds neighbourhoods and areas. Throws
/// std::invalid_argument naming the problem for an empty cloud, missing normals or bad options.
ShellNodes selectShellNodes(const SurfelCloud& cloud, const ShellNodeOptions& options);

/// Uses the given points as nodes directly (unit normals required, one per point). The sampling summary uses
/// the default thresholds of ShellNodeOptions.
ShellNodes shellNodesFromPoints(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                                size_t neighbor_count = 8);

/// Median, worst and fraction above `threshold` of nodes.sampling_anisotropy, with a warning when the
/// fraction exceeds `irregular_fraction`. Throws std::invalid_argument for threshold < 1 or a fraction
/// outside [0, 1].
ShellSamplingStats summarizeShellSampling(const ShellNodes& nodes, double threshold,
                                          double irregular_fraction);

/// Deformed node normal: the normalised sum of (x_a - x_i) x (x_b - x_i) over the node's fan pairs. Returns
/// the unnormalised length in `*length` (for gradients). Equals the rest normal up to sign convention at
/// rest.
Vec3 fanNormal(const ShellNodes& nodes, size_t i, const std::vector<Vec3>& x, double* length = nullptr);

}  // namespace rc
