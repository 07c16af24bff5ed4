#include "relaxed_connectivity/sph/sph_surface.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace rc {
namespace {

constexpr double kRestDensity = 1000.0;

struct MeshStats {
  bool closed = true;    ///< every edge in exactly two triangles
  bool oriented = true;  ///< ... traversed once in each direction
  long euler = 0;        ///< V - E + F (vertices used by triangles)
  size_t components = 0;
  double volume = 0.0;  ///< signed, > 0 for outward orientation
  double area = 0.0;
};

size_t findRoot(std::vector<size_t>& parent, size_t v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

MeshStats analyze(const TriangleMesh& mesh) {
  MeshStats stats;
  std::unordered_map<uint64_t, int> directed;
  std::vector<size_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), size_t(0));
  std::vector<bool> used(mesh.vertices.size(), false);
  for (const Triangle& t : mesh.triangles) {
    const Vec3& a = mesh.vertices.positions[t[0]];
    const Vec3& b = mesh.vertices.positions[t[1]];
    const Vec3& c = mesh.vertices.positions[t[2]];
    stats.volume += a.dot(b.cross(c)) / 6.0;
    stats.area += 0.5 * (b - a).cross(c - a).norm();
    for (int e = 0; e < 3; ++e) {
      const uint32_t u = t[e], v = t[(e + 1) % 3];
      ++directed[(uint64_t(u) << 32) | v];
      used[u] = true;
      parent[findRoot(parent, u)] = findRoot(parent, v);
    }
  }
  size_t num_edges = 0;
  for (const auto& [key, count] : directed) {
    const uint64_t reverse = (key << 32) | (key >> 32);
    const auto it = directed.find(reverse);
    const int reverse_count = it == directed.end() ? 0 : it->second;
    if (count != 1 || reverse_count != 1) stats.oriented = false;
    if (count + reverse_count != 2) stats.closed = false;
    num_edges += (key >> 32) < (key & 0xffffffffu) || reverse_count == 0 ? 1 : 0;
  }
  size_t num_vertices = 0;
  for (size_t v = 0; v < used.size(); ++v) {
    if (!used[v]) continue;
    ++num_vertices;
    stats.components += findRoot(parent, v) == v;
  }
  stats.euler = long(num_vertices) - long(num_edges) + long(mesh.triangles.size());
  return stats;
}

/// Fluid particles on the lattice s (i, j, k) + s/2 inside the ball |x - center| < radius, volume s^3 each.
size_t addLatticeBall(SphParticles& particles, const Vec3& center, double radius, double spacing) {
  const int n = int(std::ceil(radius / spacing)) + 1;
  size_t added = 0;
  for (int k = -n; k < n; ++k)
    for (int j = -n; j < n; ++j)
      for (int i = -n; i < n; ++i) {
        const Vec3 offset = spacing * Vec3(i + 0.5, j + 0.5, k + 0.5);
        if (offset.norm() >= radius) continue;
        particles.add(center + offset, Vec3::Zero(), kRestDensity * spacing * spacing * spacing,
                      SphParticleKind::kFluid);
        ++added;
      }
  return added;
}

SphSurfaceConfig configFor(double h, double cell_size = 0.0) {
  SphSurfaceConfig config;
  config.smoothing_length = h;
  config.cell_size = cell_size;
  config.rest_density = kRestDensity;
  return config;
}

