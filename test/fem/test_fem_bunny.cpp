// Thesis Fig. 9.10 preparation and the polygon-cut scenes: the open bunny scan (bunny.ply: 223 boundary
// edges) closed by hole filling and decimated is a closed manifold TetGen meshes; the Fig. 9.9 and 9.10
// scenes load, cut progressively and stay valid (volume conserved, finite, above the ground).
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include "relaxed_connectivity/fem/cholmod_solver.h"
#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/fem/fem_simulation.h"
#include "relaxed_connectivity/fem/tetgen_mesh.h"
#include "relaxed_connectivity/io/ply_io.h"
#include "relaxed_connectivity/mesh/surface_closing.h"
#include "relaxed_connectivity/mesh/surface_decimation.h"

namespace rc {
namespace {

const std::string kBunny = std::string(RC_SHARED_DATA_DIR) + "/bunny.ply";

std::string femSceneDir() {
  const std::string here = __FILE__;
  return here.substr(0, here.rfind("/test/")) + "/config/fem/";
}

double enclosedVolume(const TriangleMesh& m) {
  double v = 0.0;
  const auto& x = m.vertices.positions;
  for (const auto& t : m.triangles) v += x[t[0]].dot(x[t[1]].cross(x[t[2]])) / 6.0;
  return v;
}

TEST(SurfaceClosing, FillsASquareHoleInACubeWithConsistentOrientation) {
  // Unit cube surface with the top face missing: 4 boundary edges, one hole, 2 triangles added.
  TriangleMesh cube;
  cube.vertices.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0),
                             Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(1, 1, 1), Vec3(0, 1, 1)};
  cube.triangles = {{0, 2, 1}, {0, 3, 2}, {0, 1, 5}, {0, 5, 4}, {1, 2, 6},
                    {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  EXPECT_EQ(countBoundaryEdges(cube), 4);
  HoleFillingStats stats;
  const TriangleMesh closed = closeSurfaceHoles(cube, &stats);
  EXPECT_EQ(stats.holes, 1);
  EXPECT_EQ(stats.boundary_edges, 4);
  EXPECT_EQ(stats.added_triangles, 2);
  EXPECT_NEAR(stats.max_dihedral_degrees, 90.0, 1e-9);  // the flat lid meets the sides at right angles
  EXPECT_EQ(countBoundaryEdges(closed), 0);
  EXPECT_NEAR(enclosedVolume(closed), 1.0, 1e-14);  // outward orientation: positive unit volume
  // Inconsistent orientation is named.
  TriangleMesh bad = cube;
  std::swap(bad.triangles[0][1], bad.triangles[0][2]);
  EXPECT_THROW(closeSurfaceHoles(bad), std::invalid_argument);
}

TEST(SurfaceClosing, BunnyClosedDecimatedAndTetrahedralised) {
  if (!std::filesystem::exists(kBunny)) GTEST_SKIP() << "needs ../shared/data: " << kBunny << " is missing";
  const TriangleMesh bunny = readPlyMesh(kBunny);
  EXPECT_EQ(countBoundaryEdges(bunny), 223);
  HoleFillingStats stats;
  const TriangleMesh closed = closeSurfaceHoles(bunny, &stats);
  EXPECT_EQ(stats.boundary_edges, 223);
  EXPECT_EQ(countBoundaryEdges(closed), 0);
  EXPECT_EQ(stats.added_triangles, 223 - 2 * stats.holes);
  EXPECT_GT(enclosedVolume(closed), 0.0);
  DecimationOptions options;
  options.target_vertices = 1500;
  const TriangleMesh coarse = decimateSurface(closed, options);
  EXPECT_EQ(coarse.vertices.positions.size(), 1500u);
  EXPECT_EQ(countBoundaryEdges(coarse), 0);
  EXPECT_EQ(coarse.triangles.size(), 2u * 1500 - 4);  // closed genus-0 surface: F = 2 V - 4
  EXPECT_NEAR(enclosedVolume(coarse) / enclosedVolume(closed), 1.0, 0.01);
  std::printf(
      "bunny: %d holes (largest %d edges, max dihedral %.1f deg), %zu -> %zu vertices, volume %.6g -> %.6g\n",
      stats.holes, stats.largest_hole, stats.max_dihedral_degrees, bunny.vertices.positions.size(),
      coarse.vertices.positions.size(), enclosedVolume(closed), enclosedVolume(coarse));
  if (!tetgenAvailable()) GTEST_SKIP() << "no TetGen in this build";
  TetgenOptions tet;
  tet.max_radius_edge_ratio = 2.0;
  const PolyhedralMesh mesh = toPolyhedralMesh(tetrahedralizeSurface(coarse, tet));
  EXPECT_NEAR(mesh.volume() / enclosedVolume(coarse), 1.0, 1e-7);  // TetGen may flip near-coplanar pairs
  std::printf("bunny TetGen: %d nodes, %d elements\n", mesh.numNodes(), mesh.numElements());
}

// Volume enclosed by the deformed boundaries of all bodies (crack faces included: they cancel while closed).
double totalVolume(const FemSimulation& sim) {
  double v = 0.0;
  for (int b = 0; b < sim.numBodies(); ++b) v += sim.body(b).currentVolume();
  return v;
}

struct SceneRun {
  int nodes = 0, elements = 0, bodies = 0, crack_faces = 0;
  FemPhaseTimes times;
  double rest_volume = 0.0, max_volume_change = 0.0, lowest = INFINITY;
  bool finite = true;
};

SceneRun runScene(const FemScene& scene, long steps) {
  FemSimulation sim(scene);
  SceneRun r;
  r.rest_volume = totalVolume(sim);
  for (long s = 0; s < steps; ++s) {
    sim.step();
    r.max_volume_change = std::max(r.max_volume_change, std::abs(totalVolume(sim) / r.rest_volume - 1.0));
    r.lowest = std::min(r.lowest, sim.minGroundDistance());
  }
  for (int b = 0; b < sim.numBodies(); ++b) {
    r.finite = r.finite && sim.body(b).positions().allFinite() && sim.body(b).velocities().allFinite();
    r.crack_faces += sim.body(b).model().mesh().numCrackFaces();
  }
  r.times = sim.phaseTimes();
  std::printf("phases [s]: bases %.3f rotations %.3f assembly %.3f solve %.3f topology %.3f (%ld steps)\n",
              r.times.integration, r.times.rotations, r.times.assembly, r.times.solve, r.times.topology,
              steps);
  r.nodes = sim.numNodes();
  r.elements = sim.numElements();
  r.bodies = sim.numBodies();
  return r;
}

TEST(PolygonCutScenes, Fig99BlockSlicedProgressively) {
  const FemScene scene = loadFemScene(femSceneDir() + "fig9_9_sliced_block.yaml");
  ASSERT_EQ(scene.cuts.size(), 4u);
  for (const FemSceneCut& cut : scene.cuts) EXPECT_EQ(cut.polygons.size(), 8u);
  const double end = scene.cuts.back().time + scene.cuts.back().duration + 0.1;
  const SceneRun r = runScene(scene, long(std::ceil(end / scene.dynamics.time_step)));
  EXPECT_TRUE(r.finite);
  EXPECT_EQ(r.bodies, 5);  // four slices off the block
  // Planar slices split the 9 cells they cross once; the curved one splits some cells several times.
  EXPECT_EQ(r.elements, 81);
  EXPECT_EQ(r.nodes, 440);
  EXPECT_GE(r.lowest, -1e-9);
  EXPECT_LT(r.max_volume_change, 0.15);  // Y = 50, nu = 0.3: the soft block sags under its own weight
  std::printf(
      "Fig. 9.9: %d nodes, %d elements, %d bodies, %d crack faces, max |dV/V| %.3g (thesis: 1214 / 60)\n",
      r.nodes, r.elements, r.bodies, r.crack_faces, r.max_volume_change);
}

TEST(PolygonCutScenes, Fig910BunnyRestsStablyOnTheGround) {
  // Regression: the sliver-rich TetGen bunny (min dihedral ~1.7 deg, lumped masses down to 3e-8 against a
  // mean of 5e-5) dropped 7e-4 onto the ground. Contact nodes left active with a pulling reaction after the
  // last contact round got a negative friction limit, which accelerated them tangentially by mu |J| / m (8500
  // m/s at step 2, elastic energy 2.5e6, volume -117 % at step 3).
  if (!std::filesystem::exists(kBunny)) GTEST_SKIP() << "needs ../shared/data: " << kBunny << " is missing";
  if (!tetgenAvailable()) GTEST_SKIP() << "no TetGen in this build";
  FemScene scene = loadFemScene(femSceneDir() + "fig9_10_bunny.yaml");
  scene.cuts.clear();
  scene.dynamics.solver = cholmodAvailable() ? WarpedDynamicsOptions::Solver::kCholmod
                                             : WarpedDynamicsOptions::Solver::kSimplicialLDLT;
  FemSimulation sim(scene);
  ASSERT_EQ(sim.numBodies(), 1);
  const double v0 = sim.body(0).currentVolume(), e0 = sim.body(0).totalEnergy();
  double max_volume_change = 0.0, max_energy = 0.0, max_speed = 0.0, max_rise = -INFINITY, previous = e0;
  for (int s = 0; s < 6; ++s) {
    sim.step();
    const WarpedDynamics& body = sim.body(0);
    max_volume_change = std::max(max_volume_change, std::abs(body.currentVolume() / v0 - 1.0));
    max_energy = std::max(max_energy, body.totalEnergy());
    max_rise = std::max(max_rise, (body.totalEnergy() - previous) / e0);
    previous = body.totalEnergy();
    for (int i = 0; i < body.numNodes(); ++i)
      max_speed = std::max(max_speed, body.velocities().segment<3>(3 * i).norm());
  }
  std::printf(
      "Fig. 9.10 resting: max |dV/V| %.3g, max E / E0 %.6f, max step rise %.2e E0, max speed %.3g, min z "
      "%.3g\n",
      max_volume_change, max_energy / e0, max_rise, max_speed, sim.minGroundDistance());
  EXPECT_LT(max_volume_change, 0.002);  // measured 6.8e-4 (before the fix: 1.17)
  // Landing inside the implicit solve never adds energy: measured max E 0.9896 E0, every step loses energy
  // (before contacts moved into the solve: 1.70 E0 from the landing projection; before the fix: 1.5e6).
  EXPECT_LT(max_energy, e0);
  EXPECT_LT(max_rise, 0.0);
  EXPECT_LT(max_speed, 0.4);  // measured 0.30 m/s (before the fix: 8500 m/s)
  EXPECT_GE(sim.minGroundDistance(), -1e-12);
}

}  // namespace
}  // namespace rc
