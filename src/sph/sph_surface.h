// Fluid surface mesh per frame (thesis 8.2.7): marching cubes [133] (mesh/marching_cubes.h) on an iso-surface
// of the SPH colour field c(x) = sum_j m_j / rho_j W(x - x_j) (poly6, (C.1)), the fluid density normalised to
// 1 inside the fluid.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/mesh/marching_cubes.h"
#include "relaxed_connectivity/sph/sph_particles.h"

namespace rc {

/// Which particles make up the surface.
enum class SphSurfaceParticles {
  kFluid,             ///< only SphParticleKind::kFluid
  kFluidAndBoundary,  ///< every particle (fluid, static and moving boundary)
};

/// The field is the colour field (not the level set of Zhu & Bridson 2005): the thesis extracts "an
/// iso-surface of the fluid density", the field is a plain sum of independent particle splats (parallel and
/// deterministic without neighbour searches), reads 1 inside the fluid at any resolution, and iso 0.5 puts
/// the surface of a flat fluid boundary half a particle spacing outside the outer particle layer, where the
/// fluid volume ends. Curved surfaces shrink by about sigma^2 / R (sigma^2 = 0.091 h^2, the poly6 variance
/// per axis): 0.6% of the radius at R = 12 dx, h = 3 dx.
struct SphSurfaceConfig {
  double smoothing_length = 0.1;  ///< h, support radius of the poly6 kernel (the solver's h)
  double cell_size = 0.0;         ///< grid spacing, 0 = h / 2
  double iso_value = 0.5;         ///< surface where c(x) = iso_value, > 0
  SphSurfaceParticles particles = SphSurfaceParticles::kFluid;
  /// > 0: particle volume m_j / rest_density; 0: m_j / rho_j with rho_j from SphParticles::densities (e.g.
  /// the solver's density sum (8.4); must then be > 0).
  double rest_density = 0.0;
  bool compute_normals = true;              ///< vertex normals from the field gradient
  int num_threads = 0;                      ///< OpenMP threads, 0 = all available
  size_t max_grid_nodes = size_t(1) << 27;  ///< larger grids throw (1 GiB of doubles)

  /// Throws std::invalid_argument naming the first invalid field.
  void validate() const;
  /// cell_size, or h / 2 when it is 0.
  double effectiveCellSize() const;
};

/// The colour field on a grid covering the bounding box of the chosen particles plus a margin of h + 2 cells
/// (so every boundary node is 0 and the surface is closed). Each particle is splatted only into the nodes
/// within its support, z-planes in parallel; the sum at a node runs in a fixed particle order, so the field
/// is bitwise independent of the thread count. No chosen particle gives an empty grid (dims 0). Throws
/// std::invalid_argument for a bad config, a non-finite position, a missing or non-positive density or
/// mass (naming the particle), or a grid of more than max_grid_nodes nodes.
void computeSphColorField(const SphParticles& particles, const SphSurfaceConfig& config, ScalarGrid* grid);

/// computeSphColorField followed by marchingCubes: the fluid surface of one frame, outward oriented.
TriangleMesh extractSphSurface(const SphParticles& particles, const SphSurfaceConfig& config);

}  // namespace rc
