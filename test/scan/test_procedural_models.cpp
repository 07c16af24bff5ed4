#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>

#include "relaxed_connectivity/mesh/mesh_metrics.h"
#include "relaxed_connectivity/scan/procedural_models.h"

namespace rc {
namespace {

constexpr double kPi = 3.14159265358979323846;

void expectClosedWithOutwardNormals(const TriangleMesh& mesh, const std::string& what) {
  SCOPED_TRACE(what);
  const EdgeStatistics s = edgeStatistics(mesh);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.misoriented_edges, 0u);
  EXPECT_EQ(s.degenerate_triangles, 0u);
  // Euler characteristic of a closed manifold: V - E + F = 2 - 2 * genus, and 3F = 2E.
  EXPECT_EQ(2 * s.edges, 3 * mesh.triangles.size());
  EXPECT_TRUE(isWatertight(mesh));
  EXPECT_GT(signedVolume(mesh), 0.0);
  ASSERT_EQ(mesh.vertices.normals.size(), mesh.vertices.size());
  ASSERT_EQ(mesh.vertices.colors.size(), mesh.vertices.size());
  // Vertex normals are unit and agree with the outward area-weighted face normals.
  TriangleMesh face_normals = mesh;
  computeVertexNormals(face_normals);
  size_t disagreeing = 0;
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    EXPECT_NEAR(mesh.vertices.normals[i].norm(), 1.0, 1e-9);
    if (mesh.vertices.normals[i].dot(face_normals.vertices.normals[i]) < 0.9) ++disagreeing;
  }
  EXPECT_EQ(disagreeing, 0u);
}

int eulerCharacteristic(const TriangleMesh& mesh) {
  return static_cast<int>(mesh.vertices.size()) - static_cast<int>(edgeStatistics(mesh).edges) +
         static_cast<int>(mesh.triangles.size());
}

TEST(ProceduralModels, IcosphereIsClosedWithSphereVolume) {
  const double r = 0.7;
  const TriangleMesh mesh = makeIcosphere(r, 16);
  EXPECT_EQ(mesh.triangles.size(), 20u * 16 * 16);
  EXPECT_EQ(mesh.vertices.size(), 10u * 16 * 16 + 2);
  expectClosedWithOutwardNormals(mesh, "icosphere");
  EXPECT_EQ(eulerCharacteristic(mesh), 2);
  for (const Vec3& p : mesh.vertices.positions) EXPECT_NEAR(p.norm(), r, 1e-12);
  const double exact = 4.0 / 3.0 * kPi * r * r * r;
  const double volume = signedVolume(mesh);
  EXPECT_LT(volume, exact);  // inscribed polyhedron
  EXPECT_GT(volume, 0.99 * exact);
  EXPECT_NEAR(surfaceArea(mesh), 4.0 * kPi * r * r, 0.01 * 4.0 * kPi * r * r);
}

TEST(ProceduralModels, IcosphereVolumeErrorShrinksQuadratically) {
  const double exact = 4.0 / 3.0 * kPi;
  const double e8 = exact - signedVolume(makeIcosphere(1.0, 8));
  const double e16 = exact - signedVolume(makeIcosphere(1.0, 16));
  EXPECT_NEAR(e8 / e16, 4.0, 0.2);
}

TEST(ProceduralModels, UvSphereIsClosedWithSphereVolume) {
  const TriangleMesh mesh = makeUvSphere(0.5, 64, 32);
  EXPECT_EQ(mesh.triangles.size(), 2u * 64 * 31);
  expectClosedWithOutwardNormals(mesh, "uv_sphere");
  EXPECT_EQ(eulerCharacteristic(mesh), 2);
  const double exact = 4.0 / 3.0 * kPi * 0.125;
  EXPECT_LT(signedVolume(mesh), exact);
  EXPECT_GT(signedVolume(mesh), 0.99 * exact);
}

TEST(ProceduralModels, TorusIsClosedGenusOneWithPappusVolume) {
  const double R = 0.5, r = 0.2;
  const TriangleMesh mesh = makeTorus(R, r, 96, 48);
  EXPECT_EQ(mesh.triangles.size(), 2u * 96 * 48);
  expectClosedWithOutwardNormals(mesh, "torus");
  EXPECT_EQ(eulerCharacteristic(mesh), 0);
  const double exact = 2.0 * kPi * kPi * R * r * r;
  EXPECT_NEAR(signedVolume(mesh), exact, 0.005 * exact);
  EXPECT_NEAR(surfaceArea(mesh), 4.0 * kPi * kPi * R * r, 0.005 * 4.0 * kPi * kPi * R * r);
}

