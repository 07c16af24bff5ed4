#include <gtest/gtest.h>

#include "io_test_support.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/ply_io.h"

namespace rc {
namespace {

using test::expectCloudsEqual;
using test::tempPath;
using test::writeText;

template <typename T>
void appendBigEndian(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  for (size_t k = sizeof(T); k-- > 0;) out->push_back(bytes[k]);  // the test machine is little endian
}

TEST(PlyIo, RichCloudRoundTripsBitExactlyInEveryEncoding) {
  const SurfelCloud cloud = test::makeRichCloud(257);
  struct Case {
    const char* name;
    Encoding encoding;
    bool big_endian;
  };
  for (const Case& c : {Case{"ascii", Encoding::kAscii, false}, Case{"le", Encoding::kBinary, false},
                        Case{"be", Encoding::kBinary, true}}) {
    SCOPED_TRACE(c.name);
    const std::string path = tempPath(std::string("rich_") + c.name + ".ply");
    WriteOptions options;
    options.encoding = c.encoding;
    options.big_endian = c.big_endian;
    writePlyCloud(path, cloud, options);
    expectCloudsEqual(cloud, readPlyCloud(path));
  }
}

TEST(PlyIo, DoublePrecisionKeepsArbitraryDoubles) {
  SurfelCloud cloud;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 100; ++i) {
    cloud.positions.emplace_back(u(rng), u(rng), u(rng) * 1e-7);
    cloud.radii.push_back(std::abs(u(rng)) / 3.0);
  }
  for (Encoding e : {Encoding::kAscii, Encoding::kBinary}) {
    const std::string path = tempPath("double.ply");
    WriteOptions options;
    options.encoding = e;
    options.double_precision = true;
    writePlyCloud(path, cloud, options);
    expectCloudsEqual(cloud, readPlyCloud(path));
    // float32 storage rounds: the default loses the low bits
    writePlyCloud(path, cloud, WriteOptions{e, false, false});
    const SurfelCloud single = readPlyCloud(path);
    EXPECT_NE(single.positions[0].x(), cloud.positions[0].x());
    EXPECT_NEAR(single.positions[0].x(), cloud.positions[0].x(), 1e-7);
  }
}

TEST(PlyIo, MeshRoundTrip) {
  TriangleMesh mesh = test::makeOctahedron();
  mesh.vertices.colors.assign(6, Rgba{10, 20, 30, 40});
  for (Encoding e : {Encoding::kAscii, Encoding::kBinary}) {
    const std::string path = tempPath("octahedron.ply");
    writePlyMesh(path, mesh, WriteOptions{e, false, false});
    const TriangleMesh back = readPlyMesh(path);
    expectCloudsEqual(mesh.vertices, back.vertices);
    EXPECT_EQ(back.triangles, mesh.triangles);
    // readPlyCloud of a mesh file gives its vertices
    EXPECT_EQ(readPlyCloud(path).size(), 6u);
  }
}

TEST(PlyIo, ReadsHandWrittenBigEndianFile) {
  std::string ply =
      "ply\nformat binary_big_endian 1.0\ncomment hand written\nelement vertex 4\nproperty float x\n"
      "property float y\nproperty float z\nproperty short temperature\nproperty uchar red\nproperty uchar "
      "green\n"
      "property uchar blue\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";
  for (int i = 0; i < 4; ++i) {
    appendBigEndian<float>(&ply, 1.5f * i);
    appendBigEndian<float>(&ply, -2.25f);
    appendBigEndian<float>(&ply, 1e-3f * i);
    appendBigEndian<int16_t>(&ply, static_cast<int16_t>(-300 + 1000 * i));
    ply += static_cast<char>(200 + i);
    ply += static_cast<char>(i);
    ply += static_cast<char>(7);
  }
  ply += static_cast<char>(4);
  for (uint32_t v : {0u, 1u, 2u, 3u}) appendBigEndian<uint32_t>(&ply, v);
  const std::string path = tempPath("big_endian.ply");
  writeText(path, ply);
  const TriangleMesh mesh = readPlyMesh(path);
  ASSERT_EQ(mesh.vertices.size(), 4u);
  EXPECT_EQ(mesh.vertices.positions[3], Vec3(4.5, -2.25, double(3e-3f)));
  const Attribute* temperature = mesh.vertices.attributes.find("temperature");
  ASSERT_NE(temperature, nullptr);
  EXPECT_EQ(temperature->type, ScalarType::kInt16);
  EXPECT_EQ(temperature->get(0), -300.0);
  EXPECT_EQ(temperature->get(3), 2700.0);
  ASSERT_TRUE(mesh.vertices.hasColors());
  EXPECT_EQ(mesh.vertices.colors[2], (Rgba{202, 2, 7, 255}));
  // the quad is split into a fan
  EXPECT_EQ(mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));
}

