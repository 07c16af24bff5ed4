// Mesh generation (thesis 6.1) with CGAL: an advancing-front reconstruction of sampled analytic surfaces is a
// closed (sphere) or bounded (disc) oriented manifold agreeing with the surfel normals and within a fraction
// of the sampling of the exact surface; Garland-Heckbert simplification keeps the topology, meets its
// triangle count, and its geometric error grows as the bound allows fewer triangles and stays within the
// error bound it was given; bad input gives a clear error. With ../shared: the Stanford bunny.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "../shared_data.h"
#include "relaxed_connectivity/convert/geometric_error.h"
#include "relaxed_connectivity/convert/mesh_simplification.h"
#include "relaxed_connectivity/convert/surface_reconstruction.h"
#include "relaxed_connectivity/io/ply_io.h"
#include "relaxed_connectivity/mesh/mesh_metrics.h"
#include "sphere_surfels.h"

namespace rc {
namespace {

/// n Fibonacci points on the unit sphere, outward normals, radii of the sampling.
SurfelCloud sphereSurfels(size_t n) {
  return fibonacciSphereSurfels(n, std::sqrt(4.0 / double(n)));
}

/// The largest distance of a mesh's vertices and triangle centroids from the unit sphere.
double sphereDeviation(const TriangleMesh& m) {
  double worst = 0;
  for (const Triangle& t : m.triangles) {
    Vec3 centroid = Vec3::Zero();
    for (uint32_t v : t) {
      worst = std::max(worst, std::abs(m.vertices.positions[v].norm() - 1.0));
      centroid += m.vertices.positions[v] / 3.0;
    }
    worst = std::max(worst, std::abs(centroid.norm() - 1.0));
  }
  return worst;
}

#define REQUIRE_CGAL() \
  if (!meshGenerationAvailable()) GTEST_SKIP() << "this build has no CGAL (libcgal-dev)"

TEST(MeshGeneration, TheReconstructedSphereIsClosedOrientedOutwardAndClose) {
  REQUIRE_CGAL();
  const SurfelCloud surfels = sphereSurfels(4000);
  ReconstructionStats stats;
  const TriangleMesh mesh = reconstructSurface(surfels, {}, &stats);
  EXPECT_TRUE(isWatertight(mesh));
  EXPECT_EQ(stats.components, 1u);
  EXPECT_EQ(stats.unused_surfels, 0u);
  EXPECT_EQ(stats.boundary_edges, 0u);
  EXPECT_EQ(mesh.triangles.size(), 2 * surfels.size() - 4);  // Euler: a closed genus-0 triangulation
  EXPECT_GT(signedVolume(mesh), 0.0);                        // outward, as the normals
  EXPECT_NEAR(signedVolume(mesh), 4.0 / 3.0 * M_PI, 0.01);
  // Interpolating: the centroids sit inside by about h^2 / 8 for a sampling h of 0.056.
  EXPECT_LT(sphereDeviation(mesh), 0.002);
  const GeometricError e = geometricError(mesh, surfels);
  std::printf("sphere: %zu triangles, Hausdorff %.2e, RMS %.2e of the diagonal\n", mesh.triangles.size(),
              e.hausdorff, e.rms);
  EXPECT_LT(e.points_to_mesh_max, 1e-12);  // every surfel is a vertex
  EXPECT_LT(e.hausdorff, 0.002);
}

TEST(MeshGeneration, ScaleSpaceAndPoissonAreSelectable) {
  REQUIRE_CGAL();
  // A noisy sphere (0.5 % of the radius along the normal): scale space meshes the smoothed points and keeps
  // the triangles on the original ones; Poisson fits a watertight implicit surface with new vertices.
  SurfelCloud surfels = sphereSurfels(4000);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 0.005);
  for (Vec3& p : surfels.positions) p *= 1 + noise(rng);
  for (const char* name : {"scale_space", "poisson"}) {
    ReconstructionOptions options;
    options.method = reconstructionMethodFromName(name);
    ReconstructionStats stats;
    const TriangleMesh mesh = reconstructSurface(surfels, options, &stats);
    const GeometricError e = geometricError(mesh, surfels);
    std::printf(
        "noisy sphere, %s: %zu triangles, %zu vertices, %zu components, %zu boundary edges, Hausdorff "
        "%.2e, RMS %.2e\n",
        name, mesh.triangles.size(), mesh.vertices.size(), stats.components, stats.boundary_edges,
        e.hausdorff, e.rms);
    EXPECT_TRUE(isWatertight(mesh)) << name;
    EXPECT_EQ(stats.components, 1u) << name;
    // closed and outward; (Poisson: 486 triangles at the default mesher distance, inscribed: -2.6 %)
    EXPECT_NEAR(signedVolume(mesh), 4.0 / 3.0 * M_PI, 0.2) << name;
    EXPECT_LT(e.rms, 0.005) << name;
    if (options.method == ReconstructionMethod::kScaleSpace) {
      EXPECT_EQ(mesh.vertices.size(), surfels.size());  // the surfels themselves
      EXPECT_LT(e.points_to_mesh_max, 1e-12);
    } else {
      EXPECT_LT(sphereDeviation(mesh), 0.03);  // new vertices near the sphere, the noise averaged
    }
  }
  EXPECT_THROW(reconstructionMethodFromName("cocone"), std::invalid_argument);
  EXPECT_STREQ(reconstructionMethodName(ReconstructionMethod::kPoisson), "poisson");
}

TEST(MeshGeneration, NormalsPointingInwardTurnTheMesh) {
  REQUIRE_CGAL();
  SurfelCloud surfels = sphereSurfels(1000);
  for (Vec3& n : surfels.normals) n = -n;
  ReconstructionStats stats;
  const TriangleMesh mesh = reconstructSurface(surfels, {}, &stats);
  EXPECT_LT(signedVolume(mesh), 0.0);  // inward, as the normals say
  EXPECT_TRUE(isWatertight(mesh));
  EXPECT_EQ(stats.components, 1u);
}

TEST(MeshGeneration, AnOpenDiscKeepsItsBoundary) {
  REQUIRE_CGAL();
  SurfelCloud disc;
  std::mt19937 random(5);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  for (int i = -20; i <= 20; ++i)
    for (int j = -20; j <= 20; ++j) {
      const Vec3 p((i + jitter(random)) * 0.05, (j + jitter(random)) * 0.05, 0);
      if (p.head<2>().norm() > 1.0) continue;
      disc.positions.push_back(p);
      disc.normals.push_back(Vec3::UnitZ());
    }
  ReconstructionStats stats;
  const TriangleMesh mesh = reconstructSurface(disc, {}, &stats);
  const EdgeStatistics edges = edgeStatistics(mesh);
  EXPECT_EQ(edges.non_manifold_edges, 0u);
  EXPECT_GT(edges.boundary_edges, 60u);  // the rim: about 2 pi / 0.05 = 126 edges
  EXPECT_LT(edges.boundary_edges, 200u);
  EXPECT_EQ(stats.components, 1u);
  for (const Triangle& t : mesh.triangles) {  // facing +z, as the normals
    const Vec3& a = mesh.vertices.positions[t[0]];
    EXPECT_GT((mesh.vertices.positions[t[1]] - a).cross(mesh.vertices.positions[t[2]] - a).z(), 0.0);
  }
}

TEST(MeshGeneration, SimplificationKeepsTopologyAndItsErrorFallsWithTheBound) {
  REQUIRE_CGAL();
  const SurfelCloud surfels = sphereSurfels(6000);
  const TriangleMesh dense = reconstructSurface(surfels);
  double previous = std::numeric_limits<double>::infinity();
  for (const size_t target : {200, 800, 3200}) {
    SimplificationOptions o;
    o.target_triangles = target;
    SimplificationStats stats;
    const TriangleMesh simple = simplifyMesh(dense, o, &stats);
    const GeometricError e = geometricError(simple, surfels);
    std::printf("sphere to %zu triangles: %zu (%zu collapses), Hausdorff %.2e, RMS %.2e\n", target,
                simple.triangles.size(), stats.collapses, e.hausdorff, e.rms);
    EXPECT_LE(simple.triangles.size(), target);
    EXPECT_GE(simple.triangles.size(), target - 4);
    EXPECT_TRUE(isWatertight(simple));  // genus 0 kept: V - E + F = 2
    EXPECT_EQ(simple.triangles.size() + 4, 2 * simple.vertices.size());
    EXPECT_GT(signedVolume(simple), 0.0);
    EXPECT_LT(e.rms,
              previous);  // more triangles, less error (the RMS: the Hausdorff distance is one sample's)
    EXPECT_LT(e.hausdorff, 0.01);
    previous = e.rms;
  }
  // An error bound: no collapse's quadric error (squared plane distances) exceeds its square, so the surfels
  // stay within about it; a larger bound leaves fewer triangles.
  size_t previous_triangles = dense.triangles.size();
  for (const double bound : {1e-3, 4e-3}) {
    SimplificationOptions o;
    o.max_error = bound;
    const TriangleMesh simple = simplifyMesh(dense, o);
    const GeometricError e = geometricError(simple, surfels);
    std::printf("sphere with error bound %.0e: %zu triangles, Hausdorff %.2e\n", bound,
                simple.triangles.size(), e.hausdorff);
    EXPECT_LT(simple.triangles.size(), previous_triangles / 2);
    EXPECT_LT(e.hausdorff, 2 * bound);
    EXPECT_TRUE(isWatertight(simple));
    previous_triangles = simple.triangles.size();
  }
}

TEST(MeshGeneration, BadInputIsAClearError) {
  REQUIRE_CGAL();
  SurfelCloud few = sphereSurfels(3);
  EXPECT_THROW(reconstructSurface(few), std::invalid_argument);
  SurfelCloud no_normals = sphereSurfels(100);
  no_normals.normals.clear();
  EXPECT_THROW(reconstructSurface(no_normals), std::invalid_argument);
  SurfelCloud nan = sphereSurfels(100);
  nan.positions[17].x() = std::numeric_limits<double>::quiet_NaN();
  try {
    reconstructSurface(nan);
    ADD_FAILURE() << "a NaN surfel was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("surfel 17"), std::string::npos) << e.what();
  }
  TriangleMesh fan;  // three triangles on one edge: not a manifold
  fan.vertices.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 1)};
  fan.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  EXPECT_THROW(simplifyMesh(fan, {10, 0}), std::invalid_argument);
  EXPECT_THROW(simplifyMesh(reconstructSurface(sphereSurfels(100)), {}), std::invalid_argument);  // no bound
}

