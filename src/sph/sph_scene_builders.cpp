#include "relaxed_connectivity/sph/sph_scene_builders.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

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

std::vector<Vec3> latticeDisc(const Vec3& axis, double radius, double dx, int dimension) {
  if (dimension != 2 && dimension != 3)
    throw std::invalid_argument("latticeDisc: dimension must be 2 or 3, got " + std::to_string(dimension));
  if (!axis.allFinite() || !(axis.norm() > 0.0))
    throw std::invalid_argument("latticeDisc: axis must be finite and non-zero");
  if (dimension == 2 && axis.z() != 0.0)
    throw std::invalid_argument("latticeDisc: axis must have z = 0 in 2D");
  if (!(radius >= 0.0) || !std::isfinite(radius))
    throw std::invalid_argument("latticeDisc: radius must be finite and >= 0, got " + std::to_string(radius));
  if (!(dx > 0.0) || !std::isfinite(dx))
    throw std::invalid_argument("latticeDisc: dx must be finite and > 0, got " + std::to_string(dx));
  const Vec3 n = axis.normalized();
  Vec3 u, w = Vec3::Zero();
  if (dimension == 2) {
    u = Vec3(-n.y(), n.x(), 0.0);
  } else {
    int least = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(n[k]) < std::abs(n[least])) least = k;
    u = n.cross(Vec3::Unit(least)).normalized();
    w = n.cross(u);
  }
  const long r = static_cast<long>(std::floor(radius / dx + 1e-9));
  const long rj = dimension == 3 ? r : 0;
  const double limit = radius * radius * (1.0 + 1e-9) / (dx * dx);
  std::vector<Vec3> points;
  for (long j = -rj; j <= rj; ++j)
    for (long i = -r; i <= r; ++i)
      if (double(i * i + j * j) <= limit) points.push_back((double(i) * dx) * u + (double(j) * dx) * w);
  return points;
}

size_t addLatticeCylinder(SphParticles& particles, const Vec3& from, const Vec3& to, double radius, double dx,
                          double mass, SphParticleKind kind) {
  checkSpacing("addLatticeCylinder", dx, mass, 3);
  if (!from.allFinite() || !to.allFinite())
    throw std::invalid_argument("addLatticeCylinder: from and to must be finite");
  const Vec3 axis = to - from;
  const double length = axis.norm();
  if (!(length > 0.0)) throw std::invalid_argument("addLatticeCylinder: from and to must differ");
  if (!(radius > 0.0) || !std::isfinite(radius))
    throw std::invalid_argument("addLatticeCylinder: radius must be finite and > 0, got " +
                                std::to_string(radius));
  const std::vector<Vec3> disc = latticeDisc(axis, radius, dx, 3);
  const Vec3 n = axis / length;
  const long count = std::max<long>(1, latticeCount(0.0, length, dx));
  const double first = 0.5 * (length - double(count) * dx) + 0.5 * dx;
  for (long k = 0; k < count; ++k) {
    const Vec3 c = from + (first + double(k) * dx) * n;
    for (const Vec3& p : disc) particles.add(c + p, Vec3::Zero(), mass, kind);
  }
  return static_cast<size_t>(count) * disc.size();
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