TEST(ProceduralModels, BoxIsClosedWithExactVolumeAndArea) {
  const Vec3 size(0.8, 0.6, 0.4);
  for (int n : {1, 3, 10}) {
    const TriangleMesh mesh = makeBox(size, n);
    EXPECT_EQ(mesh.triangles.size(), 12u * n * n);
    EXPECT_EQ(mesh.vertices.size(), 6u * n * n + 2);
    expectClosedWithOutwardNormals(mesh, "box n=" + std::to_string(n));
    EXPECT_NEAR(signedVolume(mesh), 0.8 * 0.6 * 0.4, 1e-12);
    EXPECT_NEAR(surfaceArea(mesh), 2.0 * (0.8 * 0.6 + 0.6 * 0.4 + 0.4 * 0.8), 1e-12);
    Vec3 lo, hi;
    ASSERT_TRUE(mesh.vertices.bounds(&lo, &hi));
    EXPECT_TRUE(lo.isApprox(-0.5 * size, 1e-12));
    EXPECT_TRUE(hi.isApprox(0.5 * size, 1e-12));
  }
}

TEST(ProceduralModels, BlobVolumeMatchesQuadratureOfItsRadiusFunction) {
  const double radius = 0.5, amplitude = 0.3;
  const TriangleMesh mesh = makeBlob(radius, amplitude, 40);
  expectClosedWithOutwardNormals(mesh, "blob");
  EXPECT_EQ(eulerCharacteristic(mesh), 2);
  for (const Vec3& p : mesh.vertices.positions)
    EXPECT_NEAR(p.norm(), blobRadius(p.normalized(), radius, amplitude), 1e-12);
  // V = (1/3) integral of r(d)^3 over the unit sphere (midpoint rule in theta, phi).
  const int nt = 600, np = 1200;
  double exact = 0.0;
  for (int i = 0; i < nt; ++i) {
    const double theta = kPi * (i + 0.5) / nt;
    for (int j = 0; j < np; ++j) {
      const double phi = 2.0 * kPi * (j + 0.5) / np;
      const Vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      const double r = blobRadius(d, radius, amplitude);
      exact += r * r * r / 3.0 * std::sin(theta) * (kPi / nt) * (2.0 * kPi / np);
    }
  }
  EXPECT_NEAR(signedVolume(mesh), exact, 0.005 * exact);
  // The displacement is real: the radius varies by more than +-15 % over the surface.
  double r_min = 1e9, r_max = 0.0;
  for (const Vec3& p : mesh.vertices.positions) {
    r_min = std::min(r_min, p.norm());
    r_max = std::max(r_max, p.norm());
  }
  EXPECT_LT(r_min, 0.85 * radius);
  EXPECT_GT(r_max, 1.15 * radius);
}

TEST(ProceduralModels, TorusKnotTubeIsEmbeddedAndHasTubeVolume) {
  const int p = 2, q = 3;
  const double R = 0.4, r = 0.16, tube = 0.07;
  // The tube is embedded (no self-overlap) if centre-line points further apart along the curve than the tube
  // diameter stay more than a diameter apart in space.
  const int samples = 2000;
  std::vector<Vec3> c(samples);
  double length = 0.0;
  for (int i = 0; i < samples; ++i) c[i] = torusKnotPoint(p, q, R, r, 2.0 * kPi * i / samples);
  for (int i = 0; i < samples; ++i) length += (c[(i + 1) % samples] - c[i]).norm();
  double closest = 1e9;
  std::vector<double> arc(samples + 1, 0.0);
  for (int i = 0; i < samples; ++i) arc[i + 1] = arc[i] + (c[(i + 1) % samples] - c[i]).norm();
  for (int i = 0; i < samples; ++i)
    for (int j = i + 1; j < samples; ++j) {
      const double along = std::min(arc[j] - arc[i], length - (arc[j] - arc[i]));
      if (along > 4.0 * tube) closest = std::min(closest, (c[i] - c[j]).norm());
    }
  EXPECT_GT(closest, 2.0 * tube);

  const TriangleMesh mesh = makeTorusKnot(p, q, R, r, tube, 480, 40);
  EXPECT_EQ(mesh.triangles.size(), 2u * 480 * 40);
  expectClosedWithOutwardNormals(mesh, "torus_knot");
  EXPECT_EQ(eulerCharacteristic(mesh), 0);
  const double exact = kPi * tube * tube * length;  // tube volume = cross-section area * centre-line length
  EXPECT_NEAR(signedVolume(mesh), exact, 0.01 * exact);
}

