// Splitting polyhedral meshes by planes (thesis 9.3.1), needle avoidance by node snapping (9.2) and
// separation along the cut by node duplication (9.3.2).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "patch_test_support.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/plane_cut.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {
namespace {

const Vec3 kLo(0.0, 0.0, 0.0), kHi(2.0, 1.0, 1.5);

Eigen::Matrix3d linearGradient() {
  return patchGradient();
}
const Vec3 kTranslation = kPatchTranslation;

std::vector<Vec3> linearDisplacements(const PolyhedralMesh& mesh) {
  std::vector<Vec3> u;
  for (const Vec3& x : mesh.nodes()) u.push_back(linearGradient() * x + kTranslation);
  return u;
}

double maxLinearFieldError(const PolyhedralMesh& mesh, const std::vector<Vec3>& u) {
  double worst = 0.0;
  for (int i = 0; i < mesh.numNodes(); ++i)
    worst = std::max(worst, (u[i] - linearGradient() * mesh.node(i) - kTranslation).cwiseAbs().maxCoeff());
  return worst;
}

// Unique undirected edges of all element faces.
std::set<std::pair<int, int>> meshEdges(const PolyhedralMesh& mesh) {
  std::set<std::pair<int, int>> edges;
  for (int e = 0; e < mesh.numElements(); ++e)
    for (const auto& face : mesh.elementFaces(e))
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        edges.insert({std::min(a, b), std::max(a, b)});
      }
  return edges;
}

struct CrossingCounts {
  int elements = 0, edges = 0;
  double min_node_distance = INFINITY;
};

CrossingCounts countCrossings(const PolyhedralMesh& mesh, const Vec3& point, const Vec3& normal) {
  const Vec3 n = normal.normalized();
  auto d = [&](int v) { return n.dot(mesh.node(v) - point); };
  CrossingCounts counts;
  for (int v = 0; v < mesh.numNodes(); ++v)
    counts.min_node_distance = std::min(counts.min_node_distance, std::abs(d(v)));
  for (const auto& edge : meshEdges(mesh)) counts.edges += d(edge.first) * d(edge.second) < 0.0;
  for (int e = 0; e < mesh.numElements(); ++e) {
    bool pos = false, neg = false;
    for (int v : mesh.element(e).globalNodeIds()) {
      pos = pos || d(v) > 0.0;
      neg = neg || d(v) < 0.0;
    }
    counts.elements += pos && neg;
  }
  return counts;
}

double minElementVolumeRatio(const PolyhedralMesh& mesh) {
  double min_volume = INFINITY;
  for (const ConvexPolyhedron& e : mesh.elements()) min_volume = std::min(min_volume, e.volume());
  return min_volume / (mesh.volume() / mesh.numElements());
}

