// Sliver and needle detection and sliver removal by projection onto the sliver plane (thesis 9.2): counts,
// mesh validity and volume after removal, the thesis' tetrahedral case (one new node, five-node neighbours)
// and the extremes test: a mesh with a flattened tetrahedron and needles is badly conditioned without
// removal and runs with bounded energy after it. The automatic removal after cuts (removeCutSlivers) looks
// only at the elements a cut created, keeps volume and crack faces.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/plane_cut.h"
#include "relaxed_connectivity/fem/polygon_cut.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/sliver_removal.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace rc {
namespace {

constexpr int kCells = 4;  // tetrahedral grid of kCells^3 boxes (6 tets each) on the unit cube

int gridNode(int i, int j, int k) {
  return i + (kCells + 1) * (j + (kCells + 1) * k);
}

int countDefects(const std::vector<ElementDefect>& defects, ElementDefect kind) {
  return static_cast<int>(std::count(defects.begin(), defects.end(), kind));
}

bool elementHasNodes(const ConvexPolyhedron& element, std::initializer_list<int> nodes) {
  const auto& ids = element.globalNodeIds();
  for (int v : nodes)
    if (std::find(ids.begin(), ids.end(), v) == ids.end()) return false;
  return true;
}

struct PlantedMesh {
  PolyhedralMesh mesh;
  int expected_flat = 0;     // tets made flat by moving the sliver node (opposite facet in one plane)
  int expected_needles = 0;  // tets around the short edge
};

// Kuhn grid with node (1,1,1) moved to within relative_gap of the plane of the facet (a, b, c) of its star
// (a flattened tetrahedron, plus the star's other triangles in that plane) and node (3,3,2) moved to
// within relative_gap * h of node (3,3,3) (needles around that edge). All moved nodes are interior.
PlantedMesh plantedMesh(double relative_gap) {
  const PolyhedralMesh grid =
      PolyhedralMesh::tetrahedralGrid(Vec3(0, 0, 0), Vec3(1, 1, 1), kCells, kCells, kCells);
  std::vector<Vec3> nodes = grid.nodes();
  std::vector<PolyhedralMesh::ElementFaces> elements;
  for (int e = 0; e < grid.numElements(); ++e) elements.push_back(grid.elementFaces(e));
  PlantedMesh planted{grid};

  const int v = gridNode(1, 1, 1);
  int sliver = -1;
  for (int e = 0; e < grid.numElements() && sliver < 0; ++e)
    if (elementHasNodes(grid.element(e), {v})) sliver = e;
  std::vector<int> facet;
  for (int u : grid.element(sliver).globalNodeIds())
    if (u != v) facet.push_back(u);
  const Vec3 a = nodes[facet[0]], b = nodes[facet[1]], c = nodes[facet[2]];
  const Vec3 normal = (b - a).cross(c - a).normalized();
  const Vec3 centroid = (a + b + c) / 3.0;
  const double height = std::abs(normal.dot(nodes[v] - a));
  const double h = 1.0 / kCells;
  nodes[v] = centroid + (nodes[v] - centroid) * (relative_gap * h / height);
  // Flat tets: around v, with the other three nodes in the facet plane.
  for (int e = 0; e < grid.numElements(); ++e) {
    if (!elementHasNodes(grid.element(e), {v})) continue;
    bool in_plane = true;
    for (int u : grid.element(e).globalNodeIds())
      if (u != v) in_plane = in_plane && std::abs(normal.dot(grid.node(u) - a)) < 1e-12;
    planted.expected_flat += in_plane;
  }

  const int w = gridNode(3, 3, 2), target = gridNode(3, 3, 3);
  nodes[w] = nodes[target] + relative_gap * (nodes[w] - nodes[target]);
  for (int e = 0; e < grid.numElements(); ++e)
    planted.expected_needles += elementHasNodes(grid.element(e), {w, target});
  planted.mesh = PolyhedralMesh(std::move(nodes), std::move(elements));
  return planted;
}

double minRelativeThickness(const PolyhedralMesh& mesh) {
  double thinnest = INFINITY;
  for (const ConvexPolyhedron& element : mesh.elements())
    thinnest = std::min(thinnest, elementQuality(element).relative_thickness);
  return thinnest;
}

TEST(SliverQuality, MeasuresTetrahedraAndCubes) {
  // Regular-ish: the unit cube has thickness 1, diameter sqrt(3), shortest edge 1.
  const PolyhedralMesh cube = PolyhedralMesh::hexahedralGrid(Vec3(0, 0, 0), Vec3(1, 1, 1), 1, 1, 1);
  const ElementQuality q = elementQuality(cube.element(0));
  EXPECT_NEAR(q.diameter, std::sqrt(3.0), 1e-14);
  EXPECT_NEAR(q.thickness, 1.0, 1e-14);
  EXPECT_NEAR(q.relative_min_edge, 1.0 / std::sqrt(3.0), 1e-14);
  EXPECT_NEAR(q.volume_ratio, 1.0 / (3.0 * std::sqrt(3.0)), 1e-14);
  // Tetrahedron (0, e_x, e_y, t e_z): thickness = min(t, heights of the other faces).
  const double t = 1e-3;
  const ConvexPolyhedron flat =
      ConvexPolyhedron::tetrahedron(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, t));
  const ElementQuality f = elementQuality(flat);
  EXPECT_NEAR(f.thickness, t * std::sqrt(0.5) / std::sqrt(0.5 + t * t), 1e-15);  // height of the origin
  EXPECT_NEAR(f.diameter, std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(f.relative_min_edge, t / std::sqrt(2.0), 1e-15);
}

TEST(SliverDetection, CountsPlantedSliversAndNeedles) {
  const PlantedMesh planted = plantedMesh(1e-3);
  std::printf("planted: %d elements, %d flat around the sliver node, %d around the short edge\n",
              planted.mesh.numElements(), planted.expected_flat, planted.expected_needles);
  EXPECT_EQ(planted.expected_flat, 2);  // the facet is a rhombus of two triangles in the Kuhn grid
  EXPECT_EQ(planted.expected_needles, 6);
  const std::vector<ElementDefect> defects = classifyElements(planted.mesh);
  EXPECT_EQ(countDefects(defects, ElementDefect::kSliver), planted.expected_flat);
  EXPECT_EQ(countDefects(defects, ElementDefect::kNeedle), planted.expected_needles);
  // The unperturbed grid has none.
  const std::vector<ElementDefect> clean =
      classifyElements(PolyhedralMesh::tetrahedralGrid(Vec3(0, 0, 0), Vec3(1, 1, 1), kCells, kCells, kCells));
  EXPECT_EQ(countDefects(clean, ElementDefect::kNone), static_cast<int>(clean.size()));
}

TEST(SliverRemoval, RemovesPlantedDefectsAndConservesVolume) {
  const PlantedMesh planted = plantedMesh(1e-3);
  const PolyhedralMesh& mesh = planted.mesh;
  std::vector<Vec3> displacements;  // linear field: interpolation along edges is exact
  const Eigen::Matrix3d gradient = (Eigen::Matrix3d() << 1, 2, 0, 0, 1, 3, -1, 0, 2).finished() * 1e-2;
  for (const Vec3& x : mesh.nodes()) displacements.push_back(gradient * x + Vec3(0.1, 0.2, 0.3));
  const SliverRemovalResult result = removeSlivers(mesh, displacements);
  std::printf(
      "removal: %d -> %d elements, %d -> %d nodes, slivers %d, needles %d, collapsed %d, new nodes %d, "
      "merged %d, rejected %d, max projection %.3e, min relative thickness %.3e -> %.3e\n",
      mesh.numElements(), result.mesh.numElements(), mesh.numNodes(), result.mesh.numNodes(),
      result.num_slivers_removed, result.num_needles_removed, result.num_collapsed_elements,
      result.num_new_nodes, result.num_merged_nodes, result.num_rejected, result.max_projection_distance,
      minRelativeThickness(mesh), minRelativeThickness(result.mesh));
  EXPECT_EQ(result.num_rejected, 0);
  // Merging the short edge removes the needle group and collapses the other needles around it.
  EXPECT_GE(result.num_needles_removed, 1);
  EXPECT_EQ(result.num_needles_removed + result.num_collapsed_elements, planted.expected_needles);
  EXPECT_EQ(result.num_merged_nodes, 1);
  EXPECT_EQ(result.num_slivers_removed + result.num_needles_removed + result.num_collapsed_elements,
            mesh.numElements() - result.mesh.numElements());
  EXPECT_EQ(result.num_slivers_removed, planted.expected_flat);  // the cap and its coplanar neighbour
  EXPECT_EQ(result.mesh.numNodes(), mesh.numNodes() - result.num_merged_nodes + result.num_new_nodes);
  // Valid (the PolyhedralMesh constructor checked it), no thin element left, volume conserved (interior).
  EXPECT_GE(minRelativeThickness(result.mesh), SliverRemovalOptions().sliver_relative_thickness);
  EXPECT_NEAR(result.mesh.volume(), 1.0, 1e-12);
  EXPECT_NEAR(mesh.volume(), 1.0, 1e-12);
  // Maps: node map into the new mesh, merged short edge, unmoved nodes and their displacements kept.
  ASSERT_EQ(static_cast<int>(result.node_map.size()), mesh.numNodes());
  ASSERT_EQ(static_cast<int>(result.parent_element.size()), result.mesh.numElements());
  ASSERT_EQ(static_cast<int>(result.displacements.size()), result.mesh.numNodes());
  EXPECT_EQ(result.node_map[gridNode(3, 3, 2)], result.node_map[gridNode(3, 3, 3)]);
  int unmoved = 0;
  for (int i = 0; i < mesh.numNodes(); ++i) {
    const int j = result.node_map[i];
    ASSERT_GE(j, 0);
    if ((result.mesh.node(j) - mesh.node(i)).norm() == 0.0) {
      ++unmoved;
      EXPECT_EQ((result.displacements[j] - displacements[i]).norm(), 0.0);
    }
  }
  EXPECT_GE(unmoved, mesh.numNodes() - 8);
  for (int e = 0; e < result.mesh.numElements(); ++e) {
    ASSERT_GE(result.parent_element[e], 0);
    ASSERT_LT(result.parent_element[e], mesh.numElements());
  }
  // New intersection nodes lie on input edges, where the linear field is interpolated exactly.
  for (int j = 0; j < result.mesh.numNodes(); ++j)
    if (std::find(result.node_map.begin(), result.node_map.end(), j) == result.node_map.end()) {
      EXPECT_LT((result.displacements[j] - (gradient * result.mesh.node(j) + Vec3(0.1, 0.2, 0.3))).norm(),
                2e-5);  // the nodes moved by at most the sliver thickness before intersecting
    }
}

// The thesis' tetrahedral case (9.2, Figure 9.6): a sliver (A, B, C, D) with diagonal BD just above AC
// between two tetrahedra above (apex P) and two below (apex Q). Removal creates exactly one node, where the
// projected diagonals cross, and leaves four neighbours with five nodes each: the bipyramid over the square A
// B C D.
TEST(SliverRemoval, TetrahedralSliverGivesOneNodeAndFiveNodeNeighbours) {
  const double delta = 1e-3;
  const std::vector<Vec3> nodes = {Vec3(1, 0, 0),      Vec3(0, 1, delta), Vec3(-1, 0, 0),
                                   Vec3(0, -1, delta), Vec3(0, 0, 1),     Vec3(0, 0, -1)};
  enum { A, B, C, D, P, Q };
  auto tet = [&](int a, int b, int c, int d) {  // positive orientation of (a, b, c, d)
    std::array<int, 4> t{a, b, c, d};
    if ((nodes[b] - nodes[a]).cross(nodes[c] - nodes[a]).dot(nodes[d] - nodes[a]) < 0) std::swap(t[1], t[2]);
    return PolyhedralMesh::ElementFaces{
        {t[0], t[2], t[1]}, {t[0], t[1], t[3]}, {t[1], t[2], t[3]}, {t[0], t[3], t[2]}};
  };
  const PolyhedralMesh mesh(
      nodes, {tet(A, B, C, D), tet(A, B, D, P), tet(C, D, B, P), tet(A, C, B, Q), tet(A, D, C, Q)});
  const std::vector<ElementDefect> defects = classifyElements(mesh);
  EXPECT_EQ(defects[0], ElementDefect::kSliver);
  EXPECT_EQ(countDefects(defects, ElementDefect::kNone), 4);
  const SliverRemovalResult result = removeSlivers(mesh);
  EXPECT_EQ(result.num_slivers_removed, 1);
  EXPECT_EQ(result.num_new_nodes, 1);
  EXPECT_EQ(result.num_merged_nodes, 0);
  ASSERT_EQ(result.mesh.numNodes(), 7);
  ASSERT_EQ(result.mesh.numElements(), 4);
  for (int e = 0; e < 4; ++e) {
    EXPECT_EQ(result.mesh.element(e).numNodes(), 5) << "element " << e;
    EXPECT_EQ(result.parent_element[e], e + 1);
  }
  int new_node = -1;
  for (int j = 0; j < 7; ++j)
    if (std::find(result.node_map.begin(), result.node_map.end(), j) == result.node_map.end()) new_node = j;
  ASSERT_GE(new_node, 0);
  EXPECT_LT((result.mesh.node(new_node) - Vec3(0, 0, 0.5 * delta)).norm(), 1e-15);  // diagonals cross
  EXPECT_NEAR(result.max_projection_distance, 0.5 * delta, 1e-15);
  EXPECT_NEAR(result.mesh.volume(), 4.0 / 3.0, 1e-12);  // (1/3) * area 2 * (apex heights 1 - d/2 + 1 + d/2)
  EXPECT_EQ(result.mesh.numInteriorFaces(), 2 + 4);     // P B D, Q A C and the four triangles in the plane
}

TEST(SliverRemoval, RejectsBadParameters) {
  const PolyhedralMesh mesh = PolyhedralMesh::tetrahedralGrid(Vec3(0, 0, 0), Vec3(1, 1, 1), 1, 1, 1);
  auto expectThrows = [&](SliverRemovalOptions options, const char* what) {
    try {
      removeSlivers(mesh, {}, options);
      ADD_FAILURE() << "no exception for " << what;
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find(what), std::string::npos) << error.what();
    }
    EXPECT_THROW(classifyElements(mesh, options), std::invalid_argument);
  };
  SliverRemovalOptions options;
  options.sliver_relative_thickness = 0.0;
  expectThrows(options, "sliver_relative_thickness");
  options = {};
  options.needle_relative_edge = -0.1;
  expectThrows(options, "needle_relative_edge");
  options = {};
  options.merge_relative_distance = NAN;
  expectThrows(options, "merge_relative_distance");
  options = {};
  options.max_relative_tolerance = 0.5;
  expectThrows(options, "max_relative_tolerance");
  EXPECT_THROW(removeSlivers(mesh, std::vector<Vec3>(3, Vec3::Zero())), std::invalid_argument);
}

