// Mesh generation, first step (thesis 6.1): a triangle mesh interpolating the surfel centres, by CGAL's
// advancing-front surface reconstruction (Cohen-Steiner and Da 2004) in place of the thesis' Cocone family:
// it keeps boundaries (open scans) and needs no parameters beyond two plausibility bounds. The triangles are
// oriented to agree with the surfels' normals, component by component.
#pragma once

#include <cstddef>

#include "relaxed_connectivity/convert/stage_progress.h"
#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {

struct ReconstructionOptions {
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

/// The reconstructed mesh: its vertices are the surfels (positions, normals, colours: every surfel, used or
/// not, in the input order), its triangles index them. Throws std::invalid_argument for fewer than 4 surfels,
/// missing normals, non-finite positions or normals, or (with require_manifold) a non-manifold result.
/// `progress` (optional) is called every few thousand candidate triangles with an estimate of the fraction
/// done (the front's triangles over twice the surfel count); returning false throws ConversionCancelled.
TriangleMesh reconstructSurface(const SurfelCloud& surfels, const ReconstructionOptions& options = {},
                                ReconstructionStats* stats = nullptr,
                                const StageProgress& progress = nullptr);

}  // namespace rc