TEST(PlaneCut, ObliqueCutOfHexGridSplitsAndSeparates) {
  const PolyhedralMesh mesh = PolyhedralMesh::hexahedralGrid(kLo, kHi, 4, 3, 3);
  const Vec3 point(1.03, 0.51, 0.77), normal(1.0, 0.7, -0.4);
  const CrossingCounts expected = countCrossings(mesh, point, normal);
  ASSERT_GT(expected.min_node_distance, 1e-3);  // generic: no snapping
  const PlaneCutResult cut = cutMeshByPlane(mesh, linearDisplacements(mesh), point, normal);
  std::printf("oblique cut: %d -> %d elements (%d split), %d -> %d nodes (%d new)\n", mesh.numElements(),
              cut.mesh.numElements(), cut.num_split_elements, mesh.numNodes(), cut.mesh.numNodes(),
              cut.num_new_nodes);
  EXPECT_EQ(cut.num_split_elements, expected.elements);
  EXPECT_GE(expected.elements, 10);
  EXPECT_EQ(cut.mesh.numElements(), mesh.numElements() + expected.elements);
  EXPECT_EQ(cut.num_new_nodes, expected.edges);
  EXPECT_EQ(cut.mesh.numNodes(), mesh.numNodes() + expected.edges);
  EXPECT_EQ(cut.num_snapped_nodes, 0);
  EXPECT_NEAR(cut.mesh.volume(), mesh.volume(), 1e-12 * mesh.volume());
  // New nodes lie on the plane; interpolated displacements reproduce the linear field exactly.
  for (int v = mesh.numNodes(); v < cut.mesh.numNodes(); ++v)
    EXPECT_NEAR(normal.normalized().dot(cut.mesh.node(v) - point), 0.0, 1e-14);
  EXPECT_LT(maxLinearFieldError(cut.mesh, cut.displacements), 1e-15);
  // Every element lies on one side of the plane.
  for (int e = 0; e < cut.mesh.numElements(); ++e)
    for (int v : cut.mesh.element(e).globalNodeIds())
      EXPECT_GE(cut.element_side[e] * normal.normalized().dot(cut.mesh.node(v) - point), -1e-14);

  const SeparatedMesh separated = separateAlongPlane(cut);
  EXPECT_EQ(separated.numDuplicatedNodes(), cut.num_new_nodes);  // no old node on the plane
  EXPECT_EQ(static_cast<int>(separated.nodes.size()),
            mesh.numNodes() + expected.edges + separated.numDuplicatedNodes());
  std::set<int> side_nodes[2];
  for (int e = 0; e < cut.mesh.numElements(); ++e)
    for (const auto& face : separated.elements[e])
      for (int v : face) side_nodes[cut.element_side[e] > 0].insert(v);
  std::vector<int> shared;
  std::set_intersection(side_nodes[0].begin(), side_nodes[0].end(), side_nodes[1].begin(),
                        side_nodes[1].end(), std::back_inserter(shared));
  EXPECT_TRUE(shared.empty());
  ASSERT_EQ(separated.sides.size(), 2u);
  EXPECT_NEAR(separated.sides[0].volume() + separated.sides[1].volume(), mesh.volume(),
              1e-12 * mesh.volume());
  EXPECT_EQ(separated.sides[0].numElements() + separated.sides[1].numElements(), cut.mesh.numElements());
  EXPECT_EQ(separated.sides[0].numNodes() + separated.sides[1].numNodes(),
            static_cast<int>(separated.nodes.size()));
  // Duplicates carry the displacement of their original.
  for (int k = 0; k < separated.numDuplicatedNodes(); ++k)
    EXPECT_EQ(separated.displacements[cut.mesh.numNodes() + k],
              separated.displacements[separated.duplicate_of[k]]);
  std::printf("separated: sides of %d and %d elements, volumes %.6f + %.6f, %d duplicated nodes\n",
              separated.sides[0].numElements(), separated.sides[1].numElements(), separated.sides[0].volume(),
              separated.sides[1].volume(), separated.numDuplicatedNodes());
}

TEST(PlaneCut, CutsThroughNodesEdgesAndFacesSnap) {
  const PolyhedralMesh mesh = PolyhedralMesh::hexahedralGrid(Vec3(0, 0, 0), Vec3(3, 3, 3), 3, 3, 3);
  struct Case {
    const char* name;
    Vec3 point, normal;
    int split, new_nodes, on_plane_old_nodes;
  };
  // x + y + z = 3 passes through 10 grid nodes; x + y = 3 contains 4 vertical grid lines (16 nodes) and
  // splits the 3 cells per layer with i + j = 2 along their diagonal; x = 1 runs along grid faces.
  const Case cases[] = {{"nodes", Vec3(1, 1, 1), Vec3(1, 1, 1), -1, -1, 10},
                        {"edges", Vec3(1.5, 1.5, 0), Vec3(1, 1, 0), 9, 0, 16},
                        {"faces", Vec3(1, 0, 0), Vec3(1, 0, 0), 0, 0, 16}};
  for (const Case& c : cases) {
    const PlaneCutResult cut = cutMeshByPlane(mesh, {}, c.point, c.normal);
    const double ratio = minElementVolumeRatio(cut.mesh);
    int on_plane = 0;
    for (int v = 0; v < mesh.numNodes(); ++v) on_plane += cut.node_side[v] == 0;
    std::printf("%s: %d split, %d new nodes, %d old nodes on the plane, min/mean element volume %.4f\n",
                c.name, cut.num_split_elements, cut.num_new_nodes, on_plane, ratio);
    EXPECT_EQ(on_plane, c.on_plane_old_nodes) << c.name;
    if (c.split >= 0) {
      EXPECT_EQ(cut.num_split_elements, c.split) << c.name;
    }
    if (c.new_nodes >= 0) {
      EXPECT_EQ(cut.num_new_nodes, c.new_nodes) << c.name;
    }
    EXPECT_EQ(cut.mesh.numElements(), mesh.numElements() + cut.num_split_elements) << c.name;
    EXPECT_NEAR(cut.mesh.volume(), 27.0, 1e-12 * 27.0) << c.name;
    EXPECT_GT(ratio, 0.1) << c.name;
    const SeparatedMesh separated = separateAlongPlane(cut);
    EXPECT_NEAR(separated.sides[0].volume() + separated.sides[1].volume(), 27.0, 1e-12 * 27.0) << c.name;
  }
}

