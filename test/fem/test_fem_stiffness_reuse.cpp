// Element integration data reused after cuts (thesis 9.3): a body cut by a polygon gets new integration data
// (samples, basis gradients, K_e) only for the elements the cut changed; every other element shares the cut
// body's data, which equals a fresh integration bit for bit, and its built element (no new validation).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <memory>
#include <set>
#include <vector>

#include "relaxed_connectivity/fem/fem_simulation.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {
namespace {

constexpr double kYoungsModulus = 3000.0, kPoissonRatio = 0.3, kDensity = 1.0;

FemScene gridScene(const PolyhedralMesh& mesh) {
  FemScene scene;
  scene.name = "reuse";
  scene.mesh = std::make_shared<PolyhedralMesh>(mesh);
  scene.initial_velocities.assign(mesh.numNodes(), Vec3::Zero());
  scene.youngs_modulus = kYoungsModulus;
  scene.poisson_ratio = kPoissonRatio;
  scene.density = kDensity;
  scene.dynamics.time_step = 0.01;
  return scene;
}

// A quad in the plane x = x0 covering y in [y_lo, y_hi] and z in [-1, 2].
std::vector<Vec3> quadAtX(double x0, double y_lo, double y_hi) {
  return {Vec3(x0, y_lo, -1.0), Vec3(x0, y_hi, -1.0), Vec3(x0, y_hi, 2.0), Vec3(x0, y_lo, 2.0)};
}

// Every element's integration data and the assembled K, M of `model` equal a fresh model's, bit for bit.
void expectEqualsFreshIntegration(const LinearElasticModel& model) {
  const LinearElasticModel fresh(model.mesh(), kYoungsModulus, kPoissonRatio, kDensity);
  ASSERT_EQ(fresh.numRecomputedElements(), model.mesh().numElements());
  for (int e = 0; e < model.mesh().numElements(); ++e) {
    ASSERT_TRUE(model.elementStiffness(e) == fresh.elementStiffness(e)) << "K_e of element " << e;
    const ElementQuadrature &q = model.quadrature(e), &f = fresh.quadrature(e);
    ASSERT_EQ(q.weights, f.weights) << "element " << e;
    ASSERT_EQ(q.gradients.size(), f.gradients.size());
    for (size_t s = 0; s < q.gradients.size(); ++s) ASSERT_TRUE(q.gradients[s] == f.gradients[s]);
    ASSERT_TRUE(q.node_volume_fractions == f.node_volume_fractions);
    ASSERT_EQ(q.volume, f.volume);
  }
  EXPECT_TRUE(model.lumpedMasses() == fresh.lumpedMasses());
  ASSERT_EQ(model.stiffness().nonZeros(), fresh.stiffness().nonZeros());
  for (Eigen::Index k = 0; k < model.stiffness().nonZeros(); ++k)
    ASSERT_EQ(model.stiffness().valuePtr()[k], fresh.stiffness().valuePtr()[k]);
}

// Elements of `after` whose node positions (as a set) are not those of an element of `before`: the
// elements a cut created or changed (independent of the hash used by the reuse).
int changedElements(const std::vector<const PolyhedralMesh*>& before,
                    const std::vector<const PolyhedralMesh*>& after) {
  using Key = std::vector<std::array<double, 3>>;
  auto key = [](const ConvexPolyhedron& element) {
    Key k;
    for (const Vec3& x : element.nodes()) k.push_back({x[0], x[1], x[2]});
    std::sort(k.begin(), k.end());
    return k;
  };
  std::set<Key> old;
  for (const PolyhedralMesh* mesh : before)
    for (const ConvexPolyhedron& element : mesh->elements()) old.insert(key(element));
  int changed = 0;
  for (const PolyhedralMesh* mesh : after)
    for (const ConvexPolyhedron& element : mesh->elements()) changed += old.count(key(element)) ? 0 : 1;
  return changed;
}

std::vector<const PolyhedralMesh*> bodyMeshes(const FemSimulation& sim) {
  std::vector<const PolyhedralMesh*> meshes;
  for (int b = 0; b < sim.numBodies(); ++b) meshes.push_back(&sim.body(b).model().mesh());
  return meshes;
}

TEST(StiffnessReuse, ThroughCutRecomputesOnlyTheSplitColumn) {
  // 4 x 4 x 4 cubes of 6 tetrahedra; the plane x = 0.6 crosses exactly the 16 cubes of x in [0.5, 0.75]
  // (all 96 of their tetrahedra, each into 2 pieces); their neighbours share only the uncut faces x = 0.5
  // and x = 0.75, so the 384 - 96 = 288 other tetrahedra keep their geometry.
  const PolyhedralMesh grid = PolyhedralMesh::tetrahedralGrid(Vec3(0, 0, 0), Vec3(1, 1, 1), 4, 4, 4);
  ASSERT_EQ(grid.numElements(), 384);
  FemSimulation sim(gridScene(grid));
  const FemCutReport report = sim.applyPolygonCuts({quadAtX(0.6, -1.0, 2.0)});
  EXPECT_EQ(report.split_elements, 96);
  EXPECT_EQ(report.bodies_separated, 1);
  ASSERT_EQ(sim.numBodies(), 2);
  EXPECT_EQ(sim.numElements(), 288 + 2 * 96);
  EXPECT_EQ(report.recomputed_elements, 2 * 96);
  EXPECT_EQ(report.reused_elements, 288);
  EXPECT_EQ(sim.recomputedElements(), 192);
  EXPECT_EQ(sim.reusedElements(), 288);
  int recomputed = 0;
  for (int b = 0; b < sim.numBodies(); ++b) {
    recomputed += sim.body(b).model().numRecomputedElements();
    expectEqualsFreshIntegration(sim.body(b).model());
  }
  EXPECT_EQ(recomputed, 192);
}

TEST(StiffnessReuse, PartialAndObliqueCutsRecomputeExactlyTheChangedElements) {
  // A partial cut (crack, one body) and then an oblique one through the cracked body: the recomputed count
  // equals the count of elements whose node set changed, and reused data equals fresh data.
  const PolyhedralMesh grid = PolyhedralMesh::tetrahedralGrid(Vec3(0, 0, 0), Vec3(1, 1, 1), 4, 3, 3);
  FemSimulation sim(gridScene(grid));
  std::vector<const PolyhedralMesh*> before = bodyMeshes(sim);
  std::vector<PolyhedralMesh> kept;
  for (const PolyhedralMesh* mesh : before) kept.push_back(*mesh);
  const FemCutReport partial = sim.applyPolygonCuts({quadAtX(0.37, -1.0, 0.55)});
  ASSERT_EQ(sim.numBodies(), 1);
  EXPECT_GT(partial.crack_faces, 0);
  std::vector<const PolyhedralMesh*> old_meshes;
  for (const PolyhedralMesh& mesh : kept) old_meshes.push_back(&mesh);
  const int changed = changedElements(old_meshes, bodyMeshes(sim));
  EXPECT_GT(changed, 0);
  EXPECT_EQ(partial.recomputed_elements, changed);
  EXPECT_EQ(partial.reused_elements, sim.numElements() - changed);
  EXPECT_GT(partial.reused_elements, grid.numElements() / 2);
  EXPECT_EQ(sim.body(0).model().mesh().numPrebuiltElements(), partial.reused_elements);
  expectEqualsFreshIntegration(sim.body(0).model());

  kept.clear();
  for (const PolyhedralMesh* mesh : bodyMeshes(sim)) kept.push_back(*mesh);
  old_meshes.clear();
  for (const PolyhedralMesh& mesh : kept) old_meshes.push_back(&mesh);
  const std::vector<Vec3> oblique = {Vec3(-1, -1, 0.3), Vec3(2, -1, 0.6), Vec3(2, 2, 0.6), Vec3(-1, 2, 0.3)};
  const FemCutReport second = sim.applyPolygonCuts({oblique});
  const int changed_second = changedElements(old_meshes, bodyMeshes(sim));
  EXPECT_GT(second.split_elements, 0);
  EXPECT_EQ(second.recomputed_elements, changed_second);
  EXPECT_EQ(second.recomputed_elements + second.reused_elements, sim.numElements());
  for (int b = 0; b < sim.numBodies(); ++b) expectEqualsFreshIntegration(sim.body(b).model());
  // The elements the cut left unchanged were also taken over as built elements (not validated again).
  int prebuilt = 0;
  for (const PolyhedralMesh* mesh : bodyMeshes(sim)) prebuilt += mesh->numPrebuiltElements();
  EXPECT_EQ(prebuilt, second.reused_elements);
}

TEST(StiffnessReuse, DonorWithOtherMaterialOrQuadratureSharesNothing) {
  const PolyhedralMesh grid = PolyhedralMesh::hexahedralGrid(Vec3(0, 0, 0), Vec3(1, 1, 1), 2, 2, 2);
  const LinearElasticModel donor(grid, kYoungsModulus, kPoissonRatio, kDensity);
  const LinearElasticModel same(grid, kYoungsModulus, kPoissonRatio, 2.0, ElementQuadratureOptions(), &donor);
  EXPECT_EQ(same.numReusedElements(), 8);  // density enters only the masses
  EXPECT_NEAR(same.lumpedMasses().sum(), 2.0, 1e-12);
  const LinearElasticModel softer(grid, 0.5 * kYoungsModulus, kPoissonRatio, kDensity,
                                  ElementQuadratureOptions(), &donor);
  EXPECT_EQ(softer.numRecomputedElements(), 8);
  ElementQuadratureOptions options;
  options.face_sample_blend = 0.8;
  const LinearElasticModel other_samples(grid, kYoungsModulus, kPoissonRatio, kDensity, options, &donor);
  EXPECT_EQ(other_samples.numRecomputedElements(), 8);
  EXPECT_NEAR(
      (Eigen::MatrixXd(softer.stiffness()) - 0.5 * Eigen::MatrixXd(donor.stiffness())).cwiseAbs().maxCoeff(),
      0.0, 1e-9 * kYoungsModulus);
}

}  // namespace
}  // namespace rc
