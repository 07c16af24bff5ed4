// Tetrahedral meshes from TetGen (closed surfaces -> PolyhedralMesh, .node/.ele files) and the CHOLMOD
// solver option of the implicit Euler (thesis 9.1.4) against Eigen's SimplicialLDLT and warm-started PCG.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "relaxed_connectivity/fem/cholmod_solver.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/tetgen_mesh.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/off_io.h"

namespace rc {
namespace {

TriangleMesh makeSurface(std::vector<Vec3> vertices, std::vector<Triangle> triangles) {
  TriangleMesh mesh;
  mesh.vertices.positions = std::move(vertices);
  mesh.triangles = std::move(triangles);
  return mesh;
}

// Axis-aligned box [0, a] x [0, b] x [0, c], outward triangles.
TriangleMesh boxSurface(double a, double b, double c) {
  std::vector<Vec3> v;
  for (int k = 0; k < 8; ++k) v.emplace_back(k & 1 ? a : 0.0, k & 2 ? b : 0.0, k & 4 ? c : 0.0);
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::vector<Triangle> t;
  for (const auto& q : quads) {
    t.push_back({uint32_t(q[0]), uint32_t(q[1]), uint32_t(q[2])});
    t.push_back({uint32_t(q[0]), uint32_t(q[2]), uint32_t(q[3])});
  }
  return makeSurface(v, t);
}

// Icosahedron subdivided `levels` times, vertices on the unit sphere (a closed polyhedral surface).
TriangleMesh icosphereSurface(int levels) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                         {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  for (Vec3& p : v) p.normalize();
  std::vector<Triangle> t = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                             {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                             {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                             {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoint;
    auto mid = [&](uint32_t a, uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return midpoint[key] = uint32_t(v.size() - 1);
    };
    std::vector<Triangle> next;
    for (const Triangle& f : t) {
      const uint32_t ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      next.insert(next.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    t = std::move(next);
  }
  return makeSurface(v, t);
}

double enclosedVolume(const TriangleMesh& surface) {
  double volume = 0.0;
  for (const Triangle& t : surface.triangles) {
    const auto& p = surface.vertices.positions;
    volume += p[t[0]].dot(p[t[1]].cross(p[t[2]])) / 6.0;
  }
  return volume;
}

double tetrahedronVolume(const TetrahedralMesh& mesh, const std::array<int, 4>& t) {
  const auto& n = mesh.nodes;
  return std::abs((n[t[1]] - n[t[0]]).cross(n[t[2]] - n[t[0]]).dot(n[t[3]] - n[t[0]])) / 6.0;
}

double maxRadiusEdgeRatio(const TetrahedralMesh& mesh) {
  double worst = 0.0;
  for (const auto& t : mesh.tetrahedra)
    worst = std::max(worst,
                     radiusEdgeRatio(mesh.nodes[t[0]], mesh.nodes[t[1]], mesh.nodes[t[2]], mesh.nodes[t[3]]));
  return worst;
}

// Smallest dihedral angle in degrees (180 - angle between outward face normals).
double minDihedralDegrees(const TetrahedralMesh& mesh) {
  const double pi = std::acos(-1.0);
  double smallest = 180.0;
  for (const auto& t : mesh.tetrahedra) {
    Vec3 normals[4];
    for (int f = 0; f < 4; ++f) {  // face opposite corner f
      const Vec3& a = mesh.nodes[t[(f + 1) % 4]];
      normals[f] = (mesh.nodes[t[(f + 2) % 4]] - a).cross(mesh.nodes[t[(f + 3) % 4]] - a).normalized();
      if (normals[f].dot(mesh.nodes[t[f]] - a) > 0.0) normals[f] = -normals[f];
    }
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        smallest = std::min(
            smallest, 180.0 - std::acos(std::clamp(normals[i].dot(normals[j]), -1.0, 1.0)) * 180.0 / pi);
  }
  return smallest;
}

std::string temporaryPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("rc_test_fem_tetgen_" + name)).string();
}

void writeText(const std::string& path, const std::string& text) {
  FILE* file = std::fopen(path.c_str(), "w");
  ASSERT_NE(file, nullptr) << path;
  std::fputs(text.c_str(), file);
  std::fclose(file);
}

// The IoError message of reading the pair, or "" when it succeeds.
std::string readError(const std::string& node_text, const std::string& ele_text) {
  const std::string node = temporaryPath("bad.node"), ele = temporaryPath("bad.ele");
  writeText(node, node_text);
  writeText(ele, ele_text);
  try {
    readTetgenMesh(node, ele);
  } catch (const IoError& error) {
    return error.what();
  }
  return "";
}

TEST(TetgenMesh, RadiusEdgeRatioOfTheRegularTetrahedron) {
  EXPECT_NEAR(radiusEdgeRatio(Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, 1, -1), Vec3(-1, -1, 1)),
              std::sqrt(6.0) / 4.0, 1e-14);
}

TEST(TetgenMesh, SwitchesFollowTheOptions) {
  TetgenOptions options;
  EXPECT_EQ(tetgenSwitches(options), "pzq1.414Q");
  options.min_dihedral_degrees = 12;
  options.max_volume = 0.002;
  options.preserve_surface = true;
  options.quiet = false;
  EXPECT_EQ(tetgenSwitches(options), "pzq1.414/12a0.002Y");
  options.max_radius_edge_ratio = 0;
  EXPECT_EQ(tetgenSwitches(options), "pza0.002Y");
}

TEST(TetgenMesh, RejectsOpenAndBrokenSurfaces) {
  if (!tetgenAvailable()) {
    EXPECT_THROW(tetrahedralizeSurface(boxSurface(1, 1, 1)), std::runtime_error);
    GTEST_SKIP() << "build without TetGen";
  }
  TriangleMesh open = boxSurface(1, 1, 1);
  open.triangles.pop_back();
  try {
    tetrahedralizeSurface(open);
    ADD_FAILURE() << "open surface accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("not closed: 3 edges"), std::string::npos) << error.what();
  }
  TriangleMesh bad_index = boxSurface(1, 1, 1);
  bad_index.triangles[4][1] = 8;
  EXPECT_THROW(tetrahedralizeSurface(bad_index), std::invalid_argument);
  TriangleMesh degenerate = boxSurface(1, 1, 1);
  degenerate.triangles[2][2] = degenerate.triangles[2][0];
  EXPECT_THROW(tetrahedralizeSurface(degenerate), std::invalid_argument);
}

TEST(TetgenMesh, QualityMeshesOfClosedSurfacesAreValidPolyhedralMeshes) {
  if (!tetgenAvailable()) GTEST_SKIP() << "build without TetGen";
  struct Case {
    const char* name;
    TriangleMesh surface;
    TetgenOptions options;
  };
  TetgenOptions box_options;
  box_options.max_volume = 0.002;
  box_options.min_dihedral_degrees = 15;
  TetgenOptions sphere_options;
  sphere_options.max_radius_edge_ratio = 1.2;
  sphere_options.min_dihedral_degrees = 10;
  std::vector<Case> cases = {{"box", boxSurface(1.0, 0.6, 0.4), box_options},
                             {"icosphere", icosphereSurface(2), sphere_options}};
  // An unused surface vertex must not survive as a mesh node.
  cases[1].surface.vertices.positions.push_back(Vec3(5, 5, 5));
  for (const Case& c : cases) {
    const TetrahedralMesh tets = tetrahedralizeSurface(c.surface, c.options);
    const PolyhedralMesh mesh = toPolyhedralMesh(tets);
    const double expected = enclosedVolume(c.surface);
    const double ratio = maxRadiusEdgeRatio(tets), dihedral = minDihedralDegrees(tets);
    double largest = 0.0;
    for (const auto& t : tets.tetrahedra) largest = std::max(largest, tetrahedronVolume(tets, t));
    std::printf(
        "%s (%s): %d nodes, %d tetrahedra, volume %.15g (surface %.15g), max radius-edge %.4f, "
        "min dihedral %.2f, largest tet %.3g\n",
        c.name, tetgenSwitches(c.options).c_str(), mesh.numNodes(), mesh.numElements(), mesh.volume(),
        expected, ratio, dihedral, largest);
    EXPECT_EQ(mesh.numNodes(), static_cast<int>(tets.nodes.size()));
    EXPECT_EQ(mesh.numElements(), static_cast<int>(tets.tetrahedra.size()));
    EXPECT_GT(mesh.numElements(), 100);
    EXPECT_NEAR(mesh.volume(), expected, 1e-9 * expected) << c.name;
    EXPECT_LE(ratio, c.options.max_radius_edge_ratio * (1.0 + 1e-9)) << c.name;
    EXPECT_GE(dihedral, c.options.min_dihedral_degrees) << c.name;
    if (c.options.max_volume > 0.0) {
      EXPECT_LE(largest, c.options.max_volume * (1.0 + 1e-9)) << c.name;
    }
    for (int e = 0; e < mesh.numElements(); ++e) ASSERT_EQ(mesh.element(e).numNodes(), 4);
  }
}

TEST(TetgenMesh, ClosedDataModel) {
  // The Stanford bunny scan has holes; the Max Planck bust is a closed genus-0 surface.
  const std::string path = std::string(RC_SHARED_DATA_DIR) + "/maxplanck_bust.off";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "needs ../shared/data: " << path << " is missing";
  if (!tetgenAvailable()) GTEST_SKIP() << "build without TetGen";
  const TriangleMesh surface = readOffMesh(path);
  TetgenOptions options;
  options.max_radius_edge_ratio = 0.0;  // constrained Delaunay only (quality refinement adds 6x the nodes)
  // Without "Y" TetGen re-triangulates nearly coplanar neighbours and inserts boundary Steiner points: the
  // enclosed volume then moved by 4.8e-9 relative (14,079 nodes).
  options.preserve_surface = true;
  const TetrahedralMesh tets = tetrahedralizeSurface(surface, options);
  double volume = 0.0;
  for (const auto& t : tets.tetrahedra) volume += tetrahedronVolume(tets, t);
  const double expected = enclosedVolume(surface);
  std::printf(
      "maxplanck_bust: %zu surface vertices -> %zu nodes, %zu tetrahedra, volume %.12g (surface %.12g)\n",
      surface.vertices.size(), tets.nodes.size(), tets.tetrahedra.size(), volume, expected);
  EXPECT_EQ(tets.nodes.size(), surface.vertices.size());
  EXPECT_NEAR(volume, expected, 1e-9 * expected);
}

TEST(TetgenMesh, NodeEleRoundTripAndRemovalOfUnusedNodes) {
  TetrahedralMesh mesh;
  mesh.nodes = {Vec3(0, 0, 0),     Vec3(1, 0, 0), Vec3(0.1, 1, 0),
                Vec3(0.3, 0.2, 1), Vec3(9, 9, 9), Vec3(0.7, 0.9, 1.1 / 3.0)};
  mesh.tetrahedra = {{0, 1, 2, 3}, {1, 2, 3, 5}};  // node 4 unused, second tetrahedron negatively oriented
  const std::string base = temporaryPath("roundtrip");
  writeTetgenMesh(base, mesh);
  const TetrahedralMesh read = readTetgenMesh(base + ".node", base + ".ele");
  ASSERT_EQ(read.nodes.size(), mesh.nodes.size());
  for (size_t i = 0; i < mesh.nodes.size(); ++i) EXPECT_EQ(read.nodes[i], mesh.nodes[i]) << "node " << i;
  EXPECT_EQ(read.tetrahedra, mesh.tetrahedra);

  const PolyhedralMesh poly = toPolyhedralMesh(read);
  EXPECT_EQ(poly.numNodes(), 5);
  EXPECT_EQ(poly.numInteriorFaces(), 1);
  EXPECT_NEAR(poly.volume(),
              tetrahedronVolume(mesh, mesh.tetrahedra[0]) + tetrahedronVolume(mesh, mesh.tetrahedra[1]),
              1e-15);
  TetrahedralMesh compacted = read;
  EXPECT_EQ(removeUnusedNodes(compacted), 1);
  EXPECT_EQ(compacted.nodes[4], mesh.nodes[5]);
  EXPECT_EQ(compacted.tetrahedra[1], (std::array<int, 4>{1, 2, 3, 4}));

  // TetGen's own layout: one-based, attributes, boundary markers, comments.
  const std::string node = temporaryPath("one_based.node"), ele = temporaryPath("one_based.ele");
  writeText(node,
            "# comment\n4 3 1 1\n1 0 0 0 7.5 1\n2 1 0 0 7.5 1\n3 0 1 0 7.5 1  # marker\n\n4 0 0 1 7.5 0\n");
  writeText(ele, "1 4 1\n  1 1 2 3 4 -1\n# Generated by tetgen\n");
  const TetrahedralMesh one_based = readTetgenMesh(node, ele);
  EXPECT_EQ(one_based.tetrahedra[0], (std::array<int, 4>{0, 1, 2, 3}));
  EXPECT_EQ(one_based.nodes[3], Vec3(0, 0, 1));
}

TEST(TetgenMesh, NodeEleErrorsNameFileAndLine) {
  const std::string good_node = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
  const std::string good_ele = "1 4 0\n0 0 1 2 3\n";
  EXPECT_EQ(readError(good_node, good_ele), "");
  struct Case {
    std::string node, ele, expected;
  };
  const std::vector<Case> cases = {
      {"4 3 0 0\n0 0 0 0\n1 1 x 0\n2 0 1 0\n3 0 0 1\n", good_ele,
       "bad.node: line 3: y: 'x' is not a finite number"},
      {"4 2 0 0\n", good_ele, "bad.node: line 1: dimension must be 3, got 2"},
      {"4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n", good_ele,
       "bad.node: unexpected end of file, expected point 4 of 4"},
      {"4 3 0 0\n0 0 0 0\n1 1 0 0\n3 0 1 0\n3 0 0 1\n", good_ele,
       "bad.node: line 4: expected point index 2, got 3"},
      {"4 3 0 0\n0 0 0 0\n1 1 0\n2 0 1 0\n3 0 0 1\n", good_ele,
       "bad.node: line 3: a point line needs 4 fields"},
      {good_node, "1 4 0\n0 0 1 2 4\n", "bad.ele: line 2: node id 4 is outside 0..3"},
      {good_node, "1 10 0\n", "bad.ele: line 1: only linear (4-node) tetrahedra are supported"},
      {good_node, "2 4 0\n0 0 1 2 3\n", "bad.ele: unexpected end of file, expected tetrahedron 2 of 2"},
      {good_node, "1 4 0\n0 0 1 2 3\n1 0 1 2 3\n", "bad.ele: line 3: unexpected data after the 1 tetrahedra"},
  };
  for (const Case& c : cases) {
    const std::string message = readError(c.node, c.ele);
    EXPECT_NE(message.find(c.expected), std::string::npos)
        << "got '" << message << "', expected " << c.expected;
  }
  EXPECT_THROW(readTetgenMesh(temporaryPath("missing.node"), temporaryPath("missing.ele")), IoError);
}

// ---- CHOLMOD
// --------------------------------------------------------------------------------------------------

// A cantilever beam [0, 2] x [0, 0.4] x [0, 0.4] bent by its static tip-load deflection (clamped at x = 0).
struct BentCantilever {
  LinearElasticModel model;
  Eigen::VectorXd positions;
};

BentCantilever bentCantilever(bool tetrahedral) {
  const Vec3 lo(0, 0, 0), hi(2, 0.4, 0.4);
  PolyhedralMesh mesh = tetrahedral ? PolyhedralMesh::tetrahedralGrid(lo, hi, 10, 2, 2)
                                    : PolyhedralMesh::hexahedralGrid(lo, hi, 10, 2, 2);
  LinearElasticModel model(std::move(mesh), 2e4, 0.3, 1.0);
  std::vector<DisplacementConstraint> clamp;
  Eigen::VectorXd forces = Eigen::VectorXd::Zero(model.numDofs());
  for (int i = 0; i < model.mesh().numNodes(); ++i) {
    const Vec3& p = model.mesh().node(i);
    if (p.x() == 0.0) clamp.push_back({i, Vec3::Zero()});
    if (p.x() == 2.0) forces[3 * i + 2] = -0.2;  // 9 tip nodes: ~0.1 deflection
  }
  Eigen::VectorXd x = model.solveStatic(forces, clamp);
  for (int i = 0; i < model.mesh().numNodes(); ++i) x.segment<3>(3 * i) += model.mesh().node(i);
  return {std::move(model), std::move(x)};
}

WarpedDynamicsOptions cantileverOptions(WarpedDynamicsOptions::Solver solver, bool contact) {
  WarpedDynamicsOptions options;
  options.time_step = 0.01;
  options.gravity = Vec3(0, 0, -9.81);
  options.stiffness_damping = 0.002;
  options.solver = solver;
  options.ground.enabled = contact;
  options.ground.offset = -0.05;  // the bent tip reaches below
  return options;
}

TEST(CholmodSolver, MatchesSimplicialLdltAndReusesTheAnalysis) {
  if (!cholmodAvailable()) {
    EXPECT_THROW(CholmodSolver(), std::runtime_error);
    GTEST_SKIP() << "build without CHOLMOD";
  }
  const BentCantilever beam = bentCantilever(true);
  const double dt = 0.01;
  Eigen::SparseMatrix<double> a = dt * dt * beam.model.stiffness();
  for (int d = 0; d < beam.model.numDofs(); ++d) a.coeffRef(d, d) += beam.model.lumpedMasses()[d / 3];
  a.makeCompressed();
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 2.0);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(a);
  const Eigen::VectorXd reference = ldlt.solve(b);

  CholmodSolver solver;
  solver.factorize(a);
  EXPECT_TRUE(solver.supernodal());
  EXPECT_GT(solver.factorNonZeros(), 0.0);
  const double full_error = (solver.solve(b) - reference).norm() / reference.norm();
  // Same pattern, new values: no new analysis. Lower triangle only: a new pattern, a new analysis.
  a *= 2.0;
  solver.factorize(a);
  const double scaled_error = (solver.solve(b) - 0.5 * reference).norm() / (0.5 * reference.norm());
  EXPECT_EQ(solver.numAnalyses(), 1);
  const Eigen::SparseMatrix<double> lower = a.triangularView<Eigen::Lower>();
  solver.factorize(lower);
  const double lower_error = (solver.solve(b) - 0.5 * reference).norm() / (0.5 * reference.norm());
  EXPECT_EQ(solver.numAnalyses(), 2);
  EXPECT_EQ(solver.numFactorizations(), 3);
  std::printf("CHOLMOD vs SimplicialLDLT (%ld dofs): full %.2e, rescaled %.2e, lower only %.2e\n",
              long(a.rows()), full_error, scaled_error, lower_error);
  EXPECT_LT(full_error, 1e-12);
  EXPECT_LT(scaled_error, 1e-12);
  EXPECT_LT(lower_error, 1e-12);

  EXPECT_THROW(solver.solve(Eigen::VectorXd::Ones(3)), std::invalid_argument);
  a.coeffRef(7, 7) = -1.0;
  try {
    solver.factorize(a);
    ADD_FAILURE() << "indefinite matrix accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("not positive definite"), std::string::npos) << error.what();
  }
  EXPECT_THROW(solver.solve(b), std::logic_error);
}

TEST(WarpedDynamicsCholmod, StepEqualsSimplicialLdlt) {
  using Solver = WarpedDynamicsOptions::Solver;
  if (!cholmodAvailable()) {
    const BentCantilever beam = bentCantilever(false);
    EXPECT_THROW(WarpedDynamics(beam.model, cantileverOptions(Solver::kCholmod, false)), std::runtime_error);
    GTEST_SKIP() << "build without CHOLMOD";
  }
  for (const bool tetrahedral : {false, true})
    for (const bool contact : {false, true}) {
      const BentCantilever beam = bentCantilever(tetrahedral);
      Eigen::VectorXd velocity[2];
      StepStatistics stats[2];
      for (int k = 0; k < 2; ++k) {
        WarpedDynamics sim(beam.model,
                           cantileverOptions(k == 0 ? Solver::kSimplicialLDLT : Solver::kCholmod, contact));
        sim.setPositions(beam.positions);
        Eigen::VectorXd falling = Eigen::VectorXd::Zero(beam.positions.size());
        for (Eigen::Index i = 2; i < falling.size(); i += 3) falling[i] = -1.0;
        sim.setVelocities(falling);  // onto the ground
        stats[k] = sim.step();
        velocity[k] = sim.velocities();
      }
      const double difference = (velocity[1] - velocity[0]).norm() / velocity[0].norm();
      std::printf("%s cantilever%s: |v_cholmod - v_ldlt| / |v_ldlt| = %.2e (solves %d, contact nodes %d)\n",
                  tetrahedral ? "tetrahedral" : "hexahedral", contact ? " on the ground" : "", difference,
                  stats[1].contact_rounds, stats[1].contact_nodes);
      EXPECT_LT(difference, 1e-10);
      EXPECT_EQ(stats[1].contact_nodes, stats[0].contact_nodes);
      EXPECT_EQ(stats[1].solver_iterations, stats[0].solver_iterations);
      if (contact) {
        EXPECT_GT(stats[1].contact_nodes, 0);
      }
    }
}

TEST(WarpedDynamicsCholmod, MultiStepRunEqualsPcgWithinItsTolerance) {
  using Solver = WarpedDynamicsOptions::Solver;
  if (!cholmodAvailable()) GTEST_SKIP() << "build without CHOLMOD";
  const BentCantilever beam = bentCantilever(true);
  Eigen::VectorXd positions[2];
  for (int k = 0; k < 2; ++k) {
    WarpedDynamicsOptions options =
        cantileverOptions(k == 0 ? Solver::kConjugateGradient : Solver::kCholmod, false);
    WarpedDynamics sim(beam.model, options);
    sim.setPositions(beam.positions);
    for (int step = 0; step < 40; ++step) ASSERT_TRUE(sim.step().converged);
    positions[k] = sim.positions();
  }
  // Displacement over the run (released bent beam swinging and falling) against the difference.
  const double travelled = (positions[1] - beam.positions).norm();
  const double difference = (positions[1] - positions[0]).norm() / travelled;
  std::printf("40 steps: |x_cholmod - x_pcg| / |x - x0| = %.2e (PCG tolerance 1e-8)\n", difference);
  EXPECT_GT(travelled, 0.1);
  EXPECT_LT(difference, 1e-6);
}

}  // namespace
}  // namespace rc
