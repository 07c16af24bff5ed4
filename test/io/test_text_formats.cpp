// OFF, OBJ and XYZ readers and writers.
#include <gtest/gtest.h>

#include "io_test_support.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/obj_io.h"
#include "relaxed_connectivity/io/off_io.h"
#include "relaxed_connectivity/io/xyz_io.h"

namespace rc {
namespace {

using test::tempPath;
using test::writeText;

TriangleMesh richMesh() {
  TriangleMesh mesh = test::makeOctahedron();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (auto& p : mesh.vertices.positions) p += Vec3(u(rng), u(rng), u(rng)) * 1e-3;  // arbitrary doubles
  for (const auto& p : mesh.vertices.positions) mesh.vertices.normals.push_back(p.normalized());
  for (int i = 0; i < 6; ++i) mesh.vertices.colors.push_back(Rgba{uint8_t(40 * i), uint8_t(255 - i), 7, 255});
  return mesh;
}

TEST(OffIo, RoundTripWithNormalsAndColours) {
  const TriangleMesh mesh = richMesh();
  const std::string path = tempPath("rich.off");
  writeOffMesh(path, mesh);
  EXPECT_EQ(test::readFirstLine(path), "CNOFF");
  const TriangleMesh back = readOffMesh(path);
  test::expectCloudsEqual(mesh.vertices, back.vertices);
  EXPECT_EQ(back.triangles, mesh.triangles);
}

TEST(OffIo, CommentsPolygonsAndFloatColours) {
  writeText(tempPath("poly.off"),
            "# leading comment\nCOFF\n\n5 2 0 # counts\n"
            "0 0 0 1.0 0.5 0.0 1.0\n1 0 0 1 0 0 1\n1 1 0 0 0 1 1\n0 1 0 0 0 0 1\n0.5 2 0 0.2 0.2 0.2 1\n"
            "4 0 1 2 3 255 0 0\n# comment between faces\n3 3 2 4\n");
  const TriangleMesh mesh = readOffMesh(tempPath("poly.off"));
  ASSERT_EQ(mesh.vertices.size(), 5u);
  EXPECT_EQ(mesh.vertices.colors[0], (Rgba{255, 128, 0, 255}));
  EXPECT_EQ(mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}, {3, 2, 4}}));
}

TEST(OffIo, CountsOnTheHeaderLineAndIntegerColours) {
  writeText(tempPath("inline.off"), "COFF 3 1 0\n0 0 0 10 20 30 40\n1 0 0 1 2 3 4\n0 1 0 5 6 7 8\n3 0 1 2\n");
  const TriangleMesh mesh = readOffMesh(tempPath("inline.off"));
  EXPECT_EQ(mesh.vertices.colors[0], (Rgba{10, 20, 30, 40}));
  EXPECT_EQ(mesh.triangles.size(), 1u);
}

TEST(ObjIo, RoundTripWithNormalsAndColours) {
  const TriangleMesh mesh = richMesh();
  const std::string path = tempPath("rich.obj");
  writeObjMesh(path, mesh);
  const TriangleMesh back = readObjMesh(path);
  test::expectCloudsEqual(mesh.vertices, back.vertices);
  EXPECT_EQ(back.triangles, mesh.triangles);
}

TEST(ObjIo, AllCornerFormsAndNegativeIndices) {
  writeText(tempPath("corners.obj"),
            "# test\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvt 0 0\nvt 1 0\n"
            "vn 0 0 1\nvn 0 0 -1\ng group\nusemtl m\ns off\n"
            "f 1 2 3\nf 1/1 3/2 4/1\nf 1//2 2//2 3//2 4//2\nf -4/1/1 -3/2/1 -2/1/1\nl 1 2\n");
  const TriangleMesh mesh = readObjMesh(tempPath("corners.obj"));
  ASSERT_EQ(mesh.vertices.size(), 4u);
  EXPECT_FALSE(mesh.vertices.hasColors());
  const std::vector<Triangle> expected = {{0, 1, 2}, {0, 2, 3}, {0, 1, 2}, {0, 2, 3}, {0, 1, 2}};
  EXPECT_EQ(mesh.triangles, expected);
  // vertex 3 got vn 2 from the quad, vertices 0-2 were last given vn 1 by the negative-index face
  ASSERT_TRUE(mesh.vertices.hasNormals());
  EXPECT_EQ(mesh.vertices.normals[0], Vec3(0, 0, 1));
  EXPECT_EQ(mesh.vertices.normals[3], Vec3(0, 0, -1));
}

TEST(ObjIo, OutOfRangeIndexNamesTheLine) {
  writeText(tempPath("bad_index.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
  try {
    readObjMesh(tempPath("bad_index.obj"));
    FAIL() << "no exception";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bad_index.obj: line 4: vertex index 4 out of range"), std::string::npos) << what;
  }
}

TEST(XyzIo, RoundTripWithAndWithoutNormals) {
  SurfelCloud cloud = richMesh().vertices;
  cloud.colors.clear();
  const std::string path = tempPath("cloud.xyz");
  writeXyzCloud(path, cloud);
  test::expectCloudsEqual(cloud, readXyzCloud(path));
  cloud.normals.clear();
  writeXyzCloud(path, cloud);
  test::expectCloudsEqual(cloud, readXyzCloud(path));
}

TEST(XyzIo, CommentsAndMixedColumnCounts) {
  writeText(tempPath("c.xyz"), "# x y z\n1 2 3 # first\n\n4 5 6\n");
  const SurfelCloud cloud = readXyzCloud(tempPath("c.xyz"));
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.positions[1], Vec3(4, 5, 6));
  EXPECT_FALSE(cloud.hasNormals());
  writeText(tempPath("mixed.xyz"), "1 2 3\n4 5 6 0 0 1\n");
  try {
    readXyzCloud(tempPath("mixed.xyz"));
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("mixed.xyz: line 2: expected 3 values"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rc
