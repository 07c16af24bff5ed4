// Given face triangulations (PolyhedralMesh's constructor with face_triangles, hexahedralGrid's
// FaceDiagonals, the scene key mesh.face_diagonals): a plate clamped on two sides under a pressure is
// mirror-symmetric to round-off with mirrored diagonals and measurably not with fans; shared faces take one
// side's triangulation; inconsistent or non-tiling triangulations are refused with the element and face.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/fem/fem_static.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {
namespace {

std::string plateScene(const std::string& diagonals) {
  return "material: {youngs_modulus: 1000, poisson_ratio: 0.3}\n"
         "mesh: {type: hex_grid, lo: [-1, -1, 0], hi: [1, 1, 0.25], cells: [6, 6, 2], face_diagonals: " +
         diagonals +
         "}\n"
         "analysis: static\n"
         "held:\n"
         "  - {lo: [-1, -1, 0], hi: [-1, 1, 0.25]}\n"
         "  - {lo: [1, -1, 0], hi: [1, 1, 0.25]}\n"
         "loads: [{lo: [-1, -1, 0.25], hi: [1, 1, 0.25], traction: [0, 0, -1]}]\n";
}

// Largest |u(m(X)) - M u(X)| over the nodes for the mirrors x -> -x and y -> -y, relative to max |u|.
double mirrorAsymmetry(const FemScene& scene, const Eigen::VectorXd& u) {
  const PolyhedralMesh& mesh = *scene.mesh;
  double worst = 0.0;
  for (int axis = 0; axis < 2; ++axis)
    for (int i = 0; i < mesh.numNodes(); ++i) {
      Vec3 mirrored = mesh.node(i);
      mirrored[axis] = -mirrored[axis];
      int j = 0;
      while (j < mesh.numNodes() && (mesh.node(j) - mirrored).norm() > 1e-9) ++j;
      if (j == mesh.numNodes()) {
        ADD_FAILURE() << "no mirror node of " << i;
        return 1.0;
      }
      Vec3 ui = u.segment<3>(3 * i);
      ui[axis] = -ui[axis];
      worst = std::max(worst, (u.segment<3>(3 * j) - ui).norm());
    }
  return worst / u.cwiseAbs().maxCoeff();
}

TEST(FemFaceTriangulation, MirroredDiagonalsKeepASymmetricPlateSymmetric) {
  const FemScene fan = parseFemScene(plateScene("fan"), "fan.yaml", ".");
  const FemScene mirrored = parseFemScene(plateScene("symmetric"), "symmetric.yaml", ".");
  const FemStaticResult fan_result = solveFemStatic(fan), mirrored_result = solveFemStatic(mirrored);
  const double fan_asymmetry = mirrorAsymmetry(fan, fan_result.displacements);
  const double mirrored_asymmetry = mirrorAsymmetry(mirrored, mirrored_result.displacements);
  std::printf("plate under pressure, mirror asymmetry of u / max |u|: fan %.2e, symmetric %.2e\n",
              fan_asymmetry, mirrored_asymmetry);
  EXPECT_GT(fan_asymmetry, 1e-4);
  EXPECT_LT(mirrored_asymmetry, 1e-10);
  // The centre deflects as much either way to within the discretisation (a few per cent).
  EXPECT_NEAR(mirrored_result.max_displacement, fan_result.max_displacement,
              0.05 * fan_result.max_displacement);
  // The clamps carry the pressure times the area.
  double carried = 0.0;
  for (const Vec3& r : mirrored_result.held_reactions) carried += r.z();
  EXPECT_NEAR(carried, 4.0, 1e-9);
}

TEST(FemFaceTriangulation, MirroredDiagonalsPassTheUniaxialPatchTest) {
  // A column on rollers under a top traction: exact with any triangulation that the elements share.
  const FemScene scene = parseFemScene(
      "material: {youngs_modulus: 1000, poisson_ratio: 0.3}\n"
      "mesh: {type: hex_grid, lo: [0, 0, 0], hi: [1, 1, 2], cells: [4, 4, 6], face_diagonals: symmetric}\n"
      "analysis: static\n"
      "held:\n"
      "  - {lo: [0, 0, 0], hi: [1, 1, 0], components: z}\n"
      "  - {lo: [0, 0, 0], hi: [0, 1, 2], components: x}\n"
      "  - {lo: [0, 0, 0], hi: [1, 0, 2], components: y}\n"
      "loads: [{lo: [0, 0, 2], hi: [1, 1, 2], traction: [0, 0, -5]}]\n",
      "column.yaml", ".");
  const FemStaticResult result = solveFemStatic(scene);
  double error = 0.0;
  for (int i = 0; i < scene.mesh->numNodes(); ++i) {
    const Vec3 x = scene.mesh->node(i);
    const Vec3 exact(0.3 * 5 * x.x() / 1000, 0.3 * 5 * x.y() / 1000, -5 * x.z() / 1000);
    error = std::max(error, (result.displacements.segment<3>(3 * i) - exact).norm());
  }
  EXPECT_LT(error, 1e-14);
}

// Two unit cubes sharing the face x = 1 (nodes 1, 2, 6, 5 of the 12-node grid).
struct TwoCubes {
  std::vector<Vec3> nodes;
  std::vector<PolyhedralMesh::ElementFaces> elements;
  TwoCubes() {
    for (int z = 0; z < 2; ++z)
      for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 3; ++x) nodes.emplace_back(x, y, z);
    auto id = [](int x, int y, int z) { return x + 3 * (y + 2 * z); };
    for (int c = 0; c < 2; ++c) {
      const int v[8] = {id(c, 0, 0), id(c + 1, 0, 0), id(c + 1, 1, 0), id(c, 1, 0),
                        id(c, 0, 1), id(c + 1, 0, 1), id(c + 1, 1, 1), id(c, 1, 1)};
      elements.push_back({{v[0], v[3], v[2], v[1]},
                          {v[4], v[5], v[6], v[7]},
                          {v[0], v[1], v[5], v[4]},
                          {v[1], v[2], v[6], v[5]},
                          {v[2], v[3], v[7], v[6]},
                          {v[3], v[0], v[4], v[7]}});
    }
  }
};