TEST(SphSurfaceTest, LatticeBallGivesClosedOutwardSphere) {
  const double spacing = 0.01, radius = 12 * spacing, h = 3 * spacing;
  const Vec3 center(0.3, -0.2, 0.1);
  SphParticles particles;
  const size_t count = addLatticeBall(particles, center, radius, spacing);
  const double particle_volume = count * std::pow(spacing, 3);
  const double ball_volume = 4.0 / 3.0 * M_PI * std::pow(radius, 3), ball_area = 4.0 * M_PI * radius * radius;

  const TriangleMesh mesh = extractSphSurface(particles, configFor(h));
  ASSERT_FALSE(mesh.triangles.empty());
  const MeshStats stats = analyze(mesh);
  EXPECT_TRUE(stats.closed);
  EXPECT_TRUE(stats.oriented);
  EXPECT_EQ(stats.euler, 2);
  EXPECT_EQ(stats.components, 1u);
  EXPECT_GT(stats.volume, 0.0);
  const double volume_error = stats.volume / ball_volume - 1.0, area_error = stats.area / ball_area - 1.0;
  std::printf(
      "ball R = 12 dx, h = 3 dx, cell h/2: %zu particles (volume %+.2f%%), %zu vertices, %zu triangles, "
      "volume %+.2f%%, area %+.2f%%\n",
      count, 100.0 * (particle_volume / ball_volume - 1.0), mesh.vertices.size(), mesh.triangles.size(),
      100.0 * volume_error, 100.0 * area_error);
  EXPECT_LT(std::abs(volume_error), 0.05);
  EXPECT_LT(std::abs(area_error), 0.08);

  // Vertices near the sphere, normals radial and outward, every triangle facing outwards.
  ASSERT_EQ(mesh.vertices.normals.size(), mesh.vertices.size());
  double min_normal_dot = 1.0, max_radius_error = 0.0;
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Vec3 r = mesh.vertices.positions[v] - center;
    min_normal_dot = std::min(min_normal_dot, mesh.vertices.normals[v].dot(r.normalized()));
    max_radius_error = std::max(max_radius_error, std::abs(r.norm() - radius));
    EXPECT_NEAR(mesh.vertices.normals[v].norm(), 1.0, 1e-12);
  }
  size_t inward_faces = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3& a = mesh.vertices.positions[t[0]];
    const Vec3 normal = (mesh.vertices.positions[t[1]] - a).cross(mesh.vertices.positions[t[2]] - a);
    inward_faces += normal.dot(a - center) <= 0.0;
  }
  std::printf("  max |r - R| = %.3f dx, min normal . radial = %.4f\n", max_radius_error / spacing,
              min_normal_dot);
  EXPECT_EQ(inward_faces, 0u);
  EXPECT_GT(min_normal_dot, 0.95);
  EXPECT_LT(max_radius_error, spacing);
}

TEST(SphSurfaceTest, ParticleDensitiesGiveTheSameSurfaceAsTheRestDensity) {
  const double spacing = 0.01, h = 3 * spacing;
  SphParticles particles;
  addLatticeBall(particles, Vec3::Zero(), 6 * spacing, spacing);
  const TriangleMesh with_rest_density = extractSphSurface(particles, configFor(h));
  for (double& rho : particles.densities) rho = kRestDensity;
  SphSurfaceConfig config = configFor(h);
  config.rest_density = 0.0;
  const TriangleMesh with_densities = extractSphSurface(particles, config);
  ASSERT_EQ(with_densities.triangles, with_rest_density.triangles);
  ASSERT_EQ(with_densities.vertices.positions, with_rest_density.vertices.positions);
  // Half the density doubles the volumes: a larger surface.
  for (double& rho : particles.densities) rho = 0.5 * kRestDensity;
  EXPECT_GT(analyze(extractSphSurface(particles, config)).volume, 1.2 * analyze(with_densities).volume);
}

TEST(SphSurfaceTest, CellSizeHalvingConvergesOnTheLatticeBall) {
  // Reference: the iso-surface of the same field at cell h/16.
  const double spacing = 0.01, h = 3 * spacing;
  SphParticles particles;
  addLatticeBall(particles, Vec3::Zero(), 8 * spacing, spacing);
  const double reference = analyze(extractSphSurface(particles, configFor(h, h / 16))).volume;
  double previous_error = std::numeric_limits<double>::infinity();
  for (const double divisor : {1.0, 2.0, 4.0, 8.0}) {
    const MeshStats stats = analyze(extractSphSurface(particles, configFor(h, h / divisor)));
    const double error = std::abs(stats.volume / reference - 1.0);
    std::printf("lattice ball R = 8 dx, cell h/%g: volume error vs cell h/16 %.4f%%\n", divisor,
                100.0 * error);
    EXPECT_TRUE(stats.closed);
    EXPECT_EQ(stats.euler, 2);
    EXPECT_LT(error, previous_error);
    previous_error = error;
  }
  EXPECT_LT(previous_error, 0.002);
}