TEST(MeshGeneration, TheBunnyScanBecomesAManifoldAndSimplifies) {
  REQUIRE_CGAL();
  RC_SKIP_WITHOUT_SHARED_DATA("bunny.ply");
  // The scan's vertices as surfels, with the scan's area-weighted vertex normals.
  const TriangleMesh scan = readPlyMesh(test::sharedDataPath("bunny.ply"));
  SurfelCloud surfels = scan.vertices;
  surfels.normals.assign(surfels.size(), Vec3::Zero());
  for (const Triangle& t : scan.triangles) {
    const Vec3& a = surfels.positions[t[0]];
    const Vec3 n = (surfels.positions[t[1]] - a).cross(surfels.positions[t[2]] - a);
    for (uint32_t v : t) surfels.normals[v] += n;
  }
  std::vector<size_t> keep;
  for (size_t i = 0; i < surfels.size(); ++i)
    if (surfels.normals[i].norm() > 0) keep.push_back(i), surfels.normals[i].normalize();
  surfels.select(keep);
  ReconstructionStats stats;
  const TriangleMesh mesh = reconstructSurface(surfels, {}, &stats);
  const GeometricError dense = geometricError(mesh, surfels);
  std::printf(
      "bunny: %zu surfels -> %zu triangles, %zu components, %zu unused, %zu boundary edges, %zu "
      "flipped; Hausdorff %.2e RMS %.2e\n",
      surfels.size(), stats.triangles, stats.components, stats.unused_surfels, stats.boundary_edges,
      stats.flipped_components, dense.hausdorff, dense.rms);
  EXPECT_LT(stats.unused_surfels, surfels.size() / 100);
  // Measured: RMS 5.0e-4 of the diagonal; the Hausdorff distance (2.5e-2) is where the reconstruction closes
  // the scan's open base with large triangles far from any surfel.
  EXPECT_LT(dense.rms, 1e-3);
  EXPECT_EQ(stats.components, 1u);
  EXPECT_GT(signedVolume(mesh), 0.0);  // outward on the whole (the scan's base is open)
  double previous = 0;
  for (const size_t target : {20000, 5000, 1250}) {
    SimplificationOptions o;
    o.target_triangles = target;
    const TriangleMesh simple = simplifyMesh(mesh, o);
    const GeometricError e = geometricError(simple, surfels);
    std::printf("bunny to %zu triangles: %zu, Hausdorff %.2e, RMS %.2e\n", target, simple.triangles.size(),
                e.hausdorff, e.rms);
    EXPECT_LE(simple.triangles.size(), target);
    EXPECT_EQ(edgeStatistics(simple).non_manifold_edges, 0u);
    EXPECT_GT(e.rms, previous);  // fewer triangles, more error
    previous = e.rms;
  }
}

}  // namespace
}  // namespace rc
