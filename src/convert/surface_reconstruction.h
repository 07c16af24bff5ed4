// Mesh generation, first step (thesis 6.1): a triangle mesh from the oriented surfels, by one of CGAL's
// reconstructions: the advancing front (Cohen-Steiner and Da 2004; the default, in place of the thesis'
// Cocone family: it interpolates the surfel centres, keeps boundaries of open scans and needs no parameters
// beyond plausibility bounds), the scale-space reconstruction (Digne et al. 2011: the advancing front meshes
// the points smoothed by a few weighted-PCA projections, then the triangles are put back on the original
// centres; for noisy scans), or Poisson (Kazhdan et al. 2006; the implicit route the thesis names in 6.1:
// watertight, new vertices, closes holes and open sides). Interpolating results are oriented to agree with
// the surfels' normals, component by component.
#pragma once

#include <cstddef>
#include <string>

#include "relaxed_connectivity/convert/stage_progress.h"
#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

enum class ReconstructionMethod { kAdvancingFront, kScaleSpace, kPoisson };

/// "advancing_front", "scale_space", "poisson"; throws std::invalid_argument naming the choices otherwise.
ReconstructionMethod reconstructionMethodFromName(const std::string& name);
const char* reconstructionMethodName(ReconstructionMethod method);

struct ReconstructionOptions {
  ReconstructionMethod method = ReconstructionMethod::kAdvancingFront;
  /// Candidate triangles beside a surface triangle but outside the beta wedge are dropped if their radius is
  /// larger than this many times the surface triangle's (CGAL's radius_ratio_bound; bounds boundaries).
  double radius_ratio_bound = 5.0;
  /// Half the wedge angle [rad] within which only a candidate's radius decides its plausibility (CGAL's
  /// beta).
  double beta = 0.52;
  /// Candidates with an edge longer than this many times the local sample spacing (the distance from a vertex
  /// to its spacing_neighbors-th nearest surfel, the largest of the three) are refused: they would bridge
  /// holes and gaps the surfels do not cover. 0: no bound (CGAL's plain advancing front).
  double max_edge_spacing = 4.0;
  int spacing_neighbors = 8;
  /// Throws std::invalid_argument if the mesh is not (vertex- and edge-) manifold after orientation.
  bool require_manifold = true;
  /// Scale space: smoothing projections before meshing, and the neighbours of each weighted-PCA fit.
  int scale_space_iterations = 4;
  int scale_space_neighbors = 12;
  /// Poisson: the surface mesher's approximation distance in average sample spacings (CGAL's sm_distance;
  /// smaller: finer meshes, slower).
  double poisson_distance = 0.375;
};

struct ReconstructionStats {
  size_t triangles = 0;
  size_t components = 0;          ///< connected components of the mesh
  size_t flipped_components = 0;  ///< components whose triangles were turned to agree with the normals
  size_t unused_surfels = 0;      ///< surfels no triangle uses (outliers, sparse spots)
  size_t boundary_edges = 0;
};

/// True when this build has CGAL (libcgal-dev); the functions below throw std::runtime_error otherwise.
bool meshGenerationAvailable();

/// The reconstructed mesh. Advancing front and scale space: its vertices are the surfels (positions, normals,
/// colours: every surfel, used or not, in the input order), its triangles index them. Poisson: new vertices
/// (positions only) on the implicit surface, oriented by its gradient (which follows the normals). Throws
/// std::invalid_argument for fewer than 4 surfels, missing normals, non-finite positions or normals, or (with
/// require_manifold) a non-manifold result. `progress` (optional) is called every few thousand candidate
/// triangles with an estimate of the fraction done (the front's triangles over twice the surfel count);
/// returning false throws ConversionCancelled.
TriangleMesh reconstructSurface(const SurfelCloud& surfels, const ReconstructionOptions& options = {},
                                ReconstructionStats* stats = nullptr,
                                const StageProgress& progress = nullptr);

}  // namespace rc
