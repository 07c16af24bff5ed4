// Crack faces in PolyhedralMesh (thesis 9.3.2, partial cuts): a partially cut block is one validated mesh
// whose coincident crack faces are listed boundary faces; without the list the same mesh is rejected as
// non-conforming; bad lists name the problem; crack faces survive a rebuild into ProgressiveCutMesh; derived
// node values reproduce linear fields; a partially cut body simulates with its volume conserved.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cut_test_support.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/polygon_cut.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace rc {
namespace {

// Top half of the plane x = 1.5: 6 split cells, 12 crack faces, one component.
ProgressiveCutMesh halfCutBlock() {
  ProgressiveCutMesh cut(block());
  cut.cut(quadX(1.5, -1.0, 4.0, 1.5, 4.0));
  return cut;
}

std::string invalidArgument(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(CrackFaces, PartiallyCutComponentIsOneValidatedMesh) {
  const ProgressiveCutMesh cut = halfCutBlock();
  ASSERT_EQ(cut.numComponents(), 1);
  std::vector<int> ids;
  const PolyhedralMesh mesh = cut.componentMesh(0, &ids);
  EXPECT_EQ(mesh.numNodes(), 64 + 16 + 8);
  EXPECT_EQ(mesh.numElements(), 33);
  EXPECT_EQ(mesh.numCrackFaces(), 12);
  EXPECT_NEAR(mesh.volume(), 27.0, 1e-12 * 27.0);
  // Crack faces are boundary faces: boundary area = cube surface 54 + both crack sides 2 * (3 x 1.5).
  double area = 0.0;
  for (const auto& t : mesh.boundaryTriangles())
    area += 0.5 * (mesh.node(t[1]) - mesh.node(t[0])).cross(mesh.node(t[2]) - mesh.node(t[0])).norm();
  EXPECT_NEAR(area, 54.0 + 9.0, 1e-12 * 63.0);
  // Crack nodes are boundary nodes; the 4 crack-front nodes at z = 1.5 are shared (not duplicated).
  int crack_front = 0;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (std::abs(mesh.node(i).x() - 1.5) < 1e-12 && std::abs(mesh.node(i).z() - 1.5) < 1e-12) {
      ++crack_front;
      EXPECT_TRUE(mesh.isBoundaryNode()[i]);
    }
  EXPECT_EQ(crack_front, 4);
  for (const auto& [e, f] : mesh.crackFaces()) {
    EXPECT_TRUE(mesh.isCrackFace(e, f));
    for (int v : mesh.elementFaces(e)[f]) EXPECT_NEAR(mesh.node(v).x(), 1.5, 1e-12);
  }
}

TEST(CrackFaces, UnlistedCoincidentFacesAreRejected) {
  const PolyhedralMesh mesh = halfCutBlock().componentMesh(0);
  std::vector<PolyhedralMesh::ElementFaces> elements;
  for (int e = 0; e < mesh.numElements(); ++e) elements.push_back(mesh.elementFaces(e));
  const std::string message = invalidArgument([&] { PolyhedralMesh(mesh.nodes(), elements); });
  EXPECT_NE(message.find("non-conforming faces"), std::string::npos) << message;
  // Listing only some crack faces is not enough: both faces of each coincident pair must be listed.
  std::vector<PolyhedralMesh::FaceRef> half(mesh.crackFaces().begin(), mesh.crackFaces().begin() + 1);
  EXPECT_THROW(PolyhedralMesh(mesh.nodes(), elements, ConvexPolyhedron::kDefaultRelativeTolerance, half),
               std::invalid_argument);
  EXPECT_NO_THROW(
      PolyhedralMesh(mesh.nodes(), elements, ConvexPolyhedron::kDefaultRelativeTolerance, mesh.crackFaces()));
}

TEST(CrackFaces, BadListsNameTheProblem) {
  const PolyhedralMesh grid = PolyhedralMesh::hexahedralGrid(Vec3(0, 0, 0), Vec3(2, 1, 1), 2, 1, 1);
  std::vector<PolyhedralMesh::ElementFaces> elements = {grid.elementFaces(0), grid.elementFaces(1)};
  const double tol = ConvexPolyhedron::kDefaultRelativeTolerance;
  // Face 3 of element 0 is the shared face x = 1 (hexahedralCells order: bottom, top, -y, +x, +y, -x).
  std::string m = invalidArgument([&] { PolyhedralMesh(grid.nodes(), elements, tol, {{0, 3}}); });
  EXPECT_NE(m.find("still connects two elements"), std::string::npos) << m;
  m = invalidArgument([&] { PolyhedralMesh(grid.nodes(), elements, tol, {{2, 0}}); });
  EXPECT_NE(m.find("does not exist"), std::string::npos) << m;
  m = invalidArgument([&] { PolyhedralMesh(grid.nodes(), elements, tol, {{0, 6}}); });
  EXPECT_NE(m.find("does not exist"), std::string::npos) << m;
  m = invalidArgument([&] { PolyhedralMesh(grid.nodes(), elements, tol, {{0, 0}, {0, 0}}); });
  EXPECT_NE(m.find("listed twice"), std::string::npos) << m;
  // An outer boundary face may be listed (a crack face whose partner has gone).
  const PolyhedralMesh listed(grid.nodes(), elements, tol, {{1, 0}, {0, 1}});
  EXPECT_EQ(listed.numCrackFaces(), 2);
  EXPECT_TRUE(listed.isCrackFace(0, 1));
  EXPECT_FALSE(listed.isCrackFace(0, 0));
}

TEST(CrackFaces, RebuiltBodyKeepsItsCrackAndTheCutCompletes) {
  const ProgressiveCutMesh first = halfCutBlock();
  const PolyhedralMesh partial = first.componentMesh(0);
  ProgressiveCutMesh again(partial);
  EXPECT_EQ(again.numCrackFaces(), 12);
  again.validate();
  const PolygonCutStats second = again.cut(quadX(1.5, -1.0, 4.0, -1.0, 1.5));
  again.validate();
  EXPECT_EQ(second.num_split_elements, 3);
  EXPECT_EQ(second.num_duplicated_nodes, 12);
  EXPECT_EQ(again.numComponents(), 2);
  EXPECT_EQ(again.numElements(), 36);
  for (int c = 0; c < 2; ++c) EXPECT_NEAR(again.componentMesh(c).volume(), 13.5, 1e-12 * 27.0);
}

TEST(CrackFaces, DerivedNodeValuesReproduceLinearFields) {
  const Eigen::Matrix3d a = (Eigen::Matrix3d() << 0.3, -0.1, 0.2, 0.05, 0.4, -0.3, 0.1, 0.2, -0.2).finished();
  const Vec3 b(0.5, -1.0, 0.25);
  const PolyhedralMesh start = PolyhedralMesh::randomPlaneCut(Vec3(0, 0, 0), Vec3(3, 3, 3), 3, 3, 3, 3, 7);
  std::vector<Vec3> values;
  for (const Vec3& x : start.nodes()) values.push_back(a * x + b);
  ProgressiveCutMesh cut(start);
  cut.cut({Vec3(1.3, -1, 1.2), Vec3(1.3, 4, 1.2), Vec3(1.5, 4, 4), Vec3(1.5, -1, 4)});
  cut.cut({Vec3(1.3, -1, 1.2), Vec3(1.3, 4, 1.2), Vec3(1.9, 4, 0.4), Vec3(1.9, -1, 0.4)});  // bent
  cut.cut({Vec3(0.5, 0.5, 2.2), Vec3(2.5, 0.7, 2.2), Vec3(1.5, 2.5, 2.2)});                 // pocket-sized
  cut.validate();
  ASSERT_GT(cut.numNodes(), start.numNodes());
  const std::vector<Vec3> out = cut.interpolateNodeValues(values);
  ASSERT_EQ(static_cast<int>(out.size()), cut.numNodes());
  double worst = 0.0;
  for (int i = 0; i < cut.numNodes(); ++i) worst = std::max(worst, (out[i] - a * cut.nodes()[i] - b).norm());
  EXPECT_LT(worst, 1e-13);
  EXPECT_THROW(cut.interpolateNodeValues(std::vector<Vec3>(3)), std::invalid_argument);
}

TEST(CrackFaces, PartiallyCutBodySimulatesWithVolumeConserved) {
  // The half-cut block resting on the ground under gravity: the body stays one mesh with its crack.
  const PolyhedralMesh mesh = halfCutBlock().componentMesh(0);
  WarpedDynamicsOptions options;
  options.time_step = 0.01;
  options.gravity = Vec3(0, 0, -9.81);
  options.ground.enabled = true;
  WarpedDynamics body(LinearElasticModel(mesh, 5000.0, 0.3, 1.0), options);  // stiff: small strain
  const double rest_volume = body.currentVolume();
  EXPECT_NEAR(rest_volume, 27.0, 1e-12 * 27.0);
  double max_relative_change = 0.0;
  for (int s = 0; s < 100; ++s) {
    const StepStatistics stats = body.step();
    EXPECT_TRUE(stats.converged);
    EXPECT_GE(stats.warping_ms, 0.0);
    max_relative_change = std::max(max_relative_change, std::abs(body.currentVolume() / rest_volume - 1.0));
  }
  ASSERT_TRUE(body.positions().allFinite());
  double lowest = INFINITY;
  for (int i = 0; i < body.numNodes(); ++i) lowest = std::min(lowest, body.positions()[3 * i + 2]);
  EXPECT_GT(lowest, -1e-9);
  EXPECT_LT(max_relative_change, 0.01);  // rho g h / Y = 0.006: small strain under its own weight
  std::printf("half-cut block: %d nodes %d elements %d crack faces, max |dV/V| %.3g over 100 steps\n",
              mesh.numNodes(), mesh.numElements(), mesh.numCrackFaces(), max_relative_change);
}

}  // namespace
}  // namespace rc
