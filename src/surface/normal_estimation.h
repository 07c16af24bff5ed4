// Normal estimation for raw scans: weighted covariance (PCA) of the k nearest neighbours, with consistent
// orientation (towards a known sensor viewpoint, or propagated over a Riemannian minimum spanning tree when
// no viewpoint is known, Hoppe et al. 1992).
#pragma once

#include <optional>
#include <vector>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/core/neighbor_lists.h"
#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/core/weight_function.h"

namespace rc {

struct NormalEstimationConfig {
  int k = 16;  ///< neighbours per covariance fit (speed/accuracy knob)
  /// Orient normals towards this point (e.g. the scanner origin in the cloud's frame). Without it,
  /// orientation is propagated over the kNN graph and the result points away from the cloud's centroid on its
  /// extreme point.
  std::optional<Vec3> viewpoint;
  bool write_curvature =
      true;  ///< store surface variation lambda0 / (lambda0+lambda1+lambda2) in `curvature`
};

/// Fills cloud.normals (and curvature). Throws std::invalid_argument for fewer than 3 points or k < 3.
void estimateNormals(SurfelCloud& cloud, const NormalEstimationConfig& config);

/// MLS normals: for every sample i the normal of the weighted covariance plane (3.5) of the samples within
/// `support` of x_i (weights w(|x_j - x_i|)), taken from `lists` (built over `positions` at a radius >=
/// support). Unoriented (the eigen solver's sign); zero where fewer than max(3, min_neighbors) samples have
/// weight or the fit is degenerate. Multi-threaded (OpenMP). The normals MlsConfig::estimate_normals uses.
void estimatePlaneNormals(const std::vector<Vec3>& positions, const NeighborLists& lists,
                          const WeightFunction& weight, double support, size_t min_neighbors,
                          std::vector<Vec3>& normals);
/// The same from kd-tree radius queries (`tree` over `positions`); non-finite samples get zero normals.
void estimatePlaneNormals(const std::vector<Vec3>& positions, const KdTree& tree,
                          const WeightFunction& weight, double support, size_t min_neighbors,
                          std::vector<Vec3>& normals);

/// Refines unoriented sample normals (e.g. estimatePlaneNormals') by one pass of oriented sphere fits (APSS):
/// the normal of sample i becomes the gradient at x_i of the sphere fitted to the samples within `support`
/// with the current normals (oriented per neighbourhood), signed like the current one. It smooths the noise
/// of normals estimated from noisy points (the fit averages the neighbours' normals) and keeps the curvature
/// the positions give. Zero normals stay zero; a failed fit keeps the current normal. Multi-threaded
/// (OpenMP).
void refineNormalsBySpheres(const std::vector<Vec3>& positions, const NeighborLists& lists,
                            const WeightFunction& weight, double support, size_t min_neighbors,
                            std::vector<Vec3>& normals);
void refineNormalsBySpheres(const std::vector<Vec3>& positions, const KdTree& tree,
                            const WeightFunction& weight, double support, size_t min_neighbors,
                            std::vector<Vec3>& normals);

/// Flips normals so that neighbouring normals agree (MST propagation); returns the number flipped.
size_t orientNormalsConsistently(SurfelCloud& cloud, int k = 16);

}  // namespace rc