TEST(PlaneCut, NearNodeCutSnapsInsteadOfCreatingNeedles) {
  const PolyhedralMesh mesh = PolyhedralMesh::hexahedralGrid(Vec3(0, 0, 0), Vec3(3, 3, 3), 3, 3, 3);
  const Vec3 normal = Vec3(1, 1, 1).normalized();
  const PlaneCutResult exact = cutMeshByPlane(mesh, {}, Vec3(1, 1, 1), normal);
  const PlaneCutResult near = cutMeshByPlane(mesh, {}, Vec3(1, 1, 1) + 1e-7 * normal, normal);
  EXPECT_EQ(near.num_snapped_nodes, 10);
  EXPECT_EQ(near.num_split_elements, exact.num_split_elements);
  EXPECT_EQ(near.num_new_nodes, exact.num_new_nodes);
  EXPECT_NEAR(near.mesh.volume(), 27.0, 1e-12 * 27.0);
  const double snapped_ratio = minElementVolumeRatio(near.mesh);
  EXPECT_GT(snapped_ratio, 0.1);
  std::printf("near-node cut: snapped %d nodes, %d split, %d new nodes, min/mean volume %.4f\n",
              near.num_snapped_nodes, near.num_split_elements, near.num_new_nodes, snapped_ratio);
  // Without snapping the plane cuts needles 1e-7 thick off the cells at those nodes, which the element
  // validation rejects as degenerate.
  PlaneCutOptions no_snap;
  no_snap.snap_relative_distance = 0.0;
  try {
    const PlaneCutResult needles = cutMeshByPlane(mesh, {}, Vec3(1, 1, 1) + 1e-7 * normal, normal, no_snap);
    ADD_FAILURE() << "no exception; min/mean volume " << minElementVolumeRatio(needles.mesh);
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("degenerate"), std::string::npos) << error.what();
  }
}

TEST(PlaneCut, ThreeSuccessiveCutsStayValid) {
  const PolyhedralMesh start = PolyhedralMesh::hexahedralGrid(kLo, kHi, 4, 3, 3);
  const Vec3 points[3] = {Vec3(1.03, 0.51, 0.77), Vec3(0.61, 0.43, 0.9), Vec3(1.4, 0.3, 0.55)};
  const Vec3 normals[3] = {Vec3(1.0, 0.7, -0.4), Vec3(-0.3, 1.0, 0.8), Vec3(0.2, -0.5, 1.0)};
  PolyhedralMesh mesh = start;
  std::vector<Vec3> u = linearDisplacements(start);
  PlaneCutResult last = cutMeshByPlane(mesh, u, points[0], normals[0]);
  for (int k = 0; k < 3; ++k) {
    if (k > 0) last = cutMeshByPlane(mesh, u, points[k], normals[k]);
    const CrossingCounts expected = countCrossings(mesh, points[k], normals[k]);
    std::printf("cut %d: %d split, %d new nodes, %d snapped -> %d elements, %d nodes, %d interior faces\n",
                k + 1, last.num_split_elements, last.num_new_nodes, last.num_snapped_nodes,
                last.mesh.numElements(), last.mesh.numNodes(), last.mesh.numInteriorFaces());
    if (last.num_snapped_nodes == 0) {
      EXPECT_EQ(last.num_split_elements, expected.elements) << k;
      EXPECT_EQ(last.num_new_nodes, expected.edges) << k;
    }
    EXPECT_EQ(last.mesh.numElements(), mesh.numElements() + last.num_split_elements) << k;
    EXPECT_EQ(last.mesh.numNodes(), mesh.numNodes() + last.num_new_nodes) << k;
    EXPECT_NEAR(last.mesh.volume(), start.volume(), 1e-12 * start.volume()) << k;
    EXPECT_LT(maxLinearFieldError(last.mesh, last.displacements), 1e-15) << k;
    EXPECT_GT(minElementVolumeRatio(last.mesh), 1e-5) << k;  // measured 1.9e-5 .. 4.2e-5
    mesh = last.mesh;
    u = last.displacements;
  }
  const SeparatedMesh separated = separateAlongPlane(last);
  EXPECT_NEAR(separated.sides[0].volume() + separated.sides[1].volume(), start.volume(),
              1e-12 * start.volume());
}