// Largest eigenvalue of M^-1 K (squared highest angular frequency) by power iteration on M^-1/2 K M^-1/2.
double maxEigenvalue(const LinearElasticModel& model) {
  const Eigen::VectorXd inv_sqrt_mass = model.lumpedMasses().cwiseSqrt().cwiseInverse();
  Eigen::VectorXd scale(model.numDofs());
  for (int i = 0; i < model.mesh().numNodes(); ++i) scale.segment<3>(3 * i).setConstant(inv_sqrt_mass[i]);
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(model.numDofs(), 1.0, 2.0);
  double lambda = 0.0;
  for (int it = 0; it < 300; ++it) {
    x.normalize();
    const Eigen::VectorXd y = scale.cwiseProduct(model.stiffness() * scale.cwiseProduct(x));
    lambda = x.dot(y);
    x = y;
  }
  return lambda;
}

struct RunSummary {
  double max_eigenvalue = 0.0;
  double initial_energy = 0.0, max_energy = 0.0, final_energy = 0.0;
  int max_iterations = 0, unconverged_steps = 0;
  bool finite = true;
};

// A stiff block spinning freely at a fixed step: kinetic energy that only implicit Euler damping may lower.
RunSummary spin(const PolyhedralMesh& mesh, int steps) {
  const LinearElasticModel model(mesh, 1e5, 0.3, 1.0);
  WarpedDynamicsOptions options;
  options.time_step = 0.01;
  options.cg_max_iterations = 300;
  WarpedDynamics sim(model, options);
  RunSummary summary;
  summary.max_eigenvalue = maxEigenvalue(model);
  const Vec3 omega(0.4, -0.3, 2.0), com = sim.centerOfMass();
  Eigen::VectorXd v(sim.numDofs());
  for (int i = 0; i < sim.numNodes(); ++i)
    v.segment<3>(3 * i) = omega.cross(sim.positions().segment<3>(3 * i) - com);
  sim.setVelocities(v);
  summary.initial_energy = summary.max_energy = sim.totalEnergy();
  for (int s = 0; s < steps && summary.finite; ++s) {
    const StepStatistics stats = sim.step();
    summary.max_iterations = std::max(summary.max_iterations, stats.solver_iterations);
    summary.unconverged_steps += !stats.converged;
    const double energy = sim.totalEnergy();
    summary.finite = std::isfinite(energy) && sim.positions().allFinite();
    summary.max_energy = std::max(summary.max_energy, energy);
    summary.final_energy = energy;
  }
  return summary;
}

