// Scene builders for the SPH solver: lattice-filled fluid boxes, boundary-particle walls, box planes, 2D dam
// break.
#pragma once

#include <vector>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_particles.h"

namespace rc {

/// Mass that gives a particle with full kernel support on a square (2D) / cubic (3D) lattice of spacing dx
/// exactly the rest density under the poly6 density sum (8.4): m = rho_0 / sum_k W(|k| dx), self included.
/// Throws std::invalid_argument for dx or rest_density not finite and > 0.
double latticeParticleMass(const SphKernels& kernels, double rest_density, double dx);

/// Fills the box [lo, hi] with particles of `kind` on a lattice of spacing dx, cell-centred (the first at
/// lo + dx/2, as many as fit). In 2D (dimension 2) z is 0 and lo.z / hi.z are ignored. Returns the number
/// added. Throws std::invalid_argument for a bad dx, mass, dimension or an empty box.
size_t addLatticeBox(SphParticles& particles, const Vec3& lo, const Vec3& hi, double dx, double mass,
                     int dimension, SphParticleKind kind = SphParticleKind::kFluid);

/// Walls of static boundary particles around the box [lo, hi] (floor at lo.y, side walls, and the ceiling if
/// `closed_top`): `layers` lattice layers of spacing dx outside the box, aligned with the lattice of
/// addLatticeBox on the same box. Side walls reach up to hi.y. Returns the number added.
size_t addBoundaryWalls(SphParticles& particles, const Vec3& lo, const Vec3& hi, double dx, int layers,
                        double mass, int dimension, bool closed_top = false);

/// Points of the square lattice of spacing dx in the disc of `radius` (centres within radius, relative
/// tolerance 1e-9) perpendicular to `axis` around the origin, the origin included: i u + j w for integers i,
/// j with u, w an orthonormal basis of the plane (u = normalised axis x e_k, e_k the coordinate axis least
/// aligned with `axis`; w = axis x u), in the order j, then i, ascending. In 2D (dimension 2; axis with z =
/// 0) the "disc" is the segment perpendicular to axis in the x-y plane. Throws std::invalid_argument for a
/// zero or non-finite axis, a bad radius or dx, or (2D) an axis with z != 0.
std::vector<Vec3> latticeDisc(const Vec3& axis, double radius, double dx, int dimension);

/// Fills the cylinder from `from` to `to` (3D) with particles of `kind`: cross-sections latticeDisc(to -
/// from, radius, dx) at the axial positions (k + 1/2) dx + (length - n dx) / 2, k < n = max(1, floor(length /
/// dx)), i.e. cell-centred along the axis and centred on it. Returns the number added. Throws
/// std::invalid_argument for from == to, a bad radius, dx or mass.
size_t addLatticeCylinder(SphParticles& particles, const Vec3& from, const Vec3& to, double radius, double dx,
                          double mass, SphParticleKind kind = SphParticleKind::kStaticBoundary);

/// Planes bounding [lo, hi] (normals pointing inside): floor, side walls (x, and z in 3D), ceiling if
/// `closed_top`.
std::vector<SphPlane> boxPlanes(const Vec3& lo, const Vec3& hi, int dimension, bool closed_top = false,
                                double restitution = 0.0, double friction = 0.0);

/// 2D dam break (REFERENCES: column height = 2 x width, Martin & Moyce): a fluid column of
/// column_width x column_height at the left of a tank tank_width wide and tank_height high, walls of
/// boundary particles. h = smoothing_ratio * dx.
struct SphDamBreak2D {
  double column_width = 0.25;
  double column_height = 0.5;
  double tank_width = 1.0;
  double tank_height = 0.6;
  double dx = 0.0125;
  double smoothing_ratio = 3.0;
  int wall_layers = 3;
};

/// Particles of the dam break; `config` gets dimension 2 and h (its other fields are kept), and is then
/// validated.
SphParticles makeDamBreak2D(const SphDamBreak2D& scene, SphFluidConfig& config);

}  // namespace rc
