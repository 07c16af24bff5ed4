// PatchCloudSet: merging per-source patch clouds, keeping the patches a CSG tree names, and the clipper on
// the merged cloud (thesis 4.1-4.3).
#include <gtest/gtest.h>

#include <stdexcept>

#include "relaxed_connectivity/core/surfel_attributes.h"
#include "relaxed_connectivity/render/csg/patch_cloud_set.h"

namespace rc {
namespace {

// n discs on a line at height z, normal +z.
SurfelCloud row(size_t n, double z) {
  SurfelCloud c;
  for (size_t i = 0; i < n; ++i) {
    c.positions.push_back(Vec3(0.1 * double(i), 0, z));
    c.normals.push_back(Vec3::UnitZ());
    c.radii.push_back(0.08);
  }
  return c;
}

TEST(PatchCloudSet, WithoutTreeMergesEverythingAndHasNoClipper) {
  const SurfelCloud a = row(5, 0), b = row(3, 1);
  const PatchCloudSet set({{&a, 0}, {&b, 1}}, std::nullopt, "world");
  EXPECT_EQ(set.cloud().size(), 8u);
  EXPECT_EQ(set.clipper(), nullptr);
  EXPECT_EQ(set.droppedSurfels(), 0u);
  EXPECT_EQ(patchIds(set.cloud()), (std::vector<int>{0, 1}));
  EXPECT_EQ(set.cloud().frame_id, "world");
}

TEST(PatchCloudSet, TreeKeepsOnlyItsPatchesAndBuildsTheClipperOnThem) {
  const SurfelCloud a = row(5, 0), b = row(3, 1), c = row(4, 2);
  const PatchCloudSet set({{&a, 0}, {&b, 1}, {&c, 2}}, CsgTree::parse("0 - 2"), "world");
  EXPECT_EQ(set.cloud().size(), 9u);  // patch 1 is not in the tree
  EXPECT_EQ(set.droppedSurfels(), 3u);
  EXPECT_EQ(patchIds(set.cloud()), (std::vector<int>{0, 2}));
  ASSERT_NE(set.clipper(), nullptr);
  const Attribute* ids = set.cloud().attributes.find(kPatchIdAttribute);
  ASSERT_NE(ids, nullptr);
  for (size_t i = 0; i < set.cloud().size(); ++i) EXPECT_NE(int(ids->get(i)), 1);
}

TEST(PatchCloudSet, TreeNamingOnlyMissingPatchesLeavesAnEmptyCloud) {
  const SurfelCloud a = row(5, 0);
  const PatchCloudSet set({{&a, 0}}, CsgTree::parse("3 | 4"), "world");
  EXPECT_TRUE(set.cloud().empty());
  EXPECT_EQ(set.droppedSurfels(), 5u);
  EXPECT_EQ(set.clipper(), nullptr);
}

TEST(PatchCloudSet, NoInputsGiveAnEmptySet) {
  const PatchCloudSet set({}, CsgTree::parse("0 & 1"), "world");
  EXPECT_TRUE(set.cloud().empty());
  EXPECT_EQ(set.clipper(), nullptr);
}

TEST(PatchCloudSet, BadInputThrowsNamingTheProblem) {
  SurfelCloud a = row(5, 0);
  a.radii[2] = -1.0;
  try {
    const PatchCloudSet set({{&a, 0}}, std::nullopt, "world");
    FAIL() << "a negative radius was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("radi"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rc