TEST(SliverRemoval, ExtremesFlattenedTetrahedronAndNeedlesRunStablyAfterRemoval) {
  const PlantedMesh planted = plantedMesh(1e-5);
  const SliverRemovalResult removed = removeSlivers(planted.mesh);
  ASSERT_EQ(removed.num_rejected, 0);
  const int steps = 200;
  const RunSummary before = spin(planted.mesh, steps);
  const RunSummary after = spin(removed.mesh, steps);
  const RunSummary clean =
      spin(PolyhedralMesh::tetrahedralGrid(Vec3(0, 0, 0), Vec3(1, 1, 1), kCells, kCells, kCells), steps);
  for (const auto& [name, run] : {std::make_pair("with defects", before), std::make_pair("removed", after),
                                  std::make_pair("clean grid", clean)})
    std::printf(
        "%-13s lambda_max %.3e, CG iterations max %4d, unconverged steps %3d, E0 %.6e, Emax/E0 %.6f, "
        "Eend/E0 %.6f, finite %d\n",
        name, run.max_eigenvalue, run.max_iterations, run.unconverged_steps, run.initial_energy,
        run.max_energy / run.initial_energy, run.final_energy / run.initial_energy, run.finite);
  // Without removal: the spectrum is dominated by the flat elements and CG does not converge in any step.
  EXPECT_GT(before.max_eigenvalue, 1e3 * after.max_eigenvalue);
  EXPECT_EQ(before.unconverged_steps, steps);
  // With removal: a spectrum near the clean grid's, every step converged, energy as on the clean grid.
  EXPECT_LT(after.max_eigenvalue, 5.0 * clean.max_eigenvalue);
  EXPECT_TRUE(after.finite);
  EXPECT_EQ(after.unconverged_steps, 0);
  EXPECT_LT(after.max_energy, 1.05 * after.initial_energy);
  EXPECT_GT(after.final_energy, 0.95 * after.initial_energy);
  EXPECT_NEAR(after.max_energy / after.initial_energy, clean.max_energy / clean.initial_energy, 1e-3);
}

