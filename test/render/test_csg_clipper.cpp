// CsgClipper: surfel classes (4.1.2), Algorithm 4.2 per fragment with insidePatch (Algorithm 4.4) over the
// clipping partners, the unknown cases of Fig. 4.5, many partners, extreme sampling ratios (Fig. 4.7),
// near-coplanar partners and discontinuity surfels (4.3).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "relaxed_connectivity/render/csg/csg_clipper.h"

namespace rc {
namespace {

struct SceneBuilder {
  SurfelCloud cloud;
  std::vector<int> patch, role;
  uint32_t add(const Vec3& c, const Vec3& n, double r, int p, int surfel_role = 0) {
    cloud.positions.push_back(c);
    cloud.normals.push_back(n.normalized());
    cloud.radii.push_back(r);
    patch.push_back(p);
    role.push_back(surfel_role);
    return static_cast<uint32_t>(cloud.size() - 1);
  }
  // Rectangle centred at c, normal n, tangent u; half sizes a (along u) and b; spacing h; radius 0.75 h.
  void grid(const Vec3& c, const Vec3& n, const Vec3& u, double a, double b, double h, int p, int r = 0) {
    const Vec3 v = n.normalized().cross(u);
    const int ku = static_cast<int>(std::round(2 * a / h)), kv = static_cast<int>(std::round(2 * b / h));
    for (int i = 0; i < ku; ++i)
      for (int j = 0; j < kv; ++j)
        add(c + (-a + (i + 0.5) * h) * u + (-b + (j + 0.5) * h) * v, n, 0.75 * h, p, r);
  }
  SurfelCloud build() const {
    SurfelCloud c = cloud;
    Attribute& a = c.attributes.add("patch_id", ScalarType::kInt32, 1, c.size());
    Attribute& r = c.attributes.add("surfel_role", ScalarType::kUInt8, 1, c.size());
    for (size_t i = 0; i < patch.size(); ++i) {
      a.set(i, patch[i]);
      r.set(i, role[i]);
    }
    return c;
  }
};

const std::map<std::string, int> kNames = {{"A", 0}, {"B", 1}, {"C", 2}, {"D", 3}};

Vec3 onDisc(const SurfelCloud& c, uint32_t s, double a, double b) {
  const Vec3 n = c.normals[s];
  const Vec3 u = n.cross(std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).normalized();
  return c.positions[s] + c.radii[s] * (a * u + b * n.cross(u));
}

TEST(CsgClipper, Figure45UnknownPropagation) {
  // (A & B) & C with A = {x < 0}, B = {y < 0}, C = {z < 0}, each a plane of surfels.
  SceneBuilder b;
  b.grid(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), 4, 4, 0.5, 0);  // A: plane x = 0
  b.grid(Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), 4, 4, 0.5, 1);  // B: plane y = 0
  const uint32_t s1 = b.add(Vec3(0, 0, 0), Vec3(0, 0, 1), 0.6, 2);    // meets A and B
  const uint32_t s2 = b.add(Vec3(0, -3, 0), Vec3(0, 0, 1), 0.6, 2);   // meets A only, inside B
  const uint32_t s3 = b.add(Vec3(0, 3, 0), Vec3(0, 0, 1), 0.6, 2);    // meets A only, outside B
  const uint32_t s4 = b.add(Vec3(-2, -2, 0), Vec3(0, 0, 1), 0.6, 2);  // meets nothing, inside A and B
  const uint32_t s5 = b.add(Vec3(2, -2, 0), Vec3(0, 0, 1), 0.6, 2);   // meets nothing, outside A
  const SurfelCloud cloud = b.build();
  CsgClipper clipper(cloud, CsgTree::parse("(A & B) & C", kNames));
  const int A = 0, B = 1;

