// Surface animation of thin shells (thesis 7.4): rigid motions are reproduced exactly, smooth deformations
// with an error small against the node spacing, and cracks give paired discontinuity surfels that follow
// their own piece.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "relaxed_connectivity/shell/shell_crack.h"
#include "relaxed_connectivity/shell/shell_skinning.h"
#include "shell_test_support.h"

namespace rc {
namespace {

using shell_test::bendOntoCylinder;
using shell_test::sheetCloud;
using shell_test::sphereCloud;

// Elliptical tangent axes (|t1| = 0.6 r, |t2| = 0.4 r) from the normals.
void addAxes(SurfelCloud& cloud, double r) {
  cloud.axes1.clear(), cloud.axes2.clear();
  for (const Vec3& n : cloud.normals) {
    const Vec3 u = n.cross(std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).normalized();
    cloud.axes1.push_back(0.6 * r * u);
    cloud.axes2.push_back(0.4 * r * n.cross(u));
  }
}

void checkRigid(const SurfelCloud& cloud, double h, const char* what) {
  ShellNodeOptions options;
  options.spacing = h;
  const ShellNodes nodes = selectShellNodes(cloud, options);
  const ShellSkinning skin(cloud, nodes);
  const Eigen::Isometry3d motion =
      Eigen::Translation3d(0.3, -1.2, 2.5) * Eigen::AngleAxisd(2.4, Vec3(1.0, 2.0, -0.5).normalized());
  std::vector<Vec3> x;
  for (const Vec3& p : nodes.rest_positions) x.push_back(motion * p);
  SurfelCloud out = cloud;
  skin.deform(nodes, x, &out);
  double pos = 0.0, nrm = 0.0, unit = 0.0, axes = 0.0;
  for (size_t s = 0; s < cloud.size(); ++s) {
    pos = std::max(pos, (out.positions[s] - motion * cloud.positions[s]).norm());
    nrm = std::max(nrm, (out.normals[s] - motion.linear() * cloud.normals[s]).norm());
    unit = std::max(unit, std::abs(out.normals[s].norm() - 1.0));
    axes = std::max(axes, (out.axes1[s] - motion.linear() * cloud.axes1[s]).norm());
    axes = std::max(axes, (out.axes2[s] - motion.linear() * cloud.axes2[s]).norm());
  }
  std::printf(
      "%s: %zu surfels on %zu nodes, rigid motion errors: position %.2e, normal %.2e, |n|-1 %.2e, "
      "axes %.2e\n",
      what, cloud.size(), nodes.size(), pos, nrm, unit, axes);
  EXPECT_LT(pos, 1e-12);
  EXPECT_LT(nrm, 1e-12);
  EXPECT_LT(unit, 1e-12);
  EXPECT_LT(axes, 1e-12);
}

TEST(ShellSkinning, RigidMotionMovesSurfelsRigidly) {
  SurfelCloud sheet = sheetCloud(1.0, 60);
  addAxes(sheet, 0.01);
  checkRigid(sheet, 0.1, "sheet");
  SurfelCloud sphere = sphereCloud(1.0, 6000);
  addAxes(sphere, 0.02);
  checkRigid(sphere, 0.25, "sphere");
}

// Bends a sheet onto a cylinder (radius 0.5) through its nodes and compares with the exact bend of every
// surfel: max / rms position error and max normal angle, for interior surfels.
void bendError(double h, double* max_error, double* rms_error, double* normal_error) {
  const double r = 0.5;
  const SurfelCloud cloud = sheetCloud(1.0, 120);
  ShellNodeOptions options;
  options.spacing = h;
  const ShellNodes nodes = selectShellNodes(cloud, options);
  const ShellSkinning skin(cloud, nodes);
  SurfelCloud out = cloud;
  skin.deform(nodes, bendOntoCylinder(nodes.rest_positions, r), &out);
  const std::vector<Vec3> exact = bendOntoCylinder(cloud.positions, r);
  *max_error = *rms_error = *normal_error = 0.0;
  size_t count = 0;
  for (size_t s = 0; s < cloud.size(); ++s) {
    const Vec3& p = cloud.positions[s];
    if (std::abs(p.x()) > 0.5 - 1.5 * h || std::abs(p.y()) > 0.5 - 1.5 * h) continue;
    const double e = (out.positions[s] - exact[s]).norm();
    const Vec3 n(-std::sin(p.x() / r), 0.0, std::cos(p.x() / r));  // cylinder normal (rest normal +z)
    *max_error = std::max(*max_error, e);
    *rms_error += e * e;
    *normal_error = std::max(*normal_error, std::acos(std::min(1.0, out.normals[s].dot(n))));
    EXPECT_NEAR(out.normals[s].norm(), 1.0, 1e-12);
    ++count;
  }
  *rms_error = std::sqrt(*rms_error / count);
}

TEST(ShellSkinning, SmoothBendErrorIsSmallAgainstTheNodeSpacing) {
  double max1, rms1, n1, max2, rms2, n2;
  bendError(0.1, &max1, &rms1, &n1);
  bendError(0.05, &max2, &rms2, &n2);
  std::printf(
      "cylinder bend r=0.5: h=0.10 max %.2e (%.3f h) rms %.2e normal %.2f deg; h=0.05 max %.2e "
      "(%.3f h) rms %.2e normal %.2f deg; rms rate %.2f\n",
      max1, max1 / 0.1, rms1, n1 * 180 / M_PI, max2, max2 / 0.05, rms2, n2 * 180 / M_PI,
      std::log2(rms1 / rms2));
  EXPECT_LT(max1, 0.1 * 0.1);
  EXPECT_LT(max2, 0.1 * 0.05);
  EXPECT_LT(rms2, rms1);
  EXPECT_LT(n2, 5.0 * M_PI / 180);
}

TEST(ShellSkinning, CracksGivePairedDiscontinuitySurfelsThatFollowTheirPiece) {
  const double h = 0.1, gap = 0.2;
  const SurfelCloud cloud = sheetCloud(1.0, 60);
  ShellNodeOptions options;
  options.spacing = h;
  ShellNodes nodes = selectShellNodes(cloud, options);
  // A straight cut along x = 0 from discs (normal +x) every half spacing.
  std::vector<ShellCrack> cracks;
  for (double y = -0.5; y <= 0.5; y += 0.5 * h) {
    ShellCrack c;
    c.center = Vec3(0.0, y, 0.0);
    c.normal = Vec3::UnitX();
    c.radius = h;
    cracks.push_back(c);
  }
  recomputeVisibleNeighborhoods(nodes, cracks, 8);
  for (size_t i = 0; i < nodes.size(); ++i) {  // no neighbourhood reaches across the cut
    for (size_t m = 0; m < nodes.neighborCount(i); ++m) {
      ASSERT_GT(nodes.rest_positions[i].x() * nodes.rest_positions[nodes.neighborsOf(i)[m]].x(), 0.0);
    }
  }
  const SurfelCloud discs = crackDiscontinuitySurfels(cracks);
  ASSERT_EQ(discs.size(), 2 * cracks.size());
  SurfelCloud all = cloud;
  all.attributes.add("surfel_role", ScalarType::kInt32, 1, cloud.size());
  all.attributes.add("patch_id", ScalarType::kInt32, 1, cloud.size());
  all.attributes.add("crack_side", ScalarType::kInt32, 1, cloud.size());
  all.append(discs);
  ASSERT_TRUE(all.hasNormals());
  const ShellSkinning skin(all, nodes, cracks);
  std::vector<Vec3> x = nodes.rest_positions;  // pull the halves apart
  for (Vec3& p : x) p.x() += p.x() > 0 ? 0.5 * gap : -0.5 * gap;
  SurfelCloud out = all;
  skin.deform(nodes, x, &out);
  double surface = 0.0, pair = 0.0;
  for (size_t s = 0; s < cloud.size(); ++s) {  // every surfel moves with its own half
    const double shift = cloud.positions[s].x() > 0 ? 0.5 * gap : -0.5 * gap;
    surface = std::max(surface, (out.positions[s] - cloud.positions[s] - Vec3(shift, 0, 0)).norm());
  }
  const Attribute* role = out.attributes.find("surfel_role");
  size_t disc_count = 0;
  for (size_t c = 0; c < cracks.size(); ++c) {
    const size_t a = cloud.size() + 2 * c, b = a + 1;
    EXPECT_EQ(role->get(a), 1.0);
    EXPECT_EQ(role->get(b), 1.0);
    EXPECT_NEAR(out.normals[a].dot(out.normals[b]), -1.0, 1e-12);
    // The +x surfel bounds the left half (material behind its normal) and moves left.
    const double sa = out.normals[a].x() > 0 ? -0.5 * gap : 0.5 * gap;
    pair = std::max(pair, (out.positions[a] - cracks[c].center - Vec3(sa, 0, 0)).norm());
    pair = std::max(pair, (out.positions[b] - cracks[c].center - Vec3(-sa, 0, 0)).norm());
    pair = std::max(pair, std::abs((out.positions[a] - out.positions[b]).norm() - gap));
    disc_count += 2;
  }
  std::printf("crack of %zu discs: %zu discontinuity surfels; max error surface %.2e, pairs %.2e\n",
              cracks.size(), disc_count, surface, pair);
  EXPECT_LT(surface, 1e-12);
  EXPECT_LT(pair, 1e-12);
}

// A growing cut: binding against the first cracks and re-binding locally after more equals a full binding
// against all of them, for the dense surfels and for appended discontinuity surfels alike.
TEST(ShellSkinning, LocalRebindAfterNewCracksEqualsFullRebind) {
  const double h = 0.1;
  const SurfelCloud cloud = sheetCloud(1.0, 80);
  ShellNodeOptions options;
  options.spacing = h;
  ShellNodes nodes = selectShellNodes(cloud, options);
  std::vector<ShellCrack> cracks;
  for (double y = -0.5; y <= 0.1; y += 0.5 * h) {  // grows from the bottom edge up to y = 0.1
    ShellCrack c;
    c.center = Vec3(0.013, y, 0.0);
    c.normal = Vec3::UnitX();
    c.radius = h;
    cracks.push_back(c);
  }
  const size_t first = cracks.size() / 2;
  const std::vector<ShellCrack> early(cracks.begin(), cracks.begin() + first);
  recomputeVisibleNeighborhoods(nodes, cracks, 8);
  std::vector<Vec3> x = shell_test::bendOntoCylinder(nodes.rest_positions, 0.8);
  for (Vec3& p : x) p.x() += p.x() > 0.013 ? 0.05 : -0.05;
  auto discs = [&](const std::vector<ShellCrack>& list) {
    SurfelCloud d = crackDiscontinuitySurfels(list);
    for (size_t k = 0; k < d.size(); ++k) d.positions[k] -= 0.25 * list[k / 2].radius * d.normals[k];
    return d;
  };
  for (int kind = 0; kind < 2; ++kind) {  // 0: dense surfels, 1: discontinuity surfels (appended)
    const SurfelCloud before = kind == 0 ? cloud : discs(early);
    const SurfelCloud after = kind == 0 ? cloud : discs(cracks);
    ShellSkinning local(before, nodes, early);
    const size_t kept = local.rebind(after, nodes, cracks);
    const ShellSkinning full(after, nodes, cracks);
    ASSERT_EQ(local.size(), after.size());
    EXPECT_EQ(kept, 0u);
    EXPECT_EQ(local.boundCracks(), cracks.size());
    SurfelCloud a = after, b = after;
    local.deform(nodes, x, &a);
    full.deform(nodes, x, &b);
    size_t differ = 0;
    for (size_t s = 0; s < after.size(); ++s) {
      differ += a.positions[s] != b.positions[s] || a.normals[s] != b.normals[s] ||
                a.axes1.size() != b.axes1.size();
    }
    std::printf("%s: %zu surfels, %zu re-bound after %zu new cracks, %zu differ from a full binding\n",
                kind == 0 ? "dense" : "discontinuity", after.size(), local.lastRebound(),
                cracks.size() - first, differ);
    EXPECT_EQ(differ, 0u);
    EXPECT_GT(local.lastRebound(), 0u);
    if (kind == 0) {
      EXPECT_LT(local.lastRebound(), after.size() / 5);  // local: near the new cracks only
    } else {
      EXPECT_GE(local.lastRebound(), 2 * (cracks.size() - first));  // the appended pairs at least
    }
  }
  // The re-binding must extend what was bound.
  ShellSkinning skin(cloud, nodes, cracks);
  EXPECT_THROW(skin.rebind(cloud, nodes, early), std::invalid_argument);
}

TEST(ShellSkinning, RejectsBadInput) {
  const SurfelCloud cloud = sheetCloud(1.0, 30);
  ShellNodeOptions options;
  options.spacing = 0.2;
  const ShellNodes nodes = selectShellNodes(cloud, options);
  SurfelCloud no_normals = cloud;
  no_normals.normals.clear();
  EXPECT_THROW(ShellSkinning(no_normals, nodes), std::invalid_argument);
  ShellSkinningOptions bad;
  bad.node_count = 1;
  EXPECT_THROW(ShellSkinning(cloud, nodes, {}, bad), std::invalid_argument);
  const ShellSkinning skin(cloud, nodes);
  SurfelCloud out = cloud;
  EXPECT_THROW(skin.deform(nodes, std::vector<Vec3>(3), &out), std::invalid_argument);
}

}  // namespace
}  // namespace rc