TEST(PlaneCut, PatchTestPassesOnCutMeshAndOnOneSide) {
  const PolyhedralMesh mesh = PolyhedralMesh::hexahedralGrid(kLo, kHi, 4, 3, 3);
  PlaneCutResult cut = cutMeshByPlane(mesh, {}, Vec3(1.03, 0.51, 0.77), Vec3(1.0, 0.7, -0.4));
  cut = cutMeshByPlane(cut.mesh, {}, Vec3(0.61, 0.43, 0.9), Vec3(-0.3, 1.0, 0.8));
  const PatchResult whole = runPatchTest(cut.mesh);
  const SeparatedMesh separated = separateAlongPlane(cut);
  const int side = countInteriorNodes(separated.sides[0]) >= countInteriorNodes(separated.sides[1]) ? 0 : 1;
  ASSERT_GT(countInteriorNodes(separated.sides[side]), 0);
  const PatchResult one_side = runPatchTest(separated.sides[side]);
  std::printf(
      "patch test: cut mesh (%d interior nodes) displacement %.2e stress %.2e; side %d (%d elements, "
      "%d interior nodes) displacement %.2e stress %.2e\n",
      countInteriorNodes(cut.mesh), whole.max_displacement_error, whole.max_stress_error, side,
      separated.sides[side].numElements(), countInteriorNodes(separated.sides[side]),
      one_side.max_displacement_error, one_side.max_stress_error);
  EXPECT_LT(whole.max_displacement_error, 1e-10);
  EXPECT_LT(whole.max_stress_error, 1e-9);
  EXPECT_LT(one_side.max_displacement_error, 1e-10);
  EXPECT_LT(one_side.max_stress_error, 1e-9);
}

std::vector<Vec3> squareInPlane(const Vec3& center, const Vec3& normal, double half_size) {
  const Vec3 e1 = normal.normalized().unitOrthogonal(), e2 = normal.normalized().cross(e1);
  return {center + half_size * (-e1 - e2), center + half_size * (e1 - e2), center + half_size * (e1 + e2),
          center + half_size * (-e1 + e2)};
}