TEST(SphSurfaceTest, SingleParticleConvergesToTheAnalyticIsoSphere) {
  // One particle of volume h^3: c(r) = h^3 a (1 - r^2/h^2)^3 = iso at r* = h sqrt(1 - (iso / (a h^3))^(1/3)).
  const double h = 0.1, iso = 0.5;
  SphParticles particles;
  particles.add(Vec3(0.01, 0.02, -0.03), Vec3::Zero(), kRestDensity * h * h * h, SphParticleKind::kFluid);
  const double peak = 315.0 / (64.0 * M_PI);
  const double iso_radius = h * std::sqrt(1.0 - std::cbrt(iso / peak));
  const double exact = 4.0 / 3.0 * M_PI * std::pow(iso_radius, 3);
  double previous_error = std::numeric_limits<double>::infinity();
  for (const double divisor : {2.0, 4.0, 8.0, 16.0, 32.0}) {
    const MeshStats stats = analyze(extractSphSurface(particles, configFor(h, h / divisor)));
    const double error = std::abs(stats.volume / exact - 1.0);
    std::printf("one particle, r* = %.3f h, cell h/%g: volume error %.4f%%\n", iso_radius / h, divisor,
                100.0 * error);
    EXPECT_TRUE(stats.closed);
    EXPECT_TRUE(stats.oriented);
    EXPECT_EQ(stats.euler, 2);
    EXPECT_LT(error, previous_error);
    previous_error = error;
  }
  EXPECT_LT(previous_error, 0.005);
}

TEST(SphSurfaceTest, SeparateBlobsGiveSeparateComponents) {
  const double spacing = 0.01, h = 3 * spacing;
  SphParticles particles;
  addLatticeBall(particles, Vec3::Zero(), 5 * spacing, spacing);
  addLatticeBall(particles, Vec3(14 * spacing, 3 * spacing, 0.0), 5 * spacing, spacing);
  const MeshStats stats = analyze(extractSphSurface(particles, configFor(h)));
  EXPECT_TRUE(stats.closed);
  EXPECT_TRUE(stats.oriented);
  EXPECT_EQ(stats.components, 2u);
  EXPECT_EQ(stats.euler, 4);
  EXPECT_GT(stats.volume, 0.0);
}

TEST(SphSurfaceTest, ParticleSelectionAndBoundaryParticles) {
  const double spacing = 0.01, h = 3 * spacing;
  SphParticles particles;
  addLatticeBall(particles, Vec3::Zero(), 5 * spacing, spacing);
  for (auto& kind : particles.kinds) kind = SphParticleKind::kStaticBoundary;
  SphSurfaceConfig config = configFor(h);
  EXPECT_TRUE(extractSphSurface(particles, config).triangles.empty());  // fluid only: nothing
  config.particles = SphSurfaceParticles::kFluidAndBoundary;
  const MeshStats stats = analyze(extractSphSurface(particles, config));
  EXPECT_EQ(stats.components, 1u);
  EXPECT_EQ(stats.euler, 2);
}

TEST(SphSurfaceTest, EmptyAndSingleParticleInputs) {
  const double spacing = 0.01, h = 3 * spacing;
  SphParticles particles;
  const SphSurfaceConfig config = configFor(h);
  ScalarGrid grid;
  computeSphColorField(particles, config, &grid);
  EXPECT_EQ(grid.size(), 0u);
  EXPECT_TRUE(extractSphSurface(particles, config).triangles.empty());
  // A lone lattice particle peaks at a dx^3 = 0.058 < iso: no surface.
  particles.add(Vec3(1.0, 2.0, 3.0), Vec3::Zero(), kRestDensity * std::pow(spacing, 3),
                SphParticleKind::kFluid);
  const TriangleMesh lone = extractSphSurface(particles, config);
  EXPECT_TRUE(lone.triangles.empty());
  EXPECT_TRUE(lone.vertices.empty());
  // A heavy one (volume h^3) gives a small closed sphere.
  particles.masses[0] = kRestDensity * h * h * h;
  const TriangleMesh heavy = extractSphSurface(particles, config);
  const MeshStats stats = analyze(heavy);
  EXPECT_GE(heavy.triangles.size(), 8u);
  EXPECT_TRUE(stats.closed);
  EXPECT_EQ(stats.euler, 2);
  EXPECT_GT(stats.volume, 0.0);
}

