#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/render/csg/patch_clouds.h"

namespace rc {
namespace {

SurfelCloud discs(size_t n, double radius) {
  SurfelCloud c;
  for (size_t i = 0; i < n; ++i) {
    c.positions.push_back(Vec3(double(i), 0, 0));
    c.normals.push_back(Vec3(0, 0, 2));  // not unit: the merge normalises
    c.radii.push_back(radius);
  }
  return c;
}

SurfelCloud ellipses(size_t n) {
  SurfelCloud c;
  for (size_t i = 0; i < n; ++i) {
    c.positions.push_back(Vec3(0, double(i), 0));
    c.normals.push_back(Vec3::UnitZ());
    c.axes1.push_back(Vec3(0.3, 0, 0));
    c.axes2.push_back(Vec3(0, 0.1, 0));
  }
  return c;
}

void addIntColumn(SurfelCloud& c, const char* name, double value) {
  Attribute& a = c.attributes.add(name, ScalarType::kInt32, 1, c.size());
  for (size_t i = 0; i < c.size(); ++i) a.set(i, value);
}

std::string messageOf(const SurfelCloud& c, bool require_patch_id) {
  try {
    checkRenderableCloud(c, require_patch_id);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(PatchClouds, CheckNamesTheProblemAndCountsTheBadSurfels) {
  EXPECT_EQ(messageOf(SurfelCloud(), false), "empty cloud (0 surfels)");
  SurfelCloud no_normals = discs(3, 0.1);
  no_normals.normals.clear();
  EXPECT_EQ(messageOf(no_normals, false), "no normals (fields normal_x, normal_y, normal_z)");
  SurfelCloud bad = discs(5, 0.1);
  bad.positions[1].x() = NAN;
  bad.positions[3].y() = INFINITY;
  EXPECT_EQ(messageOf(bad, false), "2 of 5 surfels have non-finite positions");
  SurfelCloud flat = discs(4, 0.1);
  flat.radii[2] = 0.0;
  EXPECT_EQ(messageOf(flat, false), "1 of 4 surfels have non-positive or non-finite radii");
  SurfelCloud roles = discs(4, 0.1);
  addIntColumn(roles, kSurfelRoleAttribute, 3);
  EXPECT_EQ(messageOf(roles, false),
            "4 of 4 surfels have a surfel_role other than 0 (surface), 1 or 2 (discontinuity)");
  SurfelCloud ok = discs(4, 0.1);
  EXPECT_EQ(messageOf(ok, false), "");
  EXPECT_EQ(messageOf(ok, true), "no patch_id field (required on this topic)");
  addIntColumn(ok, kPatchIdAttribute, -1);
  EXPECT_EQ(messageOf(ok, true), "4 of 4 surfels have a patch_id that is not an integer >= 0");
}

TEST(PatchClouds, MergeOverridesPatchIdsKeepsRolesAndNormalises) {
  SurfelCloud a = discs(3, 0.2), b = discs(2, 0.5);
  addIntColumn(b, kPatchIdAttribute, 7);
  addIntColumn(b, kSurfelRoleAttribute, 1);
  b.colors.assign(2, Rgba{10, 20, 30, 255});
  const SurfelCloud merged = mergePatchClouds({{&a, 4}, {&b, -1}}, "world", Rgba{1, 2, 3, 4});
  ASSERT_EQ(merged.size(), 5u);
  EXPECT_EQ(merged.frame_id, "world");
  EXPECT_FALSE(merged.hasAxes());
  const Attribute* ids = merged.attributes.find(kPatchIdAttribute);
  const Attribute* roles = merged.attributes.find(kSurfelRoleAttribute);
  ASSERT_TRUE(ids && roles);
  const double expected_ids[5] = {4, 4, 4, 7, 7}, expected_roles[5] = {0, 0, 0, 1, 1};
  const double expected_radii[5] = {0.2, 0.2, 0.2, 0.5, 0.5};
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(ids->get(i), expected_ids[i]);
    EXPECT_EQ(roles->get(i), expected_roles[i]);
    EXPECT_EQ(merged.radii[i], expected_radii[i]);
    EXPECT_DOUBLE_EQ(merged.normals[i].norm(), 1.0);
  }
  EXPECT_EQ(merged.colors[0][0], 1);   // default colour where an input has none
  EXPECT_EQ(merged.colors[4][0], 10);  // the input's own colour
  EXPECT_EQ(patchIds(merged), (std::vector<int>{4, 7}));
  EXPECT_TRUE(patchIds(a).empty());
}

TEST(PatchClouds, MergeOfDiscsAndEllipsesGivesEnclosingRadii) {
  SurfelCloud d = discs(2, 0.05), e = ellipses(3);
  const SurfelCloud merged = mergePatchClouds({{&d, 0}, {&e, 1}}, "world");
  ASSERT_EQ(merged.size(), 5u);
  EXPECT_FALSE(merged.hasAxes());  // not every input has axes
  EXPECT_EQ(merged.radii[0], 0.05);
  EXPECT_EQ(merged.radii[1], 0.05);
  for (size_t i = 2; i < 5; ++i) EXPECT_DOUBLE_EQ(merged.radii[i], 0.3);  // max(|t1|, |t2|)
  const SurfelCloud both = mergePatchClouds({{&e, 1}, {&e, 2}}, "world");
  EXPECT_TRUE(both.hasAxes());
  EXPECT_DOUBLE_EQ(both.radii[0], 0.3);
  SurfelCloud broken = discs(2, 0.1);
  broken.radii[1] = NAN;
  EXPECT_THROW(mergePatchClouds({{&d, 0}, {&broken, 1}}, "world"), std::invalid_argument);
}

}  // namespace
}  // namespace rc