  // s1: both classifications known.
  EXPECT_EQ(clipper.surfelClass(s1), SurfelClass::kEdge);
  EXPECT_TRUE(clipper.needsClipping(s1));
  EXPECT_EQ(clipper.insidePatch(s1, A, Vec3(-0.2, -0.2, 0)), Tri::kTrue);
  EXPECT_EQ(clipper.insidePatch(s1, B, Vec3(-0.2, 0.2, 0)), Tri::kFalse);
  EXPECT_TRUE(clipper.keepFragment(s1, Vec3(-0.2, -0.2, 0)));
  EXPECT_FALSE(clipper.keepFragment(s1, Vec3(-0.2, 0.2, 0)));
  EXPECT_FALSE(clipper.keepFragment(s1, Vec3(0.2, -0.2, 0)));
  EXPECT_FALSE(clipper.keepFragment(s1, Vec3(0.2, 0.2, 0)));

  // s2: [x inside B] is unknown, so [x inside A & B] = [x inside A] (Fig. 4.5).
  EXPECT_EQ(clipper.surfelClass(s2), SurfelClass::kEdge);
  EXPECT_EQ(clipper.insidePatch(s2, B, Vec3(-0.2, -3, 0)), Tri::kUnknown);
  {
    const CsgTree& t = clipper.tree();
    const CsgTree::Node& father = t.node(t.node(t.leafOf(2)).parent);
    const int sibling = father.left == t.leafOf(2) ? father.right : father.left;  // the node A & B
    EXPECT_EQ(clipper.insideTree(s2, sibling, Vec3(-0.2, -3, 0)), Tri::kTrue);    // true AND unknown
    EXPECT_EQ(clipper.insideTree(s2, sibling, Vec3(0.2, -3, 0)), Tri::kFalse);    // false AND unknown
    EXPECT_EQ(clipper.insideTree(s4, sibling, Vec3(-2, -2, 0)), Tri::kUnknown);   // no partners at all
  }
  int kept_wrong = 0, probes = 0;
  for (int i = -9; i <= 9; ++i)
    for (int j = -9; j <= 9; ++j) {
      const double a = i / 10.0, c = j / 10.0;
      if (a * a + c * c > 0.95 || std::abs(a) < 0.02) continue;
      const Vec3 x = onDisc(cloud, s2, a, c);
      kept_wrong += clipper.keepFragment(s2, x) != (x.x() < 0);
      ++probes;
    }
  EXPECT_GT(probes, 200);
  EXPECT_EQ(kept_wrong, 0);

  // s3 touches A only where A is outside B: outside, never drawn. s4 surface, s5 outside.
  EXPECT_EQ(clipper.surfelClass(s3), SurfelClass::kOutside);
  EXPECT_FALSE(clipper.isVisible(s3));
  EXPECT_EQ(clipper.surfelClass(s4), SurfelClass::kSurface);
  EXPECT_TRUE(clipper.isVisible(s4));
  EXPECT_FALSE(clipper.needsClipping(s4));
  EXPECT_EQ(clipper.surfelClass(s5), SurfelClass::kOutside);
  EXPECT_FALSE(clipper.isVisible(s5));

  // A's surfels: kept where inside B and C; the A surfel at (0, 3.75, 3.75) is far outside both: outside.
  int a_outside = 0, a_surface = 0;
  for (uint32_t i = 0; i < 256; ++i) {
    const Vec3& c = cloud.positions[i];
    if (clipper.surfelClass(i) == SurfelClass::kEdge) continue;
    const bool truth_on = c.y() < 0 && c.z() < 0;
    EXPECT_EQ(clipper.surfelClass(i) == SurfelClass::kSurface, truth_on) << c.transpose();
    (truth_on ? a_surface : a_outside)++;
  }
  EXPECT_GT(a_outside, 100);
  EXPECT_GT(a_surface, 30);
}

