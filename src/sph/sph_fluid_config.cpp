// SphFluidConfig's checks and the names of the step limits (declared in sph_fluid_solver.h).
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"

namespace rc {

namespace {

void require(bool ok, const char* field, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string("SphFluidConfig.") + field + ": " + what);
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3g", v);
  return buf;
}

}  // namespace

const char* toString(SphStepLimit limit) {
  switch (limit) {
    case SphStepLimit::kFixed:
      return "fixed";
    case SphStepLimit::kMaxDt:
      return "max_dt";
    case SphStepLimit::kSpeed:
      return "speed (CFL)";
    case SphStepLimit::kSoundSpeed:
      return "sound speed";
    case SphStepLimit::kViscosity:
      return "viscosity";
    case SphStepLimit::kForce:
      return "force";
    case SphStepLimit::kElastic:
      return "elastic wave speed";
  }
  return "?";
}

void SphFluidConfig::validate() const {
  require(dimension == 2 || dimension == 3, "dimension", "must be 2 or 3, got " + std::to_string(dimension));
  require(smoothing_length > 0.0 && std::isfinite(smoothing_length), "smoothing_length",
          "must be finite and > 0, got " + num(smoothing_length));
  require(rest_density > 0.0 && std::isfinite(rest_density), "rest_density",
          "must be finite and > 0, got " + num(rest_density));
  require(stiffness > 0.0 && std::isfinite(stiffness), "stiffness",
          "must be finite and > 0, got " + num(stiffness));
  require(gamma >= 1.0 && std::isfinite(gamma), "gamma", "must be finite and >= 1, got " + num(gamma));
  require(negative_pressure_scale >= 0.0 && negative_pressure_scale <= 1.0, "negative_pressure_scale",
          "(zeta) must be in [0, 1], got " + num(negative_pressure_scale));
  require(tensile_correction >= 0.0 && tensile_correction <= 1.0, "tensile_correction",
          "(epsilon) must be in [0, 1] (0 = off), got " + num(tensile_correction));
  require(tensile_correction == 0.0 || (tensile_spacing > 0.0 && tensile_spacing < smoothing_length),
          "tensile_spacing",
          "must be the initial particle spacing, in (0, smoothing_length), with tensile_correction; got " +
              num(tensile_spacing));
  require(density_reinit_interval >= 0, "density_reinit_interval",
          "must be >= 0 (steps; 0 = never), got " + std::to_string(density_reinit_interval));
  require(density_reinit_interval == 0 || density == SphDensityMethod::kContinuity, "density_reinit_interval",
          "re-initialises continuity densities: set density to continuity (or the interval to 0)");
  require(viscosity >= 0.0 && std::isfinite(viscosity), "viscosity",
          "must be finite and >= 0, got " + num(viscosity));
  require(xsph >= 0.0 && xsph <= 1.0, "xsph", "(xi) must be in [0, 1], got " + num(xsph));
  require(gravity.allFinite(), "gravity", "must be finite");
  require(dimension == 3 || gravity.z() == 0.0, "gravity", "z must be 0 in 2D, got " + num(gravity.z()));
  require(cfl > 0.0 && cfl <= 1.0, "cfl", "must be in (0, 1], got " + num(cfl));
  require(fixed_dt >= 0.0 && std::isfinite(fixed_dt), "fixed_dt",
          "must be finite and >= 0 (0 = adaptive), got " + num(fixed_dt));
  require(max_dt > 0.0 && std::isfinite(max_dt), "max_dt", "must be finite and > 0, got " + num(max_dt));
  require(instability_energy_growth > 1.0, "instability_energy_growth",
          "must be > 1, got " + num(instability_energy_growth));
  require(instability_window >= 0, "instability_window",
          "must be >= 0 (0 = off), got " + std::to_string(instability_window));
  require(instability_window_growth > 1.0, "instability_window_growth",
          "must be > 1, got " + num(instability_window_growth));
  require(max_compression >= 0.0 && std::isfinite(max_compression), "max_compression",
          "must be finite and >= 0 (0 = off), got " + num(max_compression));
  require(num_threads >= 0, "num_threads", "must be >= 0 (0 = all), got " + std::to_string(num_threads));
}

double SphFluidConfig::soundSpeed() const {
  return std::sqrt(stiffness * gamma / rest_density);
}

}  // namespace rc
