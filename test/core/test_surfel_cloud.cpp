#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {
namespace {

SurfelCloud makeCloud(size_t n) {
  SurfelCloud c;
  for (size_t i = 0; i < n; ++i) {
    c.positions.emplace_back(double(i), 2.0 * i, -1.0 * i);
    c.normals.emplace_back(0, 0, 1);
    c.radii.push_back(0.1 * (i + 1));
  }
  c.attributes.add("patch_id", ScalarType::kUInt16, 1, n);
  for (size_t i = 0; i < n; ++i) c.attributes.find("patch_id")->set(i, double(10 + i));
  return c;
}

TEST(Attribute, StoresEveryScalarTypeExactly) {
  const ScalarType types[] = {ScalarType::kInt8,    ScalarType::kUInt8,  ScalarType::kInt16,
                              ScalarType::kUInt16,  ScalarType::kInt32,  ScalarType::kUInt32,
                              ScalarType::kFloat32, ScalarType::kFloat64};
  const size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  for (int t = 0; t < 8; ++t) {
    AttributeSet set;
    Attribute& a = set.add("a", types[t], 3, 5);
    EXPECT_EQ(a.stride(), 3 * sizes[t]);
    EXPECT_EQ(a.size(), 5u);
    a.set(4, 100.0, 2);
    EXPECT_EQ(a.get(4, 2), 100.0) << scalarName(types[t]);
    EXPECT_EQ(a.get(4, 1), 0.0);
  }
  AttributeSet set;
  set.add("x", ScalarType::kFloat64, 1, 1).set(0, 0.1);
  EXPECT_EQ(set.find("x")->get(0), 0.1);  // float64 is bit exact
}

TEST(Attribute, DuplicateAndZeroCountAreRejected) {
  AttributeSet set;
  set.add("a", ScalarType::kFloat32, 1, 2);
  EXPECT_THROW(set.add("a", ScalarType::kFloat32, 1, 2), std::invalid_argument);
  EXPECT_THROW(set.add("b", ScalarType::kFloat32, 0, 2), std::invalid_argument);
  set.remove("a");
  EXPECT_FALSE(set.has("a"));
}

TEST(SurfelCloud, SelectKeepsChannelsAligned) {
  SurfelCloud c = makeCloud(6);
  c.select({5, 1, 3});
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.positions[0].x(), 5.0);
  EXPECT_DOUBLE_EQ(c.radii[1], 0.2);
  EXPECT_EQ(c.attributes.find("patch_id")->get(2), 13.0);
  EXPECT_NO_THROW(c.validate());
}

TEST(SurfelCloud, AppendConcatenatesAndDropsOneSidedChannels) {
  SurfelCloud a = makeCloud(3), b = makeCloud(2);
  b.colors.assign(2, Rgba{1, 2, 3, 4});
  a.append(b);
  EXPECT_EQ(a.size(), 5u);
  EXPECT_EQ(a.radii.size(), 5u);
  EXPECT_TRUE(a.colors.empty());  // present in only one operand
  EXPECT_EQ(a.attributes.find("patch_id")->get(4), 11.0);
  EXPECT_NO_THROW(a.validate());

  SurfelCloud empty;
  empty.append(b);
  EXPECT_EQ(empty.colors.size(), 2u);
}

TEST(SurfelCloud, RemoveNonFiniteCountsAndUnorganises) {
  SurfelCloud c = makeCloud(4);
  c.width = 2;
  c.height = 2;
  EXPECT_TRUE(c.isOrganized());
  c.positions[1].x() = std::numeric_limits<double>::quiet_NaN();
  c.normals[2].z() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(c.removeNonFinite(), 2u);
  EXPECT_EQ(c.size(), 2u);
  EXPECT_FALSE(c.isOrganized());
  EXPECT_EQ(c.attributes.find("patch_id")->get(1), 13.0);
}

TEST(SurfelCloud, ValidateNamesTheBadChannel) {
  SurfelCloud c = makeCloud(3);
  c.radii.pop_back();
  try {
    c.validate();
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("radii"), std::string::npos) << e.what();
  }
}

TEST(SurfelCloud, Bounds) {
  SurfelCloud c = makeCloud(4);
  Vec3 lo, hi;
  ASSERT_TRUE(c.bounds(&lo, &hi));
  EXPECT_EQ(lo, Vec3(0, 0, -3));
  EXPECT_EQ(hi, Vec3(3, 6, 0));
  EXPECT_FALSE(SurfelCloud().bounds(&lo, &hi));
}

}  // namespace
}  // namespace rc