TEST(CsgClipper, SingleSurfelClippedByFiftyPartners) {
  // C: one disc of radius 1 in z = 0; A: 50 surfels on the faces of a regular 50-gon prism (apothem 0.8).
  SceneBuilder b;
  const uint32_t big = b.add(Vec3(0, 0, 0), Vec3(0, 0, 1), 1.0, 2);
  const double pi = std::acos(-1.0);
  for (int k = 0; k < 50; ++k) {
    const Vec3 n(std::cos(2 * pi * k / 50), std::sin(2 * pi * k / 50), 0);
    b.add(0.8 * n, n, 0.3, 0);
  }
  const SurfelCloud cloud = b.build();
  CsgClipper clipper(cloud, CsgTree::parse("C & A", kNames));
  ASSERT_EQ(clipper.partners().count(big), 50u);
  EXPECT_TRUE(clipper.needsClipping(big));
  int wrong = 0, kept = 0, probes = 0;
  for (int i = -99; i <= 99; ++i)
    for (int j = -99; j <= 99; ++j) {
      const Vec3 x(i / 100.0, j / 100.0, 0);
      if (x.norm() > 0.99) continue;
      double support = -1;
      for (int k = 0; k < 50; ++k)
        support = std::max(support, x.x() * std::cos(2 * pi * k / 50) + x.y() * std::sin(2 * pi * k / 50));
      if (std::abs(support - 0.8) < 1e-9) continue;
      const bool keep = clipper.keepFragment(big, x);
      wrong += keep != (support < 0.8);
      kept += keep;
      ++probes;
    }
  EXPECT_EQ(wrong, 0);
  EXPECT_NEAR(kept / double(probes), 50 * 0.8 * 0.8 * std::tan(pi / 50) / (pi * 0.99 * 0.99), 0.02);
  // The prism surfels are clipped by the big disc's plane: kept below z = 0.
  EXPECT_TRUE(clipper.keepFragment(1, Vec3(0.8, 0.05, -0.1)));
  EXPECT_FALSE(clipper.keepFragment(1, Vec3(0.8, 0.05, 0.1)));
}

TEST(CsgClipper, SamplingDensitiesDiffering900TimesAcrossAnEdge) {
  // Fig. 4.7: top face z = 1 as ONE surfel, side face x = 1 as 30 x 30 surfels; A & B (the cube's edge).
  SceneBuilder b;
  const uint32_t top = b.add(Vec3(0, 0, 1), Vec3(0, 0, 1), std::sqrt(2.0), 0);
  b.grid(Vec3(1, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), 1, 1, 2.0 / 30, 1);
  ASSERT_EQ(b.cloud.size(), 901u);
  const SurfelCloud cloud = b.build();
  CsgClipper clipper(cloud, CsgTree::parse("A & B", kNames));
  EXPECT_EQ(clipper.partners().count(top), 30u);  // the top row of the dense face
  EXPECT_EQ(clipper.edgeSurfels().size(), 31u);
  int wrong = 0, probes = 0;
  for (int i = 0; i <= 200; ++i)
    for (int j = 0; j <= 100; ++j) {
      const Vec3 x(0.5 + 0.9 * i / 200, -0.9 + 1.8 * j / 100, 1);
      if (std::abs(x.x() - 1) < 1e-9 || (x - cloud.positions[top]).norm() > std::sqrt(2.0)) continue;
      wrong += clipper.keepFragment(top, x) != (x.x() < 1);
      ++probes;
    }
  EXPECT_GT(probes, 15000);
  EXPECT_EQ(wrong, 0);
  int dense_wrong = 0, dense_probes = 0;
  for (uint32_t s = 1; s < cloud.size(); ++s) {
    if (!clipper.needsClipping(s)) {
      EXPECT_EQ(clipper.surfelClass(s), SurfelClass::kSurface);
      continue;
    }
    for (int k = -10; k <= 10; ++k) {
      const Vec3 x = cloud.positions[s] + Vec3(0, 0.01, 0.005 * k);
      if (std::abs(x.z() - 1) < 1e-9) continue;
      dense_wrong += clipper.keepFragment(s, x) != (x.z() < 1);
      ++dense_probes;
    }
  }
  EXPECT_EQ(dense_probes, 30 * 21);
  EXPECT_EQ(dense_wrong, 0);
}