// Automatic removal after cuts (removeCutSlivers): only the elements the cut created are examined, so the
// planted defects far from a cut stay; a thin tetrahedral slice is merged with its volume kept.
TEST(CutSliverRemoval, ExaminesOnlyTheElementsTheCutCreated) {
  const PlantedMesh planted = plantedMesh(1e-3);
  const std::vector<ElementDefect> before = classifyElements(planted.mesh);
  // z = 0.1: through the bottom layer of boxes, away from the planted nodes (z >= 0.25).
  const PlaneCutResult cut = cutMeshByPlane(planted.mesh, {}, Vec3(0, 0, 0.1), Vec3(0, 0, 1));
  const std::vector<ElementDefect> after = classifyElements(cut.mesh);
  std::printf("cut away from the planted defects: %d split, %d candidates, %d thin; defects %d -> %d\n",
              cut.num_split_elements, cut.slivers.num_candidates, cut.slivers.num_thin,
              static_cast<int>(before.size()) - countDefects(before, ElementDefect::kNone),
              static_cast<int>(after.size()) - countDefects(after, ElementDefect::kNone));
  EXPECT_EQ(cut.slivers.num_candidates, 2 * cut.num_split_elements);
  EXPECT_EQ(cut.slivers.num_thin, 0);
  EXPECT_EQ(cut.mesh.numElements(), planted.mesh.numElements() + cut.num_split_elements);
  EXPECT_EQ(countDefects(after, ElementDefect::kSliver), planted.expected_flat);
  EXPECT_EQ(countDefects(after, ElementDefect::kNeedle), planted.expected_needles);
}

