#include "relaxed_connectivity/sph/sph_fluid_source.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/sph/sph_scene_builders.h"

namespace rc {

namespace {

void require(bool ok, const char* field, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string("SphFluidSourceConfig.") + field + ": " + what);
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

}  // namespace

void SphFluidSourceConfig::validate() const {
  require(dimension == 2 || dimension == 3, "dimension", "must be 2 or 3, got " + std::to_string(dimension));
  require(center.allFinite(), "center", "must be finite");
  require(direction.allFinite() && direction.norm() > 0.0, "direction", "must be finite and non-zero");
  require(dimension == 3 || direction.z() == 0.0, "direction",
          "z must be 0 in 2D, got " + num(direction.z()));
  require(spacing > 0.0 && std::isfinite(spacing), "spacing", "must be finite and > 0, got " + num(spacing));
  require(radius > 0.0 && std::isfinite(radius), "radius", "must be finite and > 0, got " + num(radius));
  require(radius >= 0.5 * spacing, "radius",
          "must be at least half the spacing " + num(spacing) + ", got " + num(radius));
  require(speed > 0.0 && std::isfinite(speed), "speed", "must be finite and > 0, got " + num(speed));
  require(start_time >= 0.0 && std::isfinite(start_time), "start_time",
          "must be finite and >= 0, got " + num(start_time));
  require(stop_time > start_time, "stop_time",
          "must exceed start_time " + num(start_time) + ", got " + num(stop_time));
  require(std::isfinite(temperature), "temperature", "must be finite");
}

double SphFluidSourceConfig::area() const {
  return dimension == 3 ? M_PI * radius * radius : 2.0 * radius;
}

SphFluidSource::SphFluidSource(const SphFluidSourceConfig& config, const SphKernels& kernels,
                               double rest_density)
    : config_(config) {
  config_.validate();
  if (kernels.dimension != config_.dimension)
    throw std::invalid_argument("SphFluidSource: the kernels are " + std::to_string(kernels.dimension) +
                                "D, the source " + std::to_string(config_.dimension) + "D");
  if (config_.dimension == 2) config_.center.z() = 0.0;
  normal_ = config_.direction.normalized();
  disc_ = latticeDisc(normal_, config_.radius, config_.spacing, config_.dimension);
  mass_ = latticeParticleMass(kernels, rest_density, config_.spacing);
  rest_density_ = rest_density;
  pitch_ = double(disc_.size()) * mass_ / (rest_density * config_.area());
}

size_t SphFluidSource::dueLayers(double time) const {
  const double end = std::min(time, config_.stop_time);
  if (!(end >= config_.start_time)) return 0;
  const double distance = config_.speed * (end - config_.start_time);
  return static_cast<size_t>(std::floor(distance / pitch_ + 1e-9)) + 1;
}

double SphFluidSource::scheduledMass(double time) const {
  return double(dueLayers(time)) * double(disc_.size()) * mass_;
}

size_t SphFluidSource::emit(SphParticles& particles, double time) {
  if (!std::isfinite(time))
    throw std::invalid_argument("SphFluidSource::emit: time must be finite, got " + num(time));
  const size_t due = dueLayers(time);
  const size_t first = particles.size();
  const double d = config_.spacing, clear2 = 0.25 * d * d;
  const Vec3 velocity = config_.speed * normal_;
  while (next_layer_ < due && !stats_.capped) {
    // Layer k left the disc at t_k = start + k p / v and has moved v (t - t_k) since.
    const double offset = config_.speed * (time - config_.start_time) - double(next_layer_) * pitch_;
    const Vec3 base = config_.center + offset * normal_;
    // Particles near the layer (its bounding box grown by d / 2), also those of layers just appended.
    Vec3 lo = base, hi = base;
    for (const Vec3& p : disc_) {
      lo = lo.cwiseMin(base + p);
      hi = hi.cwiseMax(base + p);
    }
    lo.array() -= 0.5 * d;
    hi.array() += 0.5 * d;
    nearby_.clear();
    for (const Vec3& x : particles.positions)
      if ((x.array() >= lo.array()).all() && (x.array() <= hi.array()).all()) nearby_.push_back(x);
    const size_t layer_begin = particles.size();
    for (const Vec3& p : disc_) {
      if (config_.max_particles > 0 && stats_.emitted >= config_.max_particles) {
        stats_.capped = true;
        break;
      }
      const Vec3 x = base + p;
      bool occupied = false;
      for (const Vec3& y : nearby_)
        if ((y - x).squaredNorm() < clear2) {
          occupied = true;
          break;
        }
      if (occupied) {
        ++stats_.skipped;
        continue;
      }
      particles.add(x, velocity, mass_, SphParticleKind::kFluid);
      ++stats_.emitted;
      stats_.emitted_mass += mass_;
    }
    if (particles.size() > layer_begin || !stats_.capped) ++stats_.layers;
    if (config_.max_particles > 0 && stats_.emitted >= config_.max_particles) stats_.capped = true;
    ++next_layer_;
  }
  return particles.size() - first;
}

}  // namespace rc
