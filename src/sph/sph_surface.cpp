#include "relaxed_connectivity/sph/sph_surface.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/sph/sph_kernels.h"

namespace rc {

namespace {

void require(bool ok, const char* field, const std::string& problem) {
  if (!ok) throw std::invalid_argument(std::string("SphSurfaceConfig: ") + field + " " + problem);
}

int threadCount(int requested) {
  return requested > 0 ? requested : omp_get_max_threads();
}

// floor / ceil of a grid coordinate without a library call (x86-64 has no SSE2 rounding instruction).
long floorIndex(double v) {
  const long i = long(v);  // truncates towards zero
  return i - long(double(i) > v);
}
long ceilIndex(double v) {
  const long i = long(v);
  return i + long(double(i) < v);
}

// line[i] += weight ((row2 - dx_i^2) / h^2)^3, dx_i = x0 + i cell, clamped at 0 (adding 0 changes nothing):
// branch-free and with every operand local, so it vectorises.
void addKernelRow(double* line, int i0, int i1, double x0, double cell, double row2, double inv_h2,
                  double weight) {
  for (int i = i0; i <= i1; ++i) {  // int: SSE2 converts int32, not int64, to double in vectors
    const double dx = x0 + double(i) * cell;
    const double t = std::max(0.0, (row2 - dx * dx) * inv_h2);
    line[i] += weight * t * t * t;
  }
}

}  // namespace

void SphSurfaceConfig::validate() const {
  require(std::isfinite(smoothing_length) && smoothing_length > 0.0, "smoothing_length",
          "must be finite and > 0, got " + std::to_string(smoothing_length));
  require(std::isfinite(cell_size) && cell_size >= 0.0, "cell_size",
          "must be finite and >= 0 (0 = h/2), got " + std::to_string(cell_size));
  require(std::isfinite(iso_value) && iso_value > 0.0, "iso_value",
          "must be finite and > 0, got " + std::to_string(iso_value));
  require(std::isfinite(rest_density) && rest_density >= 0.0, "rest_density",
          "must be finite and >= 0 (0 = particle densities), got " + std::to_string(rest_density));
  require(num_threads >= 0, "num_threads", "must be >= 0 (0 = all), got " + std::to_string(num_threads));
  require(max_grid_nodes > 0, "max_grid_nodes", "must be > 0");
}

double SphSurfaceConfig::effectiveCellSize() const {
  return cell_size > 0.0 ? cell_size : 0.5 * smoothing_length;
}

void computeSphColorField(const SphParticles& particles, const SphSurfaceConfig& config, ScalarGrid* grid) {
  config.validate();
  const size_t n = particles.size();
  if (particles.masses.size() != n)
    throw std::invalid_argument("computeSphColorField: particles.masses has " +
                                std::to_string(particles.masses.size()) + " entries for " +
                                std::to_string(n) + " particles");
  if (particles.kinds.size() != n)
    throw std::invalid_argument("computeSphColorField: particles.kinds has " +
                                std::to_string(particles.kinds.size()) + " entries for " + std::to_string(n) +
                                " particles");
  const bool use_densities = config.rest_density <= 0.0;
  if (use_densities && particles.densities.size() != n)
    throw std::invalid_argument("computeSphColorField: particles.densities has " +
                                std::to_string(particles.densities.size()) + " entries for " +
                                std::to_string(n) + " particles (set rest_density to use m / rho_0)");

  // Chosen particles, their volumes m_j / rho_j and bounding box.
  std::vector<uint32_t> chosen;
  chosen.reserve(n);
  std::vector<double> volumes;
  volumes.reserve(n);
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t p = 0; p < n; ++p) {
    if (config.particles == SphSurfaceParticles::kFluid && particles.kinds[p] != SphParticleKind::kFluid)
      continue;
    const Vec3& x = particles.positions[p];
    if (!x.allFinite())
      throw std::invalid_argument("computeSphColorField: particle " + std::to_string(p) +
                                  " has a non-finite position");
    const double mass = particles.masses[p];
    if (!(std::isfinite(mass) && mass > 0.0))
      throw std::invalid_argument("computeSphColorField: particle " + std::to_string(p) + " has mass " +
                                  std::to_string(mass) + " (must be finite and > 0)");
    const double density = use_densities ? particles.densities[p] : config.rest_density;
    if (!(std::isfinite(density) && density > 0.0))
      throw std::invalid_argument("computeSphColorField: particle " + std::to_string(p) + " has density " +
                                  std::to_string(density) +
                                  " (must be finite and > 0; compute densities or set rest_density)");
    chosen.push_back(uint32_t(p));
    volumes.push_back(mass / density);
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  grid->values.clear();
  grid->dims = {{0, 0, 0}};
  const double cell = config.effectiveCellSize();
  grid->cell_size = cell;
  if (chosen.empty()) {
    grid->origin = Vec3::Zero();
    return;
  }

  // Grid over the box plus h + 2 cells: the two outer node layers lie outside every support.
  const double h = config.smoothing_length, h2 = h * h;
  const double margin = h + 2.0 * cell;
  grid->origin = lo - Vec3::Constant(margin);
  double node_count = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double cells = std::ceil((hi[a] - lo[a] + 2.0 * margin) / cell);
    node_count *= cells + 1.0;
    if (node_count > double(config.max_grid_nodes))
      throw std::invalid_argument(
          "computeSphColorField: the grid over the particles' bounding box (" +
          std::to_string(hi.x() - lo.x()) + " x " + std::to_string(hi.y() - lo.y()) + " x " +
          std::to_string(hi.z() - lo.z()) + ") at cell size " + std::to_string(cell) +
          " exceeds max_grid_nodes = " + std::to_string(config.max_grid_nodes) + "; use a larger cell_size");
    grid->dims[a] = size_t(cells) + 1;
  }
  const size_t nx = grid->dims[0], ny = grid->dims[1], nz = grid->dims[2];
  grid->values.assign(grid->size(), 0.0);