TEST(PlyIo, AsciiFacesStripsAndSkippedElements) {
  const std::string ply =
      "ply\nformat ascii 1.0\n"
      "element camera 2\nproperty float f\nproperty list uchar int tags\n"
      "element vertex 6\nproperty double x\nproperty double y\nproperty double z\n"
      "property float normal_x\nproperty float normal_y\nproperty float normal_z\n"
      "property list uchar float samples\nproperty uchar quality\n"
      "element face 2\nproperty uchar flags\nproperty list uchar int vertex_index\n"
      "element tristrips 1\nproperty list int int vertex_indices\n"
      "end_header\n"
      "1.5 3 7 8 9\n2.5 0\n"
      "0 0 0 0 0 1 2 0.5 0.25 9\n1 0 0 0 0 1 0 10\n1 1 0 0 0 1 1 1.0 11\n"
      "0 1 0 0 0 1 0 12\n0.5 2 0 0 0 1 0 13\n2 2 0 0 0 1 0 14\n"
      "0 5 0 1 2 3 4\n1 3 3 4 5\n"
      "12 5 4 -1 0 1 2 3 -1 2 2 5 4\n";
  const std::string path = tempPath("ascii_mix.ply");
  writeText(path, ply);
  const TriangleMesh mesh = readPlyMesh(path);
  ASSERT_EQ(mesh.vertices.size(), 6u);
  EXPECT_EQ(mesh.vertices.positions[4], Vec3(0.5, 2, 0));
  ASSERT_TRUE(mesh.vertices.hasNormals());
  EXPECT_EQ(mesh.vertices.normals[5], Vec3(0, 0, 1));
  const Attribute* quality = mesh.vertices.attributes.find("quality");
  ASSERT_NE(quality, nullptr);
  EXPECT_EQ(quality->type, ScalarType::kUInt8);
  EXPECT_EQ(quality->get(5), 14.0);
  EXPECT_EQ(mesh.vertices.attributes.columns().size(), 1u);  // the list property is not an attribute
  const std::vector<Triangle> expected = {
      {0, 1, 2}, {0, 2, 3}, {0, 3, 4},  // pentagon fan
      {3, 4, 5},                        // triangle
      {0, 1, 2}, {2, 1, 3},             // strip 0 1 2 3 (second triangle flipped); strip "5 4" has none
      {5, 2, 4},  // strip 2 2 5 4: the first triangle is degenerate, the second (odd) is flipped
  };
  EXPECT_EQ(mesh.triangles, expected);
}

TEST(PlyIo, NumberedPropertiesFormOneColumn) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
      "property ushort feature_0\nproperty ushort feature_1\nproperty ushort feature_2\nproperty int misc_0\n"
      "end_header\n0 0 0 1 2 3 -4\n1 1 1 5 6 7 -8\n";
  const std::string path = tempPath("numbered.ply");
  writeText(path, ply);
  const SurfelCloud cloud = readPlyCloud(path);
  const Attribute* feature = cloud.attributes.find("feature");
  ASSERT_NE(feature, nullptr);
  EXPECT_EQ(feature->count, 3u);
  EXPECT_EQ(feature->get(1, 2), 7.0);
  const Attribute* misc = cloud.attributes.find("misc_0");  // a lone _0 stays a scalar column
  ASSERT_NE(misc, nullptr);
  EXPECT_EQ(misc->get(1), -8.0);
}

TEST(PlyIo, DropsInvalidVerticesAndTheirFacesOnRequest) {
  TriangleMesh mesh = test::makeOctahedron();
  mesh.vertices.positions[4] = Vec3(std::nan(""), 0, 0);
  const std::string path = tempPath("invalid.ply");
  writePlyMesh(path, mesh);
  EXPECT_EQ(readPlyMesh(path).vertices.size(), 6u);
  ReadOptions options;
  options.keep_invalid = false;
  const TriangleMesh kept = readPlyMesh(path, options);
  ASSERT_EQ(kept.vertices.size(), 5u);
  ASSERT_EQ(kept.triangles.size(), 4u);               // the 4 faces around vertex 4 are gone
  EXPECT_EQ(kept.triangles[0], (Triangle{2, 0, 4}));  // old vertex 5 is now 4
}

TEST(PlyIo, CompressedEncodingIsRejected) {
  const std::string path = tempPath("never.ply");
  WriteOptions options;
  options.encoding = Encoding::kBinaryCompressed;
  try {
    writePlyCloud(path, test::makeRichCloud(3), options);
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("never.ply"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("binary_compressed"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rc