TEST(CsgClipper, NearCoplanarPartnersGiveADecision) {
  for (double angle : {1e-6, 1e-12}) {
    SceneBuilder b;
    b.add(Vec3(0, 0, 0), Vec3(0, 0, 1), 1, 0);
    b.add(Vec3(0, 0, 0), Vec3(std::sin(angle), 0, std::cos(angle)), 1, 1);
    const SurfelCloud cloud = b.build();
    CsgClipper clipper(cloud, CsgTree::parse("A & B", kNames));
    ASSERT_EQ(clipper.partners().count(0), 1u) << angle;
    ASSERT_EQ(clipper.partners().count(1), 1u);
    int wrong = 0;
    for (int i = -9; i <= 9; ++i)
      for (int j = -9; j <= 9; ++j) {
        if (i == 0) continue;
        const double x = i / 10.0, y = j / 10.0;
        wrong += clipper.keepFragment(0, Vec3(x, y, 0)) != (x < 0);  // inside B <=> x sin(angle) < 0
        const Vec3 on_b(x, y, -x * std::tan(angle));
        wrong += clipper.keepFragment(1, on_b) != (x > 0);  // inside A <=> z < 0
      }
    EXPECT_EQ(wrong, 0) << angle;
  }
  // Exactly coplanar partners: a deterministic decision, no exception.
  SceneBuilder b;
  b.add(Vec3(0, 0, 0), Vec3(0, 0, 1), 1, 0);
  b.add(Vec3(0.5, 0, 0), Vec3(0, 0, 1), 1, 1);
  const SurfelCloud cloud = b.build();
  CsgClipper clipper(cloud, CsgTree::parse("A | B", kNames));
  EXPECT_EQ(clipper.partners().count(0), 1u);
  EXPECT_EQ(clipper.keepFragment(0, Vec3(0.1, 0.1, 0)), clipper.keepFragment(0, Vec3(0.1, 0.1, 0)));
}

TEST(CsgClipper, DiscontinuitySurfelsAreInvisibleAndClip) {
  for (int role : {1, 2}) {
    SceneBuilder b;
    b.grid(Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(1, 0, 0), 2, 1, 0.2, 0);          // A: plane z = 0
    b.grid(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), 1, 0.5, 0.2, 3, role);  // D: sheet x = 0, normal +x
    const SurfelCloud cloud = b.build();
    CsgClipper clipper(cloud, CsgTree::parse("A - D", kNames));  // A & !D: keep x > 0
    int visible_d = 0, edge_a = 0, wrong = 0, color_only = 0, outside_a = 0;
    for (uint32_t s = 0; s < cloud.size(); ++s) {
      if (b.patch[s] == 3) {
        visible_d += clipper.isVisible(s);
        continue;
      }
      if (clipper.surfelClass(s) == SurfelClass::kOutside) ++outside_a;
      if (!clipper.needsClipping(s)) continue;
      ++edge_a;
      color_only += clipper.clipsColorOnly(s);
      for (double dx : {-0.1, -0.03, 0.03, 0.1}) {
        const Vec3 x = cloud.positions[s] + Vec3(dx, 0, 0);
        if (std::abs(x.x()) < 1e-9) continue;
        wrong += clipper.keepFragment(s, x) != (x.x() > 0);
      }
    }
    EXPECT_EQ(visible_d, 0) << role;
    EXPECT_EQ(edge_a, 2 * 10)
        << role;  // the two columns next to x = 0, |y| < 1 (the sheet spans y in [-1, 1])
    EXPECT_EQ(wrong, 0) << role;
    EXPECT_EQ(color_only, role == 2 ? edge_a : 0) << role;
    // Geometric discontinuities discard the surfels behind them; texture ones never discard geometry.
    if (role == 1) {
      EXPECT_GT(outside_a, 60);
    } else {
      EXPECT_EQ(outside_a, 0);
    }
  }
}

