// Prebuilt elements (PolyhedralMesh, ProgressiveCutMesh::componentMesh): after a cut only the elements the
// cut changed are built and validated again; the others are taken over from the input mesh and equal a
// fresh build bit for bit. Mismatching or badly sized prebuilt lists are rebuilt or rejected.
#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "cut_test_support.h"
#include "relaxed_connectivity/fem/polygon_cut.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {
namespace {

bool sameBits(double a, double b) {
  return std::memcmp(&a, &b, sizeof(double)) == 0;
}

void expectSameElement(const ConvexPolyhedron& a, const ConvexPolyhedron& b) {
  ASSERT_EQ(a.numNodes(), b.numNodes());
  for (int i = 0; i < a.numNodes(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(sameBits(a.node(i)[k], b.node(i)[k]));
  EXPECT_EQ(a.globalNodeIds(), b.globalNodeIds());
  EXPECT_EQ(a.faces(), b.faces());
  EXPECT_EQ(a.triangles(), b.triangles());
  EXPECT_EQ(a.triangleFace(), b.triangleFace());
  EXPECT_TRUE(sameBits(a.volume(), b.volume()));
  EXPECT_TRUE(sameBits(a.scale(), b.scale()));
  EXPECT_TRUE(sameBits(a.tolerance(), b.tolerance()));
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(sameBits(a.centroid()[k], b.centroid()[k]));
  for (int f = 0; f < a.numFaces(); ++f) {
    EXPECT_TRUE(sameBits(a.faceOffset(f), b.faceOffset(f)));
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(sameBits(a.faceNormal(f)[k], b.faceNormal(f)[k]));
  }
}

void expectSameMesh(const PolyhedralMesh& a, const PolyhedralMesh& b) {
  ASSERT_EQ(a.numNodes(), b.numNodes());
  ASSERT_EQ(a.numElements(), b.numElements());
  for (int e = 0; e < a.numElements(); ++e) expectSameElement(a.element(e), b.element(e));
  EXPECT_EQ(a.boundaryTriangles(), b.boundaryTriangles());
  EXPECT_EQ(a.crackFaces(), b.crackFaces());
  EXPECT_EQ(a.numInteriorFaces(), b.numInteriorFaces());
  EXPECT_TRUE(sameBits(a.volume(), b.volume()));
}

TEST(PrebuiltElements, PartialCutTakesOverExactlyTheUnchangedElements) {
  // Plane x = 1.5 below z = 1.5 through the 3 x 3 x 3 block: the 6 cells it crosses are split (12 parts),
  // the 3 cells above them get crack-front nodes on their bottom edges; the other 18 cells are unchanged.
  const PolyhedralMesh input = block();
  ProgressiveCutMesh cut(input);
  cut.cut(quadX(1.5, -1.0, 4.0, -1.0, 1.5));
  ASSERT_EQ(cut.numComponents(), 1);
  int unchanged = 0;
  for (int source : cut.unchangedInputElements()) unchanged += source >= 0;
  EXPECT_EQ(unchanged, 18);
  std::vector<int> ids_fresh, ids_reused;
  const PolyhedralMesh fresh = cut.componentMesh(0, &ids_fresh);
  const PolyhedralMesh reused = cut.componentMesh(0, &ids_reused, &input);
  EXPECT_EQ(fresh.numPrebuiltElements(), 0);
  EXPECT_EQ(reused.numPrebuiltElements(), 18);
  EXPECT_EQ(reused.numElements(), 33);
  EXPECT_EQ(ids_fresh, ids_reused);
  expectSameMesh(fresh, reused);

  // A through cut separating the block: both components take over their unchanged cells.
  ProgressiveCutMesh through(input);
  through.cut(quadX(1.5, -1.0, 4.0, -1.0, 4.0));
  ASSERT_EQ(through.numComponents(), 2);
  int prebuilt = 0, elements = 0;
  for (int c = 0; c < 2; ++c) {
    const PolyhedralMesh side = through.componentMesh(c, nullptr, &input);
    prebuilt += side.numPrebuiltElements();
    elements += side.numElements();
    expectSameMesh(through.componentMesh(c), side);
  }
  EXPECT_EQ(elements, 36);  // 27 - 9 split cells + 18 parts
  EXPECT_EQ(prebuilt, 18);
}

TEST(PrebuiltElements, MismatchingElementsAreBuiltAnewAndBadListsRejected) {
  const PolyhedralMesh input = block();
  // Prebuilt elements of a shifted block: same topology, other node positions, so none is taken over.
  const PolyhedralMesh shifted = PolyhedralMesh::hexahedralGrid(Vec3(0, 0, 1), Vec3(3, 3, 4), 3, 3, 3);
  std::vector<PolyhedralMesh::ElementFaces> faces;
  std::vector<const ConvexPolyhedron*> prebuilt;
  for (int e = 0; e < input.numElements(); ++e) {
    faces.push_back(input.elementFaces(e));
    prebuilt.push_back(&shifted.element(e));
  }
  const PolyhedralMesh rebuilt(input.nodes(), faces, ConvexPolyhedron::kDefaultRelativeTolerance, {},
                               prebuilt);
  EXPECT_EQ(rebuilt.numPrebuiltElements(), 0);
  expectSameMesh(input, rebuilt);
  // The block's own elements are all taken over.
  for (int e = 0; e < input.numElements(); ++e) prebuilt[e] = &input.element(e);
  const PolyhedralMesh same(input.nodes(), faces, ConvexPolyhedron::kDefaultRelativeTolerance, {}, prebuilt);
  EXPECT_EQ(same.numPrebuiltElements(), 27);
  expectSameMesh(input, same);

  prebuilt.pop_back();
  EXPECT_THROW(
      PolyhedralMesh(input.nodes(), faces, ConvexPolyhedron::kDefaultRelativeTolerance, {}, prebuilt),
      std::invalid_argument);
  EXPECT_THROW(input.element(0).relabelled({0, 1, 2}, 1e-10), std::invalid_argument);
  EXPECT_THROW(input.element(0).relabelled(input.element(0).globalNodeIds(), 0.5), std::invalid_argument);
  ProgressiveCutMesh cut(input);
  cut.cut(quadX(1.5, -1.0, 4.0, -1.0, 1.5));
  const PolyhedralMesh other = PolyhedralMesh::hexahedralGrid(Vec3(0, 0, 0), Vec3(3, 3, 3), 3, 3, 2);
  EXPECT_THROW(cut.componentMesh(0, nullptr, &other), std::invalid_argument);
}

}  // namespace
}  // namespace rc
