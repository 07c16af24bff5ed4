// Clipping partners (4.2.1): the exact disc-disc test, and the clip buffer (Algorithm 4.1) and the spatial
// index returning identical partner sets, equal to a brute-force reference.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "relaxed_connectivity/render/csg/clip_partners.h"
#include "relaxed_connectivity/render/splat/camera.h"

namespace rc {
namespace {

struct SceneBuilder {
  SurfelCloud cloud;
  std::vector<int> patch;
  void add(const Vec3& c, const Vec3& n, double r, int p) {
    cloud.positions.push_back(c);
    cloud.normals.push_back(n.normalized());
    cloud.radii.push_back(r);
    patch.push_back(p);
  }
  // Square face centred at c with normal n, tangent u, half size a, k x k samples.
  void face(const Vec3& c, const Vec3& n, const Vec3& u, double a, int k, int p) {
    const Vec3 v = n.cross(u);
    const double h = 2 * a / k;
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j)
        add(c + (-a + (i + 0.5) * h) * u + (-a + (j + 0.5) * h) * v, n, 0.75 * h, p);
  }
  SurfelCloud build() const {
    SurfelCloud c = cloud;
    Attribute& a = c.attributes.add("patch_id", ScalarType::kInt32, 1, c.size());
    for (size_t i = 0; i < patch.size(); ++i) a.set(i, patch[i]);
    return c;
  }
};

ClipPartners bruteForce(const SurfelDiscs& d) {
  ClipPartners out;
  out.offsets.push_back(0);
  for (uint32_t i = 0; i < d.size(); ++i) {
    for (uint32_t j = 0; j < d.size(); ++j)
      if (i != j && d.partners(i, j)) out.ids.push_back(j);
    out.offsets.push_back(static_cast<uint32_t>(out.ids.size()));
  }
  return out;
}

bool intersect(const Vec3& c1, const Vec3& n1, double r1, const Vec3& c2, const Vec3& n2, double r2) {
  auto basis = [](const Vec3& n, double r, Vec3* t1, Vec3* t2) {
    const Vec3 h = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    *t1 = n.cross(h).normalized() * r;
    *t2 = n.normalized().cross(*t1);
  };
  Vec3 a1, a2, b1, b2;
  basis(n1, r1, &a1, &a2);
  basis(n2, r2, &b1, &b2);
  return discsIntersect(c1, n1.normalized(), a1, a2, c2, n2.normalized(), b1, b2);
}

TEST(DiscIntersection, AnalyticCases) {
  const Vec3 z(0, 0, 1), x(1, 0, 0);
  EXPECT_TRUE(intersect(Vec3(0, 0, 0), z, 1, Vec3(0.5, 0, 0), x, 1));
  EXPECT_TRUE(intersect(Vec3(0, 0, 0), z, 1, Vec3(0.99, 0, 0), x, 1));
  EXPECT_FALSE(intersect(Vec3(0, 0, 0), z, 1, Vec3(1.01, 0, 0), x, 1));    // plane x=1.01 misses disc 1
  EXPECT_FALSE(intersect(Vec3(0, 0, 0), z, 1, Vec3(0.5, 0, 1.01), x, 1));  // disc 2 above the plane z = 0
  // Both chords exist but do not overlap: disc 2 in plane x = 0.5 centred at y = 1.9 (chord y in [0.9, 2.9]),
  // disc 1 chord at x = 0.5 is y in [-0.866, 0.866].
  EXPECT_FALSE(intersect(Vec3(0, 0, 0), z, 1, Vec3(0.5, 1.9, 0), x, 1));
  EXPECT_TRUE(intersect(Vec3(0, 0, 0), z, 1, Vec3(0.5, 1.8, 0), x, 1));
  // Parallel: coplanar overlapping vs offset.
  EXPECT_TRUE(intersect(Vec3(0, 0, 0), z, 1, Vec3(1.5, 0, 0), z, 1));
  EXPECT_FALSE(intersect(Vec3(0, 0, 0), z, 1, Vec3(0.1, 0, 1e-3), z, 1));
  // Elliptical disc: semi-axes 2 (along x) and 0.1 (along y), cut by the plane y = 0.2: no chord.
  EXPECT_FALSE(discsIntersect(Vec3(0, 0, 0), z, Vec3(2, 0, 0), Vec3(0, 0.1, 0), Vec3(0, 0.2, 0),
                              Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)));
  EXPECT_TRUE(discsIntersect(Vec3(0, 0, 0), z, Vec3(2, 0, 0), Vec3(0, 0.1, 0), Vec3(1.5, 0, 0), Vec3(1, 0, 0),
                             Vec3(0, 1, 0), Vec3(0, 0, 1)));
}