TEST(PlaneCut, RegionRestrictedCutSplitsOnlyOverlappedElementsWithTJunctions) {
  const PolyhedralMesh mesh = PolyhedralMesh::hexahedralGrid(kLo, kHi, 4, 3, 3);
  const Vec3 point(1.03, 0.51, 0.77), normal(1.0, 0.7, -0.4);
  const CrossingCounts full = countCrossings(mesh, point, normal);
  PlaneCutOptions options;
  options.region = squareInPlane(point, normal, 0.3);
  const PlaneCutResult cut = cutMeshByPlane(mesh, linearDisplacements(mesh), point, normal, options);
  // Independent count: unique crossed edges of the split elements.
  std::vector<int> pieces(mesh.numElements(), 0);
  for (int parent : cut.parent_element) ++pieces[parent];
  const Vec3 n = normal.normalized();
  std::set<std::pair<int, int>> crossed_edges;
  int whole_crossed = 0;
  for (int e = 0; e < mesh.numElements(); ++e) {
    const auto& ids = mesh.element(e).globalNodeIds();
    bool pos = false, neg = false;
    for (int v : ids) {
      pos = pos || n.dot(mesh.node(v) - point) > 0.0;
      neg = neg || n.dot(mesh.node(v) - point) < 0.0;
    }
    whole_crossed += pos && neg && pieces[e] == 1;
    if (pieces[e] != 2) continue;
    for (const auto& face : mesh.elementFaces(e))
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        if (n.dot(mesh.node(a) - point) * n.dot(mesh.node(b) - point) < 0.0)
          crossed_edges.insert({std::min(a, b), std::max(a, b)});
      }
  }
  std::printf(
      "region cut: %d of %d crossed elements split, %d new nodes, %d crossed elements with "
      "T-junctions\n",
      cut.num_split_elements, full.elements, cut.num_new_nodes, whole_crossed);
  EXPECT_GT(cut.num_split_elements, 0);
  EXPECT_LT(cut.num_split_elements, full.elements);
  EXPECT_EQ(cut.num_split_elements + whole_crossed, full.elements);
  EXPECT_GT(whole_crossed, 0);
  int whole_in_cut = 0;
  for (int e = 0; e < cut.mesh.numElements(); ++e) {
    if (cut.element_side[e] != 0) continue;
    ++whole_in_cut;
    EXPECT_GT(cut.mesh.element(e).numNodes(), 8) << e;  // hexahedron plus T-junction nodes
    EXPECT_GT(cut.mesh.element(e).numFaces(), 6) << e;  // a face shared with a split element is split
  }
  EXPECT_EQ(whole_in_cut, whole_crossed);
  EXPECT_EQ(cut.mesh.numElements(), mesh.numElements() + cut.num_split_elements);
  EXPECT_EQ(cut.num_new_nodes, static_cast<int>(crossed_edges.size()));
  EXPECT_EQ(cut.mesh.numNodes(), mesh.numNodes() + cut.num_new_nodes);
  EXPECT_NEAR(cut.mesh.volume(), mesh.volume(), 1e-12 * mesh.volume());
  EXPECT_LT(maxLinearFieldError(cut.mesh, cut.displacements), 1e-15);
  const PatchResult patch = runPatchTest(cut.mesh);
  std::printf("patch test on the region cut: displacement %.2e stress %.2e\n", patch.max_displacement_error,
              patch.max_stress_error);
  EXPECT_LT(patch.max_displacement_error, 1e-10);
  EXPECT_LT(patch.max_stress_error, 1e-9);
  EXPECT_THROW(separateAlongPlane(cut), std::invalid_argument);  // partial cut

  // A region covering the whole section is the full cut.
  options.region = squareInPlane(point, normal, 100.0);
  const PlaneCutResult everything = cutMeshByPlane(mesh, {}, point, normal, options);
  EXPECT_EQ(everything.num_split_elements, full.elements);
  EXPECT_EQ(everything.num_new_nodes, full.edges);

  // Bad regions.
  options.region = {point, point + Vec3(0.1, 0, 0)};
  EXPECT_THROW(cutMeshByPlane(mesh, {}, point, normal, options), std::invalid_argument);
  options.region = squareInPlane(point, normal, 0.3);
  options.region[0] += 0.1 * n;  // off the plane
  EXPECT_THROW(cutMeshByPlane(mesh, {}, point, normal, options), std::invalid_argument);
  options.region = squareInPlane(point, normal, 0.3);
  std::swap(options.region[1], options.region[2]);  // bow tie
  EXPECT_THROW(cutMeshByPlane(mesh, {}, point, normal, options), std::invalid_argument);
}

TEST(PlaneCut, RejectsBadInput) {
  const PolyhedralMesh mesh = PolyhedralMesh::hexahedralGrid(kLo, kHi, 2, 2, 2);
  EXPECT_THROW(cutMeshByPlane(mesh, {}, Vec3(1, 0.5, 0.7), Vec3::Zero()), std::invalid_argument);
  EXPECT_THROW(cutMeshByPlane(mesh, {}, Vec3(NAN, 0.5, 0.7), Vec3(1, 0, 0)), std::invalid_argument);
  EXPECT_THROW(cutMeshByPlane(mesh, std::vector<Vec3>(3, Vec3::Zero()), Vec3(1, 0.5, 0.7), Vec3(1, 0, 0)),
               std::invalid_argument);
  PlaneCutOptions bad;
  bad.snap_relative_distance = -1.0;
  EXPECT_THROW(cutMeshByPlane(mesh, {}, Vec3(1, 0.5, 0.7), Vec3(1, 0, 0), bad), std::invalid_argument);
  // A plane missing the mesh splits nothing and cannot be separated.
  const PlaneCutResult miss = cutMeshByPlane(mesh, {}, Vec3(5, 0, 0), Vec3(1, 0, 0));
  EXPECT_EQ(miss.num_split_elements, 0);
  EXPECT_EQ(miss.mesh.numNodes(), mesh.numNodes());
  EXPECT_THROW(separateAlongPlane(miss), std::invalid_argument);
}

}  // namespace
}  // namespace rc
