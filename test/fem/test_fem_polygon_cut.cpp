// Progressive cuts by polygons (thesis 9.3.2): partial cuts keep the material connected at the crack front,
// completing cuts separate it, non-planar cut surfaces, degenerate cuts through nodes and faces, pockets,
// and a Fig. 9.9-like slicing sequence.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "cut_test_support.h"
#include "relaxed_connectivity/fem/polygon_cut.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {
namespace {

const Eigen::Matrix3d kGradient =
    (Eigen::Matrix3d() << 0.01, -0.02, 0.03, 0.015, 0.005, -0.01, -0.02, 0.01, 0.025).finished();
const Vec3 kOffset(0.1, -0.2, 0.05);

std::vector<Vec3> linearField(const std::vector<Vec3>& nodes) {
  std::vector<Vec3> u;
  for (const Vec3& x : nodes) u.push_back(kGradient * x + kOffset);
  return u;
}

double maxLinearFieldError(const ProgressiveCutMesh& cut) {
  double worst = 0.0;
  for (int i = 0; i < cut.numNodes(); ++i)
    worst = std::max(worst, (cut.displacements()[i] - kGradient * cut.nodes()[i] - kOffset).norm());
  return worst;
}

std::vector<double> componentVolumes(const ProgressiveCutMesh& cut) {
  std::vector<double> volumes;
  for (int c = 0; c < cut.numComponents(); ++c) volumes.push_back(cut.componentMesh(c).volume());
  std::sort(volumes.begin(), volumes.end());
  return volumes;
}

TEST(PolygonCut, HalfCutStaysConnectedAndSecondPolygonSeparates) {
  ProgressiveCutMesh cut(block(), linearField(block().nodes()));
  // Top half of the plane x = 1.5 (through the middle column of cells), wider than the block in y.
  const PolygonCutStats first = cut.cut(quadX(1.5, -1.0, 4.0, 1.5, 4.0));
  cut.validate();
  EXPECT_NEAR(cut.volume(), 27.0, 1e-12 * 27.0);
  EXPECT_EQ(first.num_split_elements, 6);  // middle-column cells with z in [1, 3]
  EXPECT_EQ(cut.numElements(), 33);
  // 12 plane crossings of x-edges at z = 1, 2, 3 and 4 nodes on the crack front z = 1.5.
  EXPECT_EQ(first.num_new_nodes, 16);
  // The crack opens at the 8 crossings at z = 2, 3; the front nodes at z = 1.5 stay shared.
  EXPECT_EQ(first.num_duplicated_nodes, 8);
  EXPECT_EQ(first.num_pocket_nodes, 0);
  EXPECT_EQ(cut.numNodes(), 64 + 16 + 8);
  EXPECT_EQ(cut.numCrackFaces(), 12);                   // 6 crack pieces, one face per side
  EXPECT_EQ(cut.numComponents(), 1);                    // connected through the uncut part
  EXPECT_EQ(cut.componentMesh(0).numCrackFaces(), 12);  // internal crack: listed crack faces
  EXPECT_LT(maxLinearFieldError(cut), 1e-15);

  // The second polygon shares the front edge and completes the cut.
  const PolygonCutStats second = cut.cut(quadX(1.5, -1.0, 4.0, -1.0, 1.5));
  cut.validate();
  EXPECT_EQ(second.num_split_elements, 3);
  EXPECT_EQ(second.num_new_nodes, 4);          // crossings at z = 0
  EXPECT_EQ(second.num_duplicated_nodes, 12);  // z = 0, 1 and the old front z = 1.5
  EXPECT_EQ(cut.numElements(), 36);
  EXPECT_EQ(cut.numNodes(), 64 + 20 + 20);
  EXPECT_EQ(cut.numCrackFaces(), 24);
  EXPECT_EQ(cut.numComponents(), 2);
  const std::vector<double> volumes = componentVolumes(cut);
  EXPECT_NEAR(volumes[0], 13.5, 1e-12 * 27.0);
  EXPECT_NEAR(volumes[1], 13.5, 1e-12 * 27.0);
  EXPECT_LT(maxLinearFieldError(cut), 1e-15);
  std::printf(
      "half cut: %d nodes %d elements, 1 component; completed: %d nodes %d elements, volumes %.15g + "
      "%.15g\n",
      64 + 16 + 8, 33, cut.numNodes(), cut.numElements(), volumes[0], volumes[1]);
}

TEST(PolygonCut, NonPlanarCutOfTwoPolygonsAtAnAngle) {
  ProgressiveCutMesh cut(block(), linearField(block().nodes()));
  // Vertical down to z = 1.5, then inclined (x = 1.5 + (1.5 - z) / 2) through the bottom.
  const std::vector<std::vector<Vec3>> surface = {
      quadX(1.5, -1.0, 4.0, 1.5, 4.0),
      {Vec3(1.5, -1, 1.5), Vec3(1.5, 4, 1.5), Vec3(2.5, 4, -0.5), Vec3(2.5, -1, -0.5)}};
  const std::vector<PolygonCutStats> stats = cut.cutSurface(surface);
  ASSERT_EQ(cut.numComponents(), 2);
  cut.validate();
  EXPECT_NEAR(cut.volume(), 27.0, 1e-12 * 27.0);
  // Left: 3 * (1.5 * 1.5 + integral_0^1.5 (1.5 + (1.5 - z) / 2) dz) = 15.1875.
  const std::vector<double> volumes = componentVolumes(cut);
  EXPECT_NEAR(volumes[0], 27.0 - 15.1875, 1e-12 * 27.0);
  EXPECT_NEAR(volumes[1], 15.1875, 1e-12 * 27.0);
  // Below z = 1.5: the right halves of cells (1, j, 1) and cells (1, j, 0), (2, j, 0).
  EXPECT_EQ(stats[1].num_split_elements, 9);
  EXPECT_LT(maxLinearFieldError(cut), 1e-14);
  std::printf("V cut: %d + %d split elements, %d nodes, %d elements, %d crack faces, volumes %.15g %.15g\n",
              stats[0].num_split_elements, stats[1].num_split_elements, cut.numNodes(), cut.numElements(),
              cut.numCrackFaces(), volumes[0], volumes[1]);

  // Stopping the inclined polygon inside the block leaves one component.
  ProgressiveCutMesh partial(block());
  partial.cut(surface[0]);
  partial.cut({Vec3(1.5, -1, 1.5), Vec3(1.5, 4, 1.5), Vec3(1.9, 4, 0.7), Vec3(1.9, -1, 0.7)});
  partial.validate();
  EXPECT_EQ(partial.numComponents(), 1);
  EXPECT_NEAR(partial.volume(), 27.0, 1e-12 * 27.0);
}

TEST(PolygonCut, DegenerateCutsThroughGridFacesEdgesAndNodes) {
  // Along the grid plane x = 1: no element is crossed; the faces in the plane become crack faces.
  ProgressiveCutMesh faces(block());
  const PolygonCutStats first = faces.cut(quadX(1.0, -1.0, 4.0, 1.0, 4.0));  // front on grid edges z = 1
  faces.validate();
  EXPECT_EQ(first.num_split_elements, 0);
  EXPECT_EQ(first.num_new_nodes, 0);
  EXPECT_EQ(first.num_duplicated_nodes, 8);  // grid nodes x = 1, z = 2, 3
  EXPECT_EQ(faces.numCrackFaces(), 12);
  EXPECT_EQ(faces.numComponents(), 1);
  faces.cut(quadX(1.0, -1.0, 4.0, -1.0, 1.0));
  faces.validate();
  EXPECT_EQ(faces.numNodes(), 64 + 16);
  EXPECT_EQ(faces.numElements(), 27);
  std::vector<double> volumes = componentVolumes(faces);
  ASSERT_EQ(volumes.size(), 2u);
  EXPECT_NEAR(volumes[0], 9.0, 1e-12 * 27.0);
  EXPECT_NEAR(volumes[1], 18.0, 1e-12 * 27.0);

  // Diagonal plane x = y through grid nodes and edges: the diagonal cells split into prisms, no new nodes.
  ProgressiveCutMesh diagonal(block());
  const PolygonCutStats d = diagonal.cut({Vec3(-1, -1, -1), Vec3(4, 4, -1), Vec3(4, 4, 4), Vec3(-1, -1, 4)});
  diagonal.validate();
  EXPECT_EQ(d.num_split_elements, 9);
  EXPECT_EQ(d.num_new_nodes, 0);
  EXPECT_EQ(d.num_duplicated_nodes, 16);
  EXPECT_EQ(diagonal.numElements(), 36);
  volumes = componentVolumes(diagonal);
  ASSERT_EQ(volumes.size(), 2u);
  EXPECT_NEAR(volumes[0], 13.5, 1e-12 * 27.0);
  EXPECT_NEAR(volumes[1], 13.5, 1e-12 * 27.0);

  // A plane 1e-9 off the grid nodes snaps onto them (no needles) and the block still separates.
  ProgressiveCutMesh near(block());
  const PolygonCutStats s = near.cut(quadX(1.0 + 1e-9, -1.0, 4.0, -1.0, 4.0));
  near.validate();
  EXPECT_EQ(s.num_split_elements, 0);
  EXPECT_EQ(s.num_new_nodes, 0);
  EXPECT_EQ(near.numComponents(), 2);
}

TEST(PolygonCut, PolygonInsideOneElementCreatesAPocket) {
  ProgressiveCutMesh cut(block(), linearField(block().nodes()));
  // A square strictly inside the centre cell: no node can open, a centroid node is added (9.3.2).
  const PolygonCutStats stats = cut.cut(quadX(1.5, 1.25, 1.75, 1.25, 1.75));
  cut.validate();
  EXPECT_EQ(stats.num_split_elements, 1);
  // 4 crossings of the cell's x-edges, 4 polygon-edge-line nodes on the section boundary, 4 polygon corners.
  EXPECT_EQ(stats.num_new_nodes, 4 + 4 + 4);
  EXPECT_EQ(stats.num_pocket_nodes, 1);
  EXPECT_EQ(stats.num_duplicated_nodes, 1);  // only the centroid opens
  EXPECT_EQ(cut.numNodes(), 64 + 12 + 2);
  EXPECT_EQ(cut.numElements(), 28);
  EXPECT_EQ(cut.numCrackFaces(), 8);  // the inner square fanned into 4 triangles, per side
  EXPECT_EQ(cut.numComponents(), 1);
  EXPECT_NEAR(cut.volume(), 27.0, 1e-12 * 27.0);
  EXPECT_LT(maxLinearFieldError(cut), 1e-15);
}

// Slices through the block, each swept by the blade as a sequence of strips sharing their edges.
TEST(PolygonCut, Fig99LikeSlicingSequence) {
  const PolyhedralMesh start = block();
  ProgressiveCutMesh cut(start);
  const int steps = 8;
  int splits = 0, created = 0;
  const std::vector<Vec3> slice_points = {Vec3(0.7, 0, 0), Vec3(1.45, 0, 0), Vec3(2.3, 0, 0)};
  const std::vector<Vec3> slice_normals = {Vec3(1, 0.05, 0.1), Vec3(1, -0.1, 0.05), Vec3(1, 0.08, -0.12)};
  for (size_t s = 0; s < slice_points.size(); ++s) {
    const Vec3 n = slice_normals[s].normalized();
    const Vec3 a = n.cross(Vec3::UnitZ()).normalized(), b = n.cross(a);  // in-plane directions
    const Vec3 o = slice_points[s] + Vec3(0, 1.5, 1.5) - n * n.dot(Vec3(0, 1.5, 1.5));
    for (int k = 0; k < steps; ++k) {
      const double t0 = -3.0 + 6.0 * k / steps, t1 = -3.0 + 6.0 * (k + 1) / steps;
      const PolygonCutStats stats =
          cut.cut({o - 3 * a + t0 * b, o + 3 * a + t0 * b, o + 3 * a + t1 * b, o - 3 * a + t1 * b});
      splits += stats.num_split_elements;
      created += stats.num_new_nodes + stats.num_pocket_nodes + stats.num_duplicated_nodes;
      EXPECT_NEAR(cut.volume(), 27.0, 1e-12 * 27.0);
    }
    cut.validate();
    EXPECT_EQ(cut.numComponents(), static_cast<int>(s) + 2) << "after slice " << s;
  }
  EXPECT_EQ(cut.numElements(), 27 + splits);
  EXPECT_EQ(cut.numNodes(), 64 + created);
  double total = 0.0;
  for (double v : componentVolumes(cut)) total += v;
  EXPECT_NEAR(total, 27.0, 1e-12 * 27.0);
  std::printf(
      "Fig. 9.9-like: 3 slices x %d blade steps: start 64 nodes 27 elements -> %d nodes %d elements "
      "(%d crack faces, %d duplicated nodes); thesis Table 9.1: 64/27 -> 1214/60\n",
      steps, cut.numNodes(), cut.numElements(), cut.numCrackFaces(), cut.numDuplicatedNodes());
}

// Oblique blade sweeps through tetrahedral and irregular convex meshes: valid after every polygon, one
// component while the cut is partial, two once it is complete, volume and linear displacements preserved.
TEST(PolygonCut, ObliqueSweepThroughTetrahedralAndIrregularMeshes) {
  const std::vector<PolyhedralMesh> meshes = {
      PolyhedralMesh::tetrahedralGrid(Vec3(0, 0, 0), Vec3(2, 1, 1.5), 4, 3, 3),
      PolyhedralMesh::randomPlaneCut(Vec3(0, 0, 0), Vec3(2, 1, 1.5), 3, 2, 2, 4, 7u)};
  for (const PolyhedralMesh& mesh : meshes) {
    ProgressiveCutMesh cut(mesh, linearField(mesh.nodes()));
    const Vec3 n = Vec3(1, 0.3, 0.2).normalized();
    const Vec3 a = n.cross(Vec3::UnitZ()).normalized(), b = n.cross(a);
    const Vec3 o = Vec3(1.03, 0.5, 0.75);
    const int steps = 5;
    int partial_steps = 0, components = 1;
    for (int k = 0; k < steps; ++k) {
      const double t0 = -2.0 + 4.0 * k / steps, t1 = -2.0 + 4.0 * (k + 1) / steps;
      cut.cut({o - 2 * a + t0 * b, o + 2 * a + t0 * b, o + 2 * a + t1 * b, o - 2 * a + t1 * b});
      ASSERT_NO_THROW(cut.validate()) << "step " << k;
      EXPECT_NEAR(cut.volume(), mesh.volume(), 1e-12 * mesh.volume());
      const int now = cut.numComponents();
      EXPECT_GE(now, components) << "step " << k;  // cracks never heal
      components = now;
      partial_steps += now == 1 && cut.numCrackFaces() > 0;
    }
    EXPECT_GE(partial_steps, 2);  // the blade is inside the material for at least two steps
    EXPECT_EQ(components, 2);
    EXPECT_LT(maxLinearFieldError(cut), 1e-14);
    const std::vector<double> volumes = componentVolumes(cut);
    EXPECT_NEAR(volumes[0] + volumes[1], mesh.volume(), 1e-12 * mesh.volume());
    std::printf("oblique sweep: %d/%d -> %d nodes %d elements, %d partial steps, volumes %.6f + %.6f\n",
                mesh.numNodes(), mesh.numElements(), cut.numNodes(), cut.numElements(), partial_steps,
                volumes[0], volumes[1]);
  }
}

TEST(PolygonCut, RejectsBadInput) {
  EXPECT_THROW(ProgressiveCutMesh(block(), std::vector<Vec3>(3)), std::invalid_argument);
  PolygonCutOptions options;
  options.snap_relative_distance = -1.0;
  EXPECT_THROW(ProgressiveCutMesh(block(), {}, options), std::invalid_argument);
  ProgressiveCutMesh cut(block());
  EXPECT_THROW(cut.cut({Vec3(0, 0, 0), Vec3(1, 0, 0)}), std::invalid_argument);  // too few points
  std::vector<Vec3> bow = quadX(1.5, 0, 1, 0, 1);
  std::swap(bow[1], bow[2]);
  EXPECT_THROW(cut.cut(bow), std::invalid_argument);  // not convex
  std::vector<Vec3> bent = quadX(1.5, 0, 1, 0, 1);
  bent[2].x() += 0.1;
  EXPECT_THROW(cut.cut(bent), std::invalid_argument);  // not planar
  std::vector<Vec3> infinite = quadX(1.5, 0, 1, 0, 1);
  infinite[0].y() = NAN;
  EXPECT_THROW(cut.cut(infinite), std::invalid_argument);
  EXPECT_EQ(cut.numElements(), 27);  // nothing changed
  EXPECT_THROW(cut.componentMesh(1), std::invalid_argument);
}

}  // namespace
}  // namespace rc