TEST(DiscIntersection, NearParallelDiscsAreFinite) {
  const Vec3 z(0, 0, 1);
  for (double angle : {1e-2, 1e-3, 1e-6, 1e-9, 1e-12}) {
    const Vec3 n(std::sin(angle), 0, std::cos(angle));
    EXPECT_TRUE(intersect(Vec3(0, 0, 0), z, 1, Vec3(0, 0, 0), n, 1)) << angle;  // through a common centre
    // Offset by 1e-3 along z: plane z = 0 cuts disc 2 at distance 1e-3 / sin(angle) from its centre.
    EXPECT_EQ(intersect(Vec3(0, 0, 0), z, 1, Vec3(0, 0, 1e-3), n, 1), 1e-3 / std::sin(angle) < 1.0) << angle;
  }
}

// Random discs in [-1, 1]^3 with 4 patches, a quarter of them elliptical.
SurfelCloud randomScene(unsigned seed, int n) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), r(0.03, 0.25);
  SceneBuilder b;
  for (int i = 0; i < n; ++i)
    b.add(Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)), r(rng), i % 4);
  SurfelCloud c = b.build();
  c.axes1.resize(n);
  c.axes2.resize(n);
  for (int i = 0; i < n; ++i) {
    const Vec3 nrm = c.normals[i];
    const Vec3 t = nrm.cross(Vec3(u(rng), u(rng), u(rng))).normalized();
    const double squash = (i % 4 == 3) ? 0.3 : 1.0;
    c.axes1[i] = t * c.radii[i];
    c.axes2[i] = nrm.cross(t) * c.radii[i] * squash;
  }
  return c;
}

TEST(ClipPartners, ClipBufferEqualsSpatialIndexOnRandomScenes) {
  ClipPartnerFinder finder;
  for (unsigned seed = 1; seed <= 4; ++seed) {
    const SurfelDiscs d = SurfelDiscs::fromCloud(randomScene(seed, 500));
    const ClipPartners reference = bruteForce(d);
    ASSERT_GT(reference.pairCount(), 200u);
    ClipPartners spatial, buffer;
    finder.findSpatial(d, &spatial);
    EXPECT_TRUE(spatial == reference) << "seed " << seed;
    // Outside view, inside the scene (near plane crossed), edge-on views, orthographic, coarse cells.
    Camera far = Camera::perspective(320, 240, 1.0);
    far.lookAt(Vec3(3, 4, 2.5), Vec3(0, 0, 0));
    Camera inside = Camera::perspective(160, 120, 1.2);
    inside.lookAt(Vec3(0.1, 0.2, 0.0), Vec3(1, 0, 0));
    Camera ortho = Camera::orthographic(200, 200, 1.5);  // sees only part of the scene: the rest is clamped
    ortho.lookAt(Vec3(0, 0, 5), Vec3(0, 0, 0), Vec3::UnitY());
    for (const Camera* cam : {&far, &inside, &ortho}) {
      ClipPartnerStats stats;
      finder.findClipBuffer(d, *cam, &buffer, nullptr, &stats);
      EXPECT_TRUE(buffer == reference) << "seed " << seed << " camera " << (cam - &far);
      EXPECT_EQ(stats.pairs, reference.pairCount());
    }
    ClipPartnerFinder coarse(ClipBufferOptions{8.0, 0.05});
    coarse.findClipBuffer(d, far, &buffer);
    EXPECT_TRUE(buffer == reference);
  }
}

