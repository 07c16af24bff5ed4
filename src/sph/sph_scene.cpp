#include "sph/sph_scene.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

void checkSpacing(const char* fn, double dx, double mass, int dimension) {
  if (!(dx > 0.0) || !std::isfinite(dx))
    throw std::invalid_argument(std::string(fn) + ": dx must be finite and > 0, got " + std::to_string(dx));
  if (!(mass > 0.0) || !std::isfinite(mass))
    throw std::invalid_argument(std::string(fn) + ": mass must be finite and > 0, got " +
                                std::to_string(mass));
  if (dimension != 2 && dimension != 3)
    throw std::invalid_argument(std::string(fn) + ": dimension must be 2 or 3, got " +
                                std::to_string(dimension));
}

// Number of cell-centred lattice points of spacing dx in [lo, hi].
long latticeCount(double lo, double hi, double dx) {
  return static_cast<long>(std::floor((hi - lo) / dx + 1e-9));
}

}  // namespace

double latticeParticleMass(const SphKernels& kernels, double rest_density, double dx) {
  if (!(dx > 0.0) || !std::isfinite(dx))
    throw std::invalid_argument("latticeParticleMass: dx must be finite and > 0, got " + std::to_string(dx));
  if (!(rest_density > 0.0) || !std::isfinite(rest_density))
    throw std::invalid_argument("latticeParticleMass: rest_density must be finite and > 0, got " +
                                std::to_string(rest_density));
  const long r = static_cast<long>(std::ceil(kernels.h / dx));
  const long rz = kernels.dimension == 3 ? r : 0;
  double sum = 0.0;
  for (long k = -rz; k <= rz; ++k)
    for (long j = -r; j <= r; ++j)
      for (long i = -r; i <= r; ++i) sum += kernels.poly6(double(i * i + j * j + k * k) * dx * dx);
  return rest_density / sum;
}

size_t addLatticeBox(SphParticles& particles, const Vec3& lo, const Vec3& hi, double dx, double mass,
                     int dimension, SphParticleKind kind) {
  checkSpacing("addLatticeBox", dx, mass, dimension);
  if (!lo.allFinite() || !hi.allFinite()) throw std::invalid_argument("addLatticeBox: box must be finite");
  const long nx = latticeCount(lo.x(), hi.x(), dx), ny = latticeCount(lo.y(), hi.y(), dx);
  const long nz = dimension == 3 ? latticeCount(lo.z(), hi.z(), dx) : 1;
  if (nx <= 0 || ny <= 0 || nz <= 0)
    throw std::invalid_argument("addLatticeBox: the box holds no lattice point of spacing " +
                                std::to_string(dx));
  for (long k = 0; k < nz; ++k)
    for (long j = 0; j < ny; ++j)
      for (long i = 0; i < nx; ++i) {
        const double z = dimension == 3 ? lo.z() + (k + 0.5) * dx : 0.0;
        particles.add(Vec3(lo.x() + (i + 0.5) * dx, lo.y() + (j + 0.5) * dx, z), Vec3::Zero(), mass, kind);
      }
  return static_cast<size_t>(nx * ny * nz);
}

size_t addBoundaryWalls(SphParticles& particles, const Vec3& lo, const Vec3& hi, double dx, int layers,
                        double mass, int dimension, bool closed_top) {
  checkSpacing("addBoundaryWalls", dx, mass, dimension);
  if (layers < 1)
    throw std::invalid_argument("addBoundaryWalls: layers must be >= 1, got " + std::to_string(layers));
  const long nx = latticeCount(lo.x(), hi.x(), dx), ny = latticeCount(lo.y(), hi.y(), dx);
  const long nz = dimension == 3 ? latticeCount(lo.z(), hi.z(), dx) : 1;
  if (nx <= 0 || ny <= 0 || nz <= 0)
    throw std::invalid_argument("addBoundaryWalls: the box holds no lattice point of spacing " +
                                std::to_string(dx));
  const long zl = dimension == 3 ? layers : 0;
  const long y_end = closed_top ? ny + layers : ny;
  size_t added = 0;
  for (long k = -zl; k < nz + zl; ++k)
    for (long j = -layers; j < y_end; ++j)
      for (long i = -layers; i < nx + layers; ++i) {
        const bool inside = i >= 0 && i < nx && j >= 0 && j < ny && k >= 0 && k < nz;
        if (inside) continue;
        const double z = dimension == 3 ? lo.z() + (k + 0.5) * dx : 0.0;
        particles.add(Vec3(lo.x() + (i + 0.5) * dx, lo.y() + (j + 0.5) * dx, z), Vec3::Zero(), mass,
                      SphParticleKind::kStaticBoundary);
        ++added;
      }
  return added;
}

std::vector<SphPlane> boxPlanes(const Vec3& lo, const Vec3& hi, int dimension, bool closed_top,
                                double restitution, double friction) {
  std::vector<SphPlane> planes;
  auto add = [&](const Vec3& normal, double offset) {
    SphPlane p;
    p.normal = normal;
    p.offset = offset;
    p.restitution = restitution;
    p.friction = friction;
    planes.push_back(p);
  };
  add(Vec3(0, 1, 0), lo.y());
  add(Vec3(1, 0, 0), lo.x());
  add(Vec3(-1, 0, 0), -hi.x());
  if (dimension == 3) {
    add(Vec3(0, 0, 1), lo.z());
    add(Vec3(0, 0, -1), -hi.z());
  }
  if (closed_top) add(Vec3(0, -1, 0), -hi.y());
  return planes;
}

SphParticles makeDamBreak2D(const SphDamBreak2D& scene, SphFluidConfig& config) {
  if (!(scene.column_width > 0.0 && scene.column_height > 0.0 && scene.tank_width >= scene.column_width &&
        scene.tank_height > 0.0))
    throw std::invalid_argument("makeDamBreak2D: need column sizes > 0 and tank_width >= column_width");
  if (!(scene.smoothing_ratio > 0.0))
    throw std::invalid_argument("makeDamBreak2D: smoothing_ratio must be > 0");
  config.dimension = 2;
  config.smoothing_length = scene.smoothing_ratio * scene.dx;
  if (config.gravity.z() != 0.0) config.gravity.z() = 0.0;
  config.validate();
  const SphKernels kernels(2, config.smoothing_length);
  const double mass = latticeParticleMass(kernels, config.rest_density, scene.dx);
  SphParticles particles;
  addLatticeBox(particles, Vec3(0, 0, 0), Vec3(scene.column_width, scene.column_height, 0), scene.dx, mass,
                2);
  addBoundaryWalls(particles, Vec3(0, 0, 0), Vec3(scene.tank_width, scene.tank_height, 0), scene.dx,
                   scene.wall_layers, mass, 2);
  return particles;
}

}  // namespace rc