TEST(SphSurfaceTest, MarchingCubesIsWatertightOnRandomFields) {
  // Random node values (and values exactly at the iso level) exercise all 256 cases; the border is outside.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<bool> seen(256, false);
  for (int trial = 0; trial < 40; ++trial) {
    ScalarGrid grid;
    grid.cell_size = 0.5;
    grid.dims = {{9, 10, 11}};
    grid.values.assign(grid.size(), 0.0);
    for (size_t k = 1; k + 1 < grid.dims[2]; ++k)
      for (size_t j = 1; j + 1 < grid.dims[1]; ++j)
        for (size_t i = 1; i + 1 < grid.dims[0]; ++i) {
          const double u = uniform(rng);
          grid.values[grid.index(i, j, k)] = trial % 2 ? std::round(2.0 * u) / 2.0 : u;
        }
    for (size_t k = 0; k + 1 < grid.dims[2]; ++k)
      for (size_t j = 0; j + 1 < grid.dims[1]; ++j)
        for (size_t i = 0; i + 1 < grid.dims[0]; ++i) {
          int config = 0;
          for (int c = 0; c < 8; ++c)
            config |= int(grid.at(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)) >= 0.5) << c;
          seen[size_t(config)] = true;
        }
    TriangleMesh mesh;
    marchingCubes(grid, 0.5, true, 0, &mesh);
    const MeshStats stats = analyze(mesh);
    ASSERT_TRUE(stats.closed) << "trial " << trial;
    ASSERT_TRUE(stats.oriented) << "trial " << trial;
    EXPECT_GT(stats.volume, 0.0) << "trial " << trial;
    for (const Triangle& t : mesh.triangles) EXPECT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), true), 256);
}

TEST(SphSurfaceTest, MarchingCubesVolumeOfAnInsideBlockIsExact) {
  // A 3 x 4 x 5 node block of value 1 in a field of 0, iso 0.5: faces half a cell outside the block.
  ScalarGrid grid;
  grid.cell_size = 0.25;
  grid.dims = {{7, 8, 9}};
  grid.values.assign(grid.size(), 0.0);
  for (size_t k = 2; k < 7; ++k)
    for (size_t j = 2; j < 6; ++j)
      for (size_t i = 2; i < 5; ++i) grid.values[grid.index(i, j, k)] = 1.0;
  TriangleMesh mesh;
  marchingCubes(grid, 0.5, false, 1, &mesh);
  const MeshStats stats = analyze(mesh);
  EXPECT_TRUE(stats.closed);
  EXPECT_EQ(stats.euler, 2);
  EXPECT_TRUE(mesh.vertices.normals.empty());
  // Chamfered box: 3 x 4 x 5 cells minus the corner tetrahedra and edge prisms of the marching-cubes cut.
  const double c3 = std::pow(grid.cell_size, 3);
  // Edge cubes keep a prism of 1/8 of their 1/4, corner cubes a tetrahedron of 1/48 of their 1/8.
  const double box = 3.0 * 4.0 * 5.0, edge_cut = 4.0 * (2.0 + 3.0 + 4.0) / 8.0,
               corner_cut = 8.0 * (1.0 / 8 - 1.0 / 48);
  EXPECT_NEAR(stats.volume / c3, box - edge_cut - corner_cut, 1e-9);
}