TEST(ClipPartners, CubeWith25SurfelsPerFace) {
  SceneBuilder b;
  const Vec3 axes[3] = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  for (int f = 0; f < 6; ++f) {
    const Vec3 n = (f % 2 ? -1.0 : 1.0) * axes[f / 2];
    b.face(n, n, axes[(f / 2 + 1) % 3], 1.0, 5, f);
  }
  const SurfelDiscs d = SurfelDiscs::fromCloud(b.build());
  ASSERT_EQ(d.size(), 150u);
  const ClipPartners reference = bruteForce(d);
  ClipPartnerFinder finder;
  ClipPartners spatial, buffer;
  finder.findSpatial(d, &spatial);
  EXPECT_TRUE(spatial == reference);
  Camera cam = Camera::perspective(400, 300, 0.9);
  cam.lookAt(Vec3(4, 3, 2.5), Vec3(0, 0, 0));
  ClipPartnerStats stats;
  finder.findClipBuffer(d, cam, &buffer, nullptr, &stats);
  EXPECT_TRUE(buffer == reference);
  // Exactly the 16 border surfels of each face touch a neighbouring face (their discs reach 0.3 past
  // centres 0.2 from the edge); the 9 interior ones (0.6 from every edge) have none.
  int edge = 0;
  for (uint32_t i = 0; i < d.size(); ++i) {
    const int local = i % 25, gi = local / 5, gj = local % 5;
    const bool border = gi == 0 || gi == 4 || gj == 0 || gj == 4;
    EXPECT_EQ(buffer.count(i) > 0, border) << i;
    edge += buffer.count(i) > 0;
    for (const uint32_t* p = buffer.begin(i); p != buffer.end(i); ++p) EXPECT_NE(d.patches[*p], d.patches[i]);
  }
  EXPECT_EQ(edge, 96);
  // Candidates restricted to the edge surfels give the same lists (partners are edge surfels themselves).
  std::vector<uint32_t> edges;
  for (uint32_t i = 0; i < d.size(); ++i)
    if (reference.count(i)) edges.push_back(i);
  finder.findClipBuffer(d, cam, &buffer, &edges);
  EXPECT_TRUE(buffer == reference);
  finder.findSpatial(d, &spatial, &edges);
  EXPECT_TRUE(spatial == reference);
}

TEST(ClipPartners, EdgeOnSurfelsAreRasterisedAsThickLines) {
  // A wall of discs seen exactly edge-on, crossed by discs of another patch.
  SceneBuilder b;
  for (int i = 0; i < 20; ++i) b.add(Vec3(0, -1 + 0.1 * i, 0), Vec3(1, 0, 0), 0.08, 0);
  for (int i = 0; i < 20; ++i) b.add(Vec3(0.02, -1 + 0.1 * i + 0.05, 0), Vec3(0, 0, 1), 0.06, 1);
  const SurfelDiscs d = SurfelDiscs::fromCloud(b.build());
  Camera cam = Camera::perspective(300, 300, 0.8);
  cam.lookAt(Vec3(0, 0, 5), Vec3(0, 0, 0), Vec3::UnitY());  // looks along -z: patch-0 discs are edge-on
  ClipPartnerFinder finder;
  ClipPartners buffer;
  ClipPartnerStats stats;
  finder.findClipBuffer(d, cam, &buffer, nullptr, &stats);
  EXPECT_EQ(stats.edge_on, 20u);
  EXPECT_TRUE(buffer == bruteForce(d));
  EXPECT_GT(buffer.pairCount(), 20u);
}

TEST(ClipPartners, BadInputIsRejected) {
  SceneBuilder b;
  b.add(Vec3(0, 0, 0), Vec3(0, 0, 1), 1, 0);
  SurfelCloud no_patch = b.cloud;
  EXPECT_THROW(SurfelDiscs::fromCloud(no_patch), std::invalid_argument);
  SurfelCloud bad_radius = b.build();
  bad_radius.radii[0] = 0;
  EXPECT_THROW(SurfelDiscs::fromCloud(bad_radius), std::invalid_argument);
  SurfelCloud bad_role = b.build();
  bad_role.attributes.add("surfel_role", ScalarType::kInt32, 1, 1).set(0, 5);
  EXPECT_THROW(SurfelDiscs::fromCloud(bad_role), std::invalid_argument);
  const SurfelDiscs d = SurfelDiscs::fromCloud(b.build());
  ClipPartnerFinder finder;
  ClipPartners out;
  std::vector<uint32_t> bad = {3};
  EXPECT_THROW(finder.findSpatial(d, &out, &bad), std::invalid_argument);
  EXPECT_THROW(finder.find(PartnerMethod::kClipBuffer, d, nullptr, &out), std::invalid_argument);
}

}  // namespace
}  // namespace rc