TEST(ProceduralModels, GroundPlaneIsOpenSquareFacingUp) {
  const TriangleMesh plane = makeGroundPlane(-0.3, 2.0, 5);
  EXPECT_EQ(plane.triangles.size(), 50u);
  const EdgeStatistics s = edgeStatistics(plane);
  EXPECT_EQ(s.boundary_edges, 20u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.misoriented_edges, 0u);
  EXPECT_NEAR(surfaceArea(plane), 16.0, 1e-12);
  const auto& p = plane.vertices.positions;
  for (const Triangle& t : plane.triangles) EXPECT_GT((p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).z(), 0.0);
}

TEST(ProceduralModels, MakeModelBuildsEveryNamedModelClosed) {
  const int resolution = 6;
  const std::vector<size_t> expected_triangles = {20 * 36, 2 * 12 * 5, 4 * 36, 12 * 36, 20 * 36, 16 * 36};
  ASSERT_EQ(modelNames().size(), expected_triangles.size());
  for (size_t i = 0; i < modelNames().size(); ++i) {
    const std::string& name = modelNames()[i];
    const TriangleMesh mesh = makeModel(name, resolution);
    EXPECT_EQ(mesh.triangles.size(), expected_triangles[i]) << name;
    EXPECT_TRUE(isWatertight(mesh)) << name;
    EXPECT_GT(signedVolume(mesh), 0.0) << name;

    const TriangleMesh scene = makeModel(name, resolution, true);
    const EdgeStatistics s = edgeStatistics(scene);
    const int plane_cells = std::max(1, resolution / 4);
    EXPECT_EQ(scene.triangles.size(), mesh.triangles.size() + 2u * plane_cells * plane_cells) << name;
    EXPECT_EQ(s.boundary_edges, 4u * plane_cells) << name;
    Vec3 lo, hi, scene_lo, scene_hi;
    mesh.vertices.bounds(&lo, &hi);
    scene.vertices.bounds(&scene_lo, &scene_hi);
    EXPECT_LT(scene_lo.z(), lo.z()) << name;
    EXPECT_GT(scene_lo.z(), lo.z() - 0.01) << name;
    EXPECT_EQ(scene.vertices.colors.size(), scene.vertices.size()) << name;
  }
}

TEST(ProceduralModels, BadInputThrowsClearErrors) {
  try {
    makeModel("teapot", 8);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("teapot"), std::string::npos) << message;
    for (const std::string& name : modelNames()) EXPECT_NE(message.find(name), std::string::npos) << message;
  }
  EXPECT_THROW(makeModel("torus", 2), std::invalid_argument);
  EXPECT_THROW(makeModel("box", 0), std::invalid_argument);
  EXPECT_THROW(makeIcosphere(-1.0, 4), std::invalid_argument);
  EXPECT_THROW(makeTorus(0.2, 0.5, 16, 8), std::invalid_argument);
  EXPECT_THROW(makeUvSphere(1.0, 2, 8), std::invalid_argument);
  EXPECT_THROW(makeBox(Vec3(1.0, 0.0, 1.0), 2), std::invalid_argument);
  EXPECT_THROW(makeBlob(1.0, 0.95, 4), std::invalid_argument);
  EXPECT_THROW(makeTorusKnot(2, 3, 1.0, 0.4, 0.1, 2, 8), std::invalid_argument);
}

TEST(MeshMetrics, DetectsOpenNonManifoldAndMisorientedEdges) {
  TriangleMesh mesh = makeBox(Vec3(1, 1, 1), 1);
  EXPECT_TRUE(isWatertight(mesh));
  TriangleMesh open = mesh;
  open.triangles.pop_back();
  EXPECT_EQ(edgeStatistics(open).boundary_edges, 3u);
  EXPECT_FALSE(isWatertight(open));
  TriangleMesh flipped = mesh;
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  EXPECT_EQ(edgeStatistics(flipped).misoriented_edges, 3u);
  EXPECT_FALSE(isWatertight(flipped));
  TriangleMesh doubled = mesh;
  doubled.triangles.push_back(mesh.triangles[0]);
  EXPECT_EQ(edgeStatistics(doubled).non_manifold_edges, 3u);
  TriangleMesh inverted = mesh;
  for (Triangle& t : inverted.triangles) std::swap(t[1], t[2]);
  EXPECT_NEAR(signedVolume(inverted), -1.0, 1e-12);
  TriangleMesh bad = mesh;
  bad.triangles[0][0] = 99;
  EXPECT_THROW(edgeStatistics(bad), std::invalid_argument);
}

}  // namespace
}  // namespace rc