  // Counting sort of the chosen particles by the z-plane of nodes just below them (stable: index order).
  const Vec3 origin = grid->origin;
  const double inv_cell = 1.0 / cell;
  const size_t m = chosen.size();
  std::vector<uint32_t> plane_start(nz + 1, 0), sorted(m);
  std::vector<uint32_t> plane_of(m);
  for (size_t q = 0; q < m; ++q) {
    const double z = (particles.positions[chosen[q]].z() - origin.z()) * inv_cell;
    plane_of[q] = uint32_t(std::min<double>(std::max(0.0, std::floor(z)), double(nz - 1)));
    ++plane_start[plane_of[q] + 1];
  }
  for (size_t k = 0; k < nz; ++k) plane_start[k + 1] += plane_start[k];
  {
    std::vector<uint32_t> fill(plane_start.begin(), plane_start.end() - 1);
    for (size_t q = 0; q < m; ++q) sorted[fill[plane_of[q]]++] = uint32_t(q);
  }
  const SphKernels kernels(3, h);
  std::vector<std::array<double, 4>> splats(m);  // x, y, z, a V_j in sorted order
  for (size_t s = 0; s < m; ++s) {
    const Vec3& x = particles.positions[chosen[sorted[s]]];
    splats[s] = {{x.x(), x.y(), x.z(), kernels.poly6_coeff * volumes[sorted[s]]}};
  }

  // Each thread owns whole z-planes of nodes and adds the particles within h of a plane in sorted order:
  // (C.1) W = a (1 - d^2/h^2)^3 = a ((h^2 - d^2) / h^2)^3.
  const double inv_h2 = 1.0 / h2;
  const long reach = ceilIndex(h * inv_cell) + 1;
  double* values = grid->values.data();
  const int threads = std::max(1, std::min<int>(threadCount(config.num_threads), int(nz)));
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (long k = 0; k < long(nz); ++k) {
    const double plane_z = origin.z() + double(k) * cell;
    const size_t first_plane = size_t(std::max(0L, k - reach));
    const size_t last_plane = size_t(std::min(long(nz) - 1, k + reach));
    double* plane = values + size_t(k) * nx * ny;
    for (uint32_t s = plane_start[first_plane]; s < plane_start[last_plane + 1]; ++s) {
      const double px = splats[s][0], py = splats[s][1], weight = splats[s][3];
      const double dz = plane_z - splats[s][2];
      const double disc2 = h2 - dz * dz;  // squared radius of the support disc in this plane
      if (disc2 <= 0.0) continue;
      const double disc = std::sqrt(disc2);
      const long j0 = std::max(0L, ceilIndex((py - disc - origin.y()) * inv_cell));
      const long j1 = std::min(long(ny) - 1, floorIndex((py + disc - origin.y()) * inv_cell));
      const long i0 = std::max(0L, ceilIndex((px - disc - origin.x()) * inv_cell));
      const long i1 = std::min(long(nx) - 1, floorIndex((px + disc - origin.x()) * inv_cell));
      for (long j = j0; j <= j1; ++j) {
        const double dy = origin.y() + double(j) * cell - py;
        const double row2 = disc2 - dy * dy;  // h^2 - dy^2 - dz^2
        if (row2 <= 0.0) continue;
        // The disc's x-extent, not the row's: no square root per row, a few clamped zeros more.
        addKernelRow(plane + size_t(j) * nx, int(i0), int(i1), origin.x() - px, cell, row2, inv_h2, weight);
      }
    }
  }
}

TriangleMesh extractSphSurface(const SphParticles& particles, const SphSurfaceConfig& config) {
  ScalarGrid grid;
  computeSphColorField(particles, config, &grid);
  TriangleMesh mesh;
  marchingCubes(grid, config.iso_value, config.compute_normals, config.num_threads, &mesh);
  return mesh;
}

}  // namespace rc
