// Shared helpers of the I/O tests: temporary paths, an attribute-rich surfel cloud and exact comparisons.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/core/triangle_mesh.h"

namespace rc {
namespace test {

/// A fresh path in a per-process temporary folder.
inline std::string tempPath(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("rc_io_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

/// Removes the temporary folder when the test program ends.
class TempFolderCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(std::filesystem::path(tempPath("x")).parent_path(), ignored);
  }
};
inline ::testing::Environment* const kTempFolderCleanup =
    ::testing::AddGlobalTestEnvironment(new TempFolderCleanup);

inline void writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

inline std::string readFirstLine(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::getline(in, line);
  return line;
}

inline std::string sharedData(const std::string& name) {
  return std::string(RC_SHARED_DATA_DIR) + "/" + name;
}

/// Skips visibly when the shared test data folder is missing (the message test/shared_data.h uses).
#define RC_REQUIRE_SHARED_DATA()                    \
  if (!std::filesystem::exists(RC_SHARED_DATA_DIR)) \
  GTEST_SKIP() << "needs ../shared/data: the folder " << RC_SHARED_DATA_DIR << " does not exist"

/// Values that float32 represents exactly, so float32 files round-trip them bit-exactly.
inline double floatValue(std::mt19937& rng, double lo, double hi) {
  return static_cast<float>(std::uniform_real_distribution<double>(lo, hi)(rng));
}

/// Elliptical surfels with every channel and attributes of several types (scalar and count > 1).
inline SurfelCloud makeRichCloud(size_t n, uint32_t seed = 7) {
  std::mt19937 rng(seed);
  SurfelCloud c;
  for (size_t i = 0; i < n; ++i) {
    c.positions.emplace_back(floatValue(rng, -5, 5), floatValue(rng, -5, 5), floatValue(rng, -5, 5));
    c.normals.emplace_back(floatValue(rng, -1, 1), floatValue(rng, -1, 1), floatValue(rng, -1, 1));
    c.radii.push_back(floatValue(rng, 0.01, 0.1));
    c.axes1.emplace_back(floatValue(rng, -1, 1), floatValue(rng, -1, 1), 0.0);
    c.axes2.emplace_back(0.0, floatValue(rng, -1, 1), floatValue(rng, -1, 1));
    c.colors.push_back(Rgba{uint8_t(rng()), uint8_t(rng()), uint8_t(rng()), uint8_t(rng())});
    c.confidence.push_back(static_cast<float>(floatValue(rng, 0, 1)));
    c.curvature.push_back(static_cast<float>(floatValue(rng, 0, 0.3)));
  }
  Attribute& id = c.attributes.add("patch_id", ScalarType::kUInt32, 1, n);
  Attribute& weight = c.attributes.add("weight", ScalarType::kFloat64, 1, n);
  Attribute& flags = c.attributes.add("flags", ScalarType::kInt8, 3, n);
  Attribute& descriptor = c.attributes.add("descriptor", ScalarType::kFloat32, 5, n);
  Attribute& level = c.attributes.add("level", ScalarType::kInt16, 1, n);
  for (auto* a : {&id, &weight, &flags, &descriptor, &level})
    for (auto& byte : a->bytes) byte = static_cast<uint8_t>(rng());
  // random bytes may form NaN payloads for the float columns; keep those finite so ascii also round-trips
  for (size_t i = 0; i < n; ++i) {
    weight.set(i, std::uniform_real_distribution<double>(-1e6, 1e6)(rng));
    for (uint32_t k = 0; k < 5; ++k) descriptor.set(i, floatValue(rng, -1e3, 1e3), k);
  }
  return c;
}

/// Bitwise equality of doubles (so NaN == NaN).
inline bool sameBits(double a, double b) {
  return std::memcmp(&a, &b, sizeof(double)) == 0;
}
inline bool sameVec(const Vec3& a, const Vec3& b) {
  return sameBits(a.x(), b.x()) && sameBits(a.y(), b.y()) && sameBits(a.z(), b.z());
}

inline void expectVecsEqual(const std::vector<Vec3>& a, const std::vector<Vec3>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  size_t differing = 0;
  for (size_t i = 0; i < a.size(); ++i) differing += !sameVec(a[i], b[i]);
  EXPECT_EQ(differing, 0u) << what;
}

/// Every channel and attribute equal bit for bit.
inline void expectCloudsEqual(const SurfelCloud& expected, const SurfelCloud& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  expectVecsEqual(expected.positions, actual.positions, "positions");
  expectVecsEqual(expected.normals, actual.normals, "normals");
  expectVecsEqual(expected.axes1, actual.axes1, "axes1");
  expectVecsEqual(expected.axes2, actual.axes2, "axes2");
  EXPECT_EQ(expected.radii, actual.radii);
  EXPECT_EQ(expected.colors, actual.colors);
  EXPECT_EQ(expected.confidence, actual.confidence);
  EXPECT_EQ(expected.curvature, actual.curvature);
  ASSERT_EQ(expected.attributes.columns().size(), actual.attributes.columns().size());
  for (size_t c = 0; c < expected.attributes.columns().size(); ++c) {
    const Attribute& e = expected.attributes.columns()[c];
    const Attribute* a = actual.attributes.find(e.name);
    ASSERT_NE(a, nullptr) << "attribute " << e.name << " lost";
    EXPECT_EQ(a->type, e.type) << e.name;
    EXPECT_EQ(a->count, e.count) << e.name;
    EXPECT_TRUE(a->bytes == e.bytes) << "attribute " << e.name << " differs";
  }
}

/// A closed octahedron: 6 vertices, 8 consistently oriented triangles.
inline TriangleMesh makeOctahedron() {
  TriangleMesh m;
  m.vertices.positions = {Vec3(1, 0, 0),  Vec3(-1, 0, 0), Vec3(0, 1, 0),
                          Vec3(0, -1, 0), Vec3(0, 0, 1),  Vec3(0, 0, -1)};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

}  // namespace test
}  // namespace rc