TEST(CutSliverRemoval, MergesAThinSliceOfATetrahedralGrid) {
  // x = 1 - 1e-3 h through the Kuhn grid: thin wedges and tetrahedra at the block face, merged back.
  const PolyhedralMesh grid =
      PolyhedralMesh::tetrahedralGrid(Vec3(0, 0, 0), Vec3(1, 1, 1), kCells, kCells, kCells);
  const double h = 1.0 / kCells;
  PlaneCutOptions off;
  off.slivers.enabled = false;
  const Vec3 point(1.0 - 1e-3 * h, 0, 0), normal(1, 0, 0);
  const PlaneCutResult kept = cutMeshByPlane(grid, {}, point, normal, off);
  const PlaneCutResult merged = cutMeshByPlane(grid, {}, point, normal);
  std::printf(
      "tet grid slice: off %d elements (min relative thickness %.2e); on %d elements: %d thin, %d removed, "
      "%d collapsed, %d rejected, %d merged nodes, %d new nodes, volume - 1 = %.2e, min relative thickness "
      "%.3f\n",
      kept.mesh.numElements(), minRelativeThickness(kept.mesh), merged.mesh.numElements(),
      merged.slivers.num_thin, merged.slivers.num_removed, merged.slivers.num_collapsed,
      merged.slivers.num_rejected, merged.slivers.num_merged_nodes, merged.slivers.num_new_nodes,
      merged.mesh.volume() - 1.0, minRelativeThickness(merged.mesh));
  EXPECT_EQ(kept.mesh.numElements(), grid.numElements() + kept.num_split_elements);
  EXPECT_GT(merged.slivers.num_thin, 0);
  EXPECT_EQ(merged.slivers.num_rejected, 0);
  // Thin wedges along grid edges collapse onto the edge when their new nodes snap to its nodes.
  EXPECT_EQ(kept.mesh.numElements() - merged.mesh.numElements(),
            merged.slivers.num_removed + merged.slivers.num_collapsed);
  EXPECT_EQ(merged.mesh.numElements(), grid.numElements());
  EXPECT_EQ(merged.mesh.numNodes(), grid.numNodes());
  EXPECT_NEAR(merged.mesh.volume(), 1.0, 1e-11);
  EXPECT_GT(minRelativeThickness(merged.mesh), 0.1);
  // Values follow the nodes: a linear field through the stencils is the field at the node's place before
  // the projection onto its sliver plane (at most the projection distance away).
  ASSERT_EQ(static_cast<int>(merged.node_stencils.size()), merged.mesh.numNodes());
  double stencil_error = 0.0;
  for (int v = 0; v < merged.mesh.numNodes(); ++v) {
    Vec3 x = Vec3::Zero();
    for (const auto& [u, w] : merged.node_stencils[v]) x += w * grid.node(u);
    stencil_error = std::max(stencil_error, (x - merged.mesh.node(v)).norm());
  }
  EXPECT_LE(stencil_error, merged.slivers.max_projection_distance + 1e-12);
}

