// Reads every model in the shared data folder and checks counts against the files' headers, PROVENANCE.md and
// values parsed by hand here (independently of the readers).
#include <gtest/gtest.h>

#include <unordered_set>

#include "io_test_support.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/io/file_bytes.h"

namespace rc {
namespace {

using test::sharedData;

size_t countFinite(const SurfelCloud& cloud) {
  size_t finite = 0;
  for (const Vec3& p : cloud.positions) finite += p.allFinite();
  return finite;
}

// Number of "element <name> N" in a PLY header, parsed by hand.
size_t headerCount(const std::string& bytes, const std::string& element) {
  const std::string key = "element " + element + " ";
  const size_t at = bytes.find(key);
  return at == std::string::npos ? 0 : std::stoul(bytes.substr(at + key.size(), 20));
}

size_t bodyOffset(const std::string& bytes, const std::string& marker) {
  return bytes.find(marker) + marker.size();
}

// Every index in range, no degenerate triangle, and no directed edge used twice (consistent orientation).
void expectValidOrientedMesh(const TriangleMesh& mesh) {
  const size_t n = mesh.vertices.size();
  size_t out_of_range = 0, degenerate = 0, repeated_edges = 0;
  std::unordered_set<uint64_t> directed;
  directed.reserve(mesh.triangles.size() * 3);
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) out_of_range += t[k] >= n;
    degenerate += t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
    for (int k = 0; k < 3; ++k)
      repeated_edges += !directed.insert(uint64_t(t[k]) << 32 | t[(k + 1) % 3]).second;
  }
  EXPECT_EQ(out_of_range, 0u);
  EXPECT_EQ(degenerate, 0u);
  EXPECT_EQ(repeated_edges, 0u);
}

TEST(SharedData, BunnyPly) {
  RC_REQUIRE_SHARED_DATA();
  const std::string bytes = readFileBytes(sharedData("bunny.ply"));
  const TriangleMesh mesh = readMesh(sharedData("bunny.ply"));
  EXPECT_EQ(mesh.vertices.size(), 35947u);
  EXPECT_EQ(headerCount(bytes, "face"), 69451u);
  EXPECT_EQ(mesh.triangles.size(), headerCount(bytes, "face"));  // all faces are triangles
  float first[3];
  std::memcpy(first, bytes.data() + bodyOffset(bytes, "end_header\n"), sizeof(first));
  EXPECT_EQ(mesh.vertices.positions[0], Vec3(first[0], first[1], first[2]));
  expectValidOrientedMesh(mesh);
}

TEST(SharedData, IgeaPlyTriangleStrips) {
  RC_REQUIRE_SHARED_DATA();
  const std::string bytes = readFileBytes(sharedData("igea.ply"));
  const TriangleMesh mesh = readMesh(sharedData("igea.ply"));
  ASSERT_EQ(mesh.vertices.size(), 134345u);
  EXPECT_GT(mesh.triangles.size(), 0u);
  // Hand count of the non-degenerate strip triangles: one list (int length, int indices) after the vertices.
  const char* strip = bytes.data() + bodyOffset(bytes, "end_header\n") + 134345 * 12;
  int32_t length;
  std::memcpy(&length, strip, 4);
  std::vector<int32_t> indices(length);
  std::memcpy(indices.data(), strip + 4, 4 * size_t(length));
  size_t expected = 0, run = 0;
  for (int32_t k = 0; k < length; ++k) {
    if (indices[k] == -1) {
      run = 0;
      continue;
    }
    if (++run >= 3)
      expected +=
          indices[k] != indices[k - 1] && indices[k] != indices[k - 2] && indices[k - 1] != indices[k - 2];
  }
  EXPECT_EQ(mesh.triangles.size(), expected);
  expectValidOrientedMesh(mesh);  // would fail massively if the strip parity were ignored
}

TEST(SharedData, DragonObj) {
  RC_REQUIRE_SHARED_DATA();
  const std::string bytes = readFileBytes(sharedData("dragon_50k.obj"));
  size_t face_lines = 0;
  for (size_t at = bytes.find("\nf "); at != std::string::npos; at = bytes.find("\nf ", at + 1)) ++face_lines;
  const TriangleMesh mesh = readMesh(sharedData("dragon_50k.obj"));
  EXPECT_EQ(mesh.vertices.size(), 50000u);
  EXPECT_EQ(mesh.triangles.size(), face_lines);
  EXPECT_EQ(face_lines, 100000u);
  expectValidOrientedMesh(mesh);
}

TEST(SharedData, ArmadilloPly) {
  RC_REQUIRE_SHARED_DATA();
  const std::string bytes = readFileBytes(sharedData("armadillo.ply"));
  const TriangleMesh mesh = readMesh(sharedData("armadillo.ply"));
  EXPECT_EQ(mesh.vertices.size(), 35374u);
  EXPECT_EQ(mesh.triangles.size(), headerCount(bytes, "face"));
  EXPECT_EQ(readCloud(sharedData("armadillo.ply")).size(), 35374u);
}