TEST(CsgClipper, UpdatePerFrameKeepsPartnersAndBothMethodsAgree) {
  SceneBuilder b;
  const Vec3 axes[3] = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  for (int f = 0; f < 6; ++f) {
    const Vec3 n = (f % 2 ? -1.0 : 1.0) * axes[f / 2];
    b.grid(n, n, axes[(f / 2 + 1) % 3], 1, 1, 0.4, f);
  }
  const SurfelCloud cloud = b.build();
  const CsgTree tree = CsgTree::parse("((0 & 1) & (2 & 3)) & (4 & 5)");
  CsgClipperOptions spatial_options, buffer_options;
  spatial_options.method = PartnerMethod::kSpatialIndex;
  buffer_options.method = PartnerMethod::kClipBuffer;
  CsgClipper spatial(cloud, tree, spatial_options), buffer(cloud, tree, buffer_options);
  const ClipPartners initial = spatial.partners();
  EXPECT_EQ(spatial.edgeSurfels().size(), 96u);
  Camera cam = Camera::perspective(320, 240, 1.0);
  cam.lookAt(Vec3(3, -4, 2), Vec3(0, 0, 0));
  spatial.update(cam);
  buffer.update(cam);
  EXPECT_TRUE(spatial.partners() == initial);
  EXPECT_TRUE(buffer.partners() == initial);
  buffer.prepare();
  EXPECT_TRUE(buffer.partners() == initial);
  // Cube = intersection of 6 half-spaces: every visible edge fragment inside the cube is kept.
  int wrong = 0;
  for (uint32_t s : spatial.edgeSurfels())
    for (double a : {-0.9, -0.4, 0.0, 0.4, 0.9})
      for (double c : {-0.9, 0.0, 0.9}) {
        const Vec3 x = onDisc(cloud, s, a, c);
        if ((x.cwiseAbs().maxCoeff() - 1) > -1e-9 && (x.cwiseAbs().maxCoeff() - 1) < 1e-9) continue;
        const bool truth = x.cwiseAbs().maxCoeff() < 1 + 1e-12;
        wrong += spatial.keepFragment(s, x) != truth;
        wrong += buffer.keepFragment(s, x) != spatial.keepFragment(s, x);
      }
  EXPECT_EQ(wrong, 0);
}

TEST(CsgClipper, SurfelsOfComplementedPatchesFlipTheirShadingNormal) {
  SceneBuilder b;
  b.grid(Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(1, 0, 0), 1, 1, 0.2, 0);  // A
  b.grid(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), 1, 1, 0.2, 1);  // B
  b.grid(Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(1, 0, 0), 1, 1, 0.2, 2);  // C
  const SurfelCloud cloud = b.build();
  // A - (B | !C) = A & !B & C: B is complemented, C twice complemented (not), A not.
  const CsgClipper clipper(cloud, CsgTree::parse("A - (B | !C)", kNames));
  int flipped[3] = {0, 0, 0}, counts[3] = {0, 0, 0};
  for (uint32_t s = 0; s < cloud.size(); ++s) {
    ++counts[b.patch[s]];
    flipped[b.patch[s]] += clipper.flipsNormal(s);
    EXPECT_EQ(clipper.flipsNormal(s), clipper.isInverted(s));
  }
  EXPECT_EQ(flipped[0], 0);
  EXPECT_EQ(flipped[1], counts[1]);
  EXPECT_EQ(flipped[2], 0);
  EXPECT_GT(counts[1], 0);
  // Flipping is for shading only: the clipper's geometry keeps the stored normals.
  for (uint32_t s = 0; s < cloud.size(); ++s)
    if (b.patch[s] == 1) {
      EXPECT_EQ(clipper.discs().normals[s], Vec3(1, 0, 0));
    }
}

TEST(CsgClipper, BadInputIsRejected) {
  SceneBuilder b;
  b.add(Vec3(0, 0, 0), Vec3(0, 0, 1), 1, 5);
  const SurfelCloud cloud = b.build();
  EXPECT_THROW(CsgClipper(cloud, CsgTree::parse("A & B", kNames)), std::invalid_argument);  // patch 5 absent
  SurfelCloud no_normals = cloud;
  no_normals.normals.clear();
  EXPECT_THROW(CsgClipper(no_normals, CsgTree::parse("5")), std::invalid_argument);
  EXPECT_NO_THROW(CsgClipper(cloud, CsgTree::parse("!5")));
}

}  // namespace
}  // namespace rc