// The triangles element e uses on the face made of `face` (global ids), as global triangles.
std::vector<PolyhedralMesh::Triangle> trianglesOnFace(const PolyhedralMesh& mesh, int e,
                                                      const std::vector<int>& face) {
  const ConvexPolyhedron& element = mesh.element(e);
  const std::vector<int>& ids = element.globalNodeIds();
  std::vector<PolyhedralMesh::Triangle> out;
  for (const auto& t : element.triangles()) {
    PolyhedralMesh::Triangle g = {ids[size_t(t[0])], ids[size_t(t[1])], ids[size_t(t[2])]};
    if (std::all_of(g.begin(), g.end(),
                    [&](int v) { return std::find(face.begin(), face.end(), v) != face.end(); }))
      out.push_back(g);
  }
  return out;
}

TEST(FemFaceTriangulation, ASharedFaceTakesTheGivenSidesTriangles) {
  TwoCubes cubes;
  // Element 0's face 3 is (1, 4, 10, 7) in this numbering; the fan takes the diagonal from its first corner
  // (1 - 10). Give the other diagonal (4 - 7) on element 0 only.
  const std::vector<int> shared = cubes.elements[0][3];
  std::vector<std::vector<std::vector<PolyhedralMesh::Triangle>>> given(2);
  given[0].resize(6);
  given[0][3] = {{shared[1], shared[2], shared[3]}, {shared[1], shared[3], shared[0]}};
  const PolyhedralMesh mesh(cubes.nodes, cubes.elements, given);
  for (int e = 0; e < 2; ++e) {
    const auto on_face = trianglesOnFace(mesh, e, shared);
    ASSERT_EQ(on_face.size(), 2u) << e;
    for (const auto& t : on_face)  // both use the given diagonal: every triangle has nodes 4 and 7
      EXPECT_TRUE(std::count(t.begin(), t.end(), shared[1]) == 1 &&
                  std::count(t.begin(), t.end(), shared[3]) == 1)
          << "element " << e;
  }
  EXPECT_NEAR(mesh.volume(), 2.0, 1e-12);
}

TEST(FemFaceTriangulation, InconsistentOrBadTriangulationsAreRefused) {
  TwoCubes cubes;
  const std::vector<int> shared = cubes.elements[0][3];
  std::vector<std::vector<std::vector<PolyhedralMesh::Triangle>>> given(2);
  given[0].resize(6);
  given[1].resize(6);
  given[0][3] = {{shared[1], shared[2], shared[3]}, {shared[1], shared[3], shared[0]}};
  // Element 1 uses the face as its face 5 (4, 1, 7, 10), opposite orientation, and gives the diagonal 1 - 10.
  const std::vector<int> other_side = cubes.elements[1][5];
  given[1][5] = {{other_side[1], other_side[2], other_side[3]},
                 {other_side[1], other_side[3], other_side[0]}};
  try {
    PolyhedralMesh mesh(cubes.nodes, cubes.elements, given);
    ADD_FAILURE() << "inconsistent shared triangulations accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("element 1 face 5"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("differs"), std::string::npos) << e.what();
  }
  given[1][5].clear();
  given[0][3] = {{shared[0], shared[1], shared[2]}};  // leaves half the face uncovered
  try {
    PolyhedralMesh mesh(cubes.nodes, cubes.elements, given);
    ADD_FAILURE() << "a triangulation that does not tile its face accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("element 0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(PolyhedralMesh(cubes.nodes, cubes.elements,
                              std::vector<std::vector<std::vector<PolyhedralMesh::Triangle>>>(1)),
               std::invalid_argument);
  given.assign(2, {});
  given[0].resize(3);
  EXPECT_THROW(PolyhedralMesh(cubes.nodes, cubes.elements, given), std::invalid_argument);
}

TEST(FemFaceTriangulation, TheSceneKeyIsCheckedWithItsLine) {
  try {
    parseFemScene(
        "material: {youngs_modulus: 1000, poisson_ratio: 0.3}\n"
        "analysis: static\n"
        "mesh: {type: tet_grid, lo: [0, 0, 0], hi: [1, 1, 1], cells: [1, 1, 1], face_diagonals: fan}\n"
        "held: [{lo: [0, 0, 0], hi: [1, 1, 0]}]\n",
        "bad.yaml", ".");
    ADD_FAILURE() << "accepted";
  } catch (const FemSceneError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("bad.yaml:3:", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("only for type hex_grid"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rc