TEST(SharedData, OffModels) {
  RC_REQUIRE_SHARED_DATA();
  const TriangleMesh face = readMesh(sharedData("face_mask.off"));
  EXPECT_EQ(face.vertices.size(), 1180u);
  EXPECT_EQ(face.triangles.size(), 2000u);  // header "1180 2000 0", all triangles
  EXPECT_EQ(face.vertices.positions[0], Vec3(151.776611, 54.994499, 209.696597));
  expectValidOrientedMesh(face);
  const TriangleMesh bust = readMesh(sharedData("maxplanck_bust.off"));
  EXPECT_EQ(bust.vertices.size(), 12556u);
  EXPECT_EQ(bust.triangles.size(), 25108u);
  expectValidOrientedMesh(bust);
}

TEST(SharedData, KittenXyz) {
  RC_REQUIRE_SHARED_DATA();
  const SurfelCloud cloud = readCloud(sharedData("kitten.xyz"));
  ASSERT_EQ(cloud.size(), 5210u);
  ASSERT_TRUE(cloud.hasNormals());
  EXPECT_EQ(cloud.positions[0], Vec3(-0.0721898, -0.159749, -0.108444));
  EXPECT_EQ(cloud.normals[0], Vec3(0.340472, 0.937712, -0.0690972));
  size_t unit = 0;
  for (const Vec3& n : cloud.normals) unit += std::abs(n.norm() - 1.0) < 1e-4;
  EXPECT_EQ(unit, cloud.size());
}

TEST(SharedData, MilkPcds) {
  RC_REQUIRE_SHARED_DATA();
  const SurfelCloud color = readCloud(sharedData("pcl/milk_color.pcd"));
  const SurfelCloud plain = readCloud(sharedData("pcl/milk.pcd"));
  ASSERT_EQ(color.size(), 13704u);
  ASSERT_EQ(plain.size(), 13704u);
  EXPECT_TRUE(color.hasColors());
  EXPECT_FALSE(plain.hasColors());
  EXPECT_EQ(countFinite(color), 13704u);
  // the same scan: both compressed files decode to identical positions
  test::expectVecsEqual(plain.positions, color.positions, "milk positions");
  size_t grey = 0;  // a real photograph is not all one colour
  for (const Rgba& c : color.colors) grey += c[0] == color.colors[0][0] && c[1] == color.colors[0][1];
  EXPECT_LT(grey, color.size() / 2);
}

TEST(SharedData, OrganisedPcds) {
  RC_REQUIRE_SHARED_DATA();
  struct Case {
    const char* file;
    size_t finite;
  };
  for (const Case& c : {Case{"pcl/milk_cartoon_all_small_clorox.pcd", 241407},
                        Case{"pcl/table_scene_mug_stereo_textured.pcd", 209280}}) {
    SCOPED_TRACE(c.file);
    const SurfelCloud cloud = readCloud(sharedData(c.file));
    ASSERT_EQ(cloud.size(), 307200u);
    EXPECT_EQ(cloud.width, 640u);
    EXPECT_EQ(cloud.height, 480u);
    EXPECT_TRUE(cloud.isOrganized());
    EXPECT_TRUE(cloud.hasColors());
    EXPECT_EQ(countFinite(cloud), c.finite);
    ReadOptions drop;
    drop.keep_invalid = false;
    const SurfelCloud valid = readCloud(sharedData(c.file), drop);
    EXPECT_EQ(valid.size(), c.finite);
    EXPECT_EQ(countFinite(valid), c.finite);
  }
}

TEST(SharedData, ColoredCloudPcdMatchesHandParsedBinary) {
  RC_REQUIRE_SHARED_DATA();
  const std::string bytes = readFileBytes(sharedData("pcl/colored_cloud.pcd"));
  const SurfelCloud cloud = readCloud(sharedData("pcl/colored_cloud.pcd"));
  ASSERT_EQ(cloud.size(), 1000u);
  ASSERT_TRUE(cloud.hasNormals());
  ASSERT_TRUE(cloud.hasColors());
  ASSERT_TRUE(cloud.hasCurvature());
  // FIELDS x y z rgb normal_x normal_y normal_z curvature, all 4 bytes: 32-byte records
  const char* data = bytes.data() + bodyOffset(bytes, "DATA binary\n");
  size_t mismatches = 0;
  for (size_t i = 0; i < 1000; ++i) {
    float f[8];
    uint8_t bgra[4];
    std::memcpy(f, data + 32 * i, 32);
    std::memcpy(bgra, data + 32 * i + 12, 4);
    mismatches += cloud.positions[i] != Vec3(f[0], f[1], f[2]);
    mismatches += cloud.normals[i] != Vec3(f[4], f[5], f[6]);
    mismatches += cloud.curvature[i] != f[7];
    mismatches += cloud.colors[i] != Rgba{bgra[2], bgra[1], bgra[0], 255};
  }
  EXPECT_EQ(mismatches, 0u);
}

}  // namespace
}  // namespace rc