TEST(CutSliverRemoval, PartialPolygonCutKeepsCrackAndVolume) {
  // A polygon over half the block (y < 0.5) at x = 1/4 + 1e-3 h: thin slices along the crack, which ends
  // inside the block (partial cut: the crack front nodes stay shared).
  const PolyhedralMesh grid =
      PolyhedralMesh::hexahedralGrid(Vec3(0, 0, 0), Vec3(1, 1, 1), kCells, kCells, kCells);
  const double x = 0.25 + 1e-3 * 0.25;
  const std::vector<Vec3> polygon = {Vec3(x, -1, -1), Vec3(x, 0.5, -1), Vec3(x, 0.5, 2), Vec3(x, -1, 2)};
  PolygonCutOptions off;
  off.slivers.enabled = false;
  ProgressiveCutMesh kept(grid, {}, off), merged(grid);
  const PolygonCutStats kept_stats = kept.cut(polygon), stats = merged.cut(polygon);
  kept.validate();
  merged.validate();
  std::printf(
      "partial polygon slice: off %d elements, %d crack faces; on %d elements, %d crack faces: %d thin, %d "
      "removed, %d rejected; volume - 1 = %.2e, components %d\n",
      kept.numElements(), kept.numCrackFaces(), merged.numElements(), merged.numCrackFaces(),
      stats.slivers.num_thin, stats.slivers.num_removed, stats.slivers.num_rejected, merged.volume() - 1.0,
      merged.numComponents());
  EXPECT_EQ(kept_stats.slivers.num_removed, 0);
  EXPECT_GT(stats.slivers.num_thin, 0);
  EXPECT_EQ(stats.slivers.num_removed, stats.slivers.num_thin);
  EXPECT_EQ(merged.numElements(), kept.numElements() - stats.slivers.num_removed);
  EXPECT_NEAR(merged.volume(), 1.0, 1e-12);
  EXPECT_EQ(merged.numComponents(), 1);
  EXPECT_GT(merged.numCrackFaces(), 0);
  const PolyhedralMesh body = merged.componentMesh(0);  // one valid mesh with its crack faces listed
  EXPECT_NEAR(body.volume(), 1.0, 1e-12);
  EXPECT_EQ(body.numCrackFaces(), merged.numCrackFaces());
}

TEST(CutSliverRemoval, RejectsBadParameters) {
  EditableMesh mesh{{}, {}, {}, {}};
  CutSliverOptions options;
  options.relative_thickness = 1.0;
  EXPECT_THROW(removeCutSlivers(mesh, {}, 0, 1e-10, options), std::invalid_argument);
  options = CutSliverOptions();
  options.merge_relative_distance = 0.5;
  EXPECT_THROW(removeCutSlivers(mesh, {}, 0, 1e-10, options), std::invalid_argument);
  options = CutSliverOptions();
  options.max_relative_tolerance = 0.0;
  EXPECT_THROW(removeCutSlivers(mesh, {}, 0, 1e-10, options), std::invalid_argument);
}

}  // namespace
}  // namespace rc