TEST(SphSurfaceTest, ResultDoesNotDependOnTheThreadCount) {
  const double spacing = 0.01, h = 3 * spacing;
  SphParticles particles;
  addLatticeBall(particles, Vec3::Zero(), 9 * spacing, spacing);
  std::mt19937 rng(3);
  std::normal_distribution<double> jitter(0.0, 0.2 * spacing);
  for (Vec3& x : particles.positions) x += Vec3(jitter(rng), jitter(rng), jitter(rng));
  SphSurfaceConfig config = configFor(h, h / 3);
  config.num_threads = 1;
  const TriangleMesh serial = extractSphSurface(particles, config);
  config.num_threads = 4;
  const TriangleMesh parallel = extractSphSurface(particles, config);
  ASSERT_FALSE(serial.triangles.empty());
  EXPECT_EQ(serial.triangles, parallel.triangles);
  EXPECT_EQ(serial.vertices.positions, parallel.vertices.positions);
  EXPECT_EQ(serial.vertices.normals, parallel.vertices.normals);
}

TEST(SphSurfaceTest, BadInputThrowsNamingTheProblem) {
  SphParticles particles;
  addLatticeBall(particles, Vec3::Zero(), 0.03, 0.01);
  const auto expectThrow = [&](const SphSurfaceConfig& config, const std::string& needle) {
    try {
      extractSphSurface(particles, config);
      ADD_FAILURE() << "no exception, expected one naming " << needle;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  SphSurfaceConfig config = configFor(0.03);
  config.smoothing_length = 0.0;
  expectThrow(config, "smoothing_length");
  config = configFor(0.03);
  config.iso_value = 0.0;
  expectThrow(config, "iso_value");
  config = configFor(0.03);
  config.cell_size = -1.0;
  expectThrow(config, "cell_size");
  config = configFor(0.03);
  config.max_grid_nodes = 100;
  expectThrow(config, "max_grid_nodes");
  config.max_grid_nodes = SphSurfaceConfig().max_grid_nodes;
  config.rest_density = 0.0;  // the densities are all 0
  expectThrow(config, "particle 0 has density");
  particles.positions[3].y() = std::nan("");
  expectThrow(configFor(0.03), "particle 3 has a non-finite position");
}

TEST(SphSurfaceTest, TimingFor100kParticles) {
  // A 50 x 50 x 40 lattice block (100k particles), h = 3 dx, as in the solver scenes; timing printed only.
  const double spacing = 0.01, h = 3 * spacing;
  SphParticles particles;
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 50; ++j)
      for (int i = 0; i < 50; ++i)
        particles.add(spacing * Vec3(i, j, k), Vec3::Zero(), kRestDensity * std::pow(spacing, 3),
                      SphParticleKind::kFluid);
  for (const double divisor : {2.0, 4.0}) {
    const SphSurfaceConfig config = configFor(h, h / divisor);
    double best_field = 1e30, best_total = 1e30;
    TriangleMesh mesh;
    ScalarGrid grid;
    for (int repeat = 0; repeat < 3; ++repeat) {
      const auto t0 = std::chrono::steady_clock::now();
      computeSphColorField(particles, config, &grid);
      const auto t1 = std::chrono::steady_clock::now();
      marchingCubes(grid, config.iso_value, true, config.num_threads, &mesh);
      const auto t2 = std::chrono::steady_clock::now();
      best_field = std::min(best_field, std::chrono::duration<double, std::milli>(t1 - t0).count());
      best_total = std::min(best_total, std::chrono::duration<double, std::milli>(t2 - t0).count());
    }
    const MeshStats stats = analyze(mesh);
    std::printf(
        "100k particles, cell h/%g (%zu x %zu x %zu nodes): field %.1f ms, total %.1f ms, %zu triangles\n",
        divisor, grid.dims[0], grid.dims[1], grid.dims[2], best_field, best_total, mesh.triangles.size());
    EXPECT_TRUE(stats.closed);
    EXPECT_EQ(stats.euler, 2);
    // The block [0, 0.49] x [0, 0.49] x [0, 0.39] of particle cells is 0.5 x 0.5 x 0.4 (rounded corners).
    EXPECT_NEAR(stats.volume, 0.5 * 0.5 * 0.4, 0.02 * 0.1);
  }
}

}  // namespace
}  // namespace rc
