// Mean value coordinates on convex polyhedra (thesis 9.1.1, appendix D) and the polyhedral element checks.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "random_hull_support.h"
#include "relaxed_connectivity/fem/convex_polyhedron.h"
#include "relaxed_connectivity/fem/mean_value_coordinates.h"

#if defined(RC_HAVE_VTK)
#include <vtkIdList.h>
#include <vtkMeanValueCoordinatesInterpolator.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#endif

namespace rc {
namespace {

std::vector<Vec3> icosahedronPoints() {
  const double phi = 0.5 * (1.0 + std::sqrt(5.0));
  std::vector<Vec3> p;
  for (double s : {-1.0, 1.0})
    for (double t : {-1.0, 1.0}) {
      p.emplace_back(0.0, s, t * phi);
      p.emplace_back(s, t * phi, 0.0);
      p.emplace_back(t * phi, 0.0, s);
    }
  return p;
}

ConvexPolyhedron unitCube() {
  return ConvexPolyhedron::hexahedron({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0),
                                       Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(1, 1, 1), Vec3(0, 1, 1)});
}

ConvexPolyhedron skewTetrahedron() {
  return ConvexPolyhedron::tetrahedron(Vec3(0.1, -0.2, 0.05), Vec3(2.0, 0.3, -0.1), Vec3(0.4, 1.7, 0.2),
                                       Vec3(0.5, 0.6, 1.3));
}

struct NamedElement {
  std::string name;
  ConvexPolyhedron element;
};

std::vector<NamedElement> testElements() {
  std::vector<NamedElement> elements;
  elements.push_back({"tetrahedron", skewTetrahedron()});
  elements.push_back({"cube", unitCube()});
  elements.push_back(
      {"frustum", ConvexPolyhedron::hexahedron({Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0),
                                                Vec3(-1, 1, 0), Vec3(-0.4, -0.5, 0.8), Vec3(0.6, -0.5, 0.8),
                                                Vec3(0.6, 0.5, 0.8), Vec3(-0.4, 0.5, 0.8)})});
  elements.push_back({"icosahedron", ConvexPolyhedron::convexHull(icosahedronPoints())});
  elements.push_back({"random12", ConvexPolyhedron::convexHull(randomPointsOnEllipsoid(12, 7))});
  elements.push_back({"random36", ConvexPolyhedron::convexHull(randomPointsOnEllipsoid(36, 11))});
  return elements;
}

// Random interior points: random convex combinations of the nodes, mixed with points pulled towards one node.
std::vector<Vec3> randomInteriorPoints(const ConvexPolyhedron& e, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<Vec3> points;
  for (int k = 0; k < count; ++k) {
    Vec3 p = Vec3::Zero();
    double total = 0.0;
    for (const Vec3& node : e.nodes()) {
      const double w = -std::log(1.0 - uniform(rng));
      p += w * node;
      total += w;
    }
    p /= total;
    if (k % 3 == 0) p = 0.9 * e.node(k % e.numNodes()) + 0.1 * p;
    points.push_back(p);
  }
  return points;
}

Vec3 interpolatedPosition(const ConvexPolyhedron& e, const Eigen::VectorXd& lambda) {
  Vec3 x = Vec3::Zero();
  for (int i = 0; i < e.numNodes(); ++i) x += lambda[i] * e.node(i);
  return x;
}

TEST(ConvexPolyhedron, VolumeCentroidAndHull) {
  const ConvexPolyhedron cube = unitCube();
  EXPECT_NEAR(cube.volume(), 1.0, 1e-14);
  EXPECT_LT((cube.centroid() - Vec3(0.5, 0.5, 0.5)).norm(), 1e-14);
  EXPECT_EQ(cube.numTriangles(), 12);
  const ConvexPolyhedron tet = skewTetrahedron();
  Eigen::Matrix3d edges;
  for (int k = 0; k < 3; ++k) edges.col(k) = tet.node(k + 1) - tet.node(0);
  EXPECT_NEAR(tet.volume(), edges.determinant() / 6.0, 1e-14);
  EXPECT_LT((tet.centroid() - 0.25 * (tet.node(0) + tet.node(1) + tet.node(2) + tet.node(3))).norm(), 1e-14);

  // Icosahedron of edge length 2: V = 5/12 (3 + sqrt 5) a^3, 12 nodes, 20 faces.
  const ConvexPolyhedron ico = ConvexPolyhedron::convexHull(icosahedronPoints());
  EXPECT_EQ(ico.numNodes(), 12);
  EXPECT_EQ(ico.numFaces(), 20);
  EXPECT_NEAR(ico.volume(), 5.0 / 12.0 * (3.0 + std::sqrt(5.0)) * 8.0, 1e-12);
  EXPECT_LT(ico.centroid().norm(), 1e-14);

  // Cube corners + edge midpoints + face centres + centre: 6 octagonal faces with mid-edge nodes; face
  // centres and the centre are no hull nodes.
  std::vector<Vec3> points;
  for (int x = 0; x <= 2; ++x)
    for (int y = 0; y <= 2; ++y)
      for (int z = 0; z <= 2; ++z) points.emplace_back(0.5 * x, 0.5 * y, 0.5 * z);
  const ConvexPolyhedron box = ConvexPolyhedron::convexHull(points);
  EXPECT_EQ(box.numNodes(), 20);
  EXPECT_EQ(box.numFaces(), 6);
  for (const auto& face : box.faces()) EXPECT_EQ(face.size(), 8u);
  EXPECT_NEAR(box.volume(), 1.0, 1e-14);
  for (int i = 0; i < box.numNodes(); ++i) EXPECT_EQ(box.node(i), points[box.globalNodeIds()[i]]);
  // The best fan avoids zero-area triangles on faces with collinear nodes.
  for (const auto& t : box.triangles())
    EXPECT_GT((box.node(t[1]) - box.node(t[0])).cross(box.node(t[2]) - box.node(t[0])).norm(), 0.1);
}

void expectRejected(const std::function<void()>& build, const std::string& message_part) {
  try {
    build();
    ADD_FAILURE() << "accepted an invalid polyhedron (expected '" << message_part << "')";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(message_part), std::string::npos) << e.what();
  }
}

TEST(ConvexPolyhedron, RejectsInvalidElements) {
  const std::vector<Vec3> cube_nodes = unitCube().nodes();
  const std::vector<ConvexPolyhedron::Face> cube_faces = unitCube().faces();
  // Open: one face missing.
  expectRejected(
      [&] {
        ConvexPolyhedron(cube_nodes, {cube_faces.begin(), cube_faces.end() - 1});
      },
      "not closed");
  // One face reversed.
  auto flipped = cube_faces;
  std::reverse(flipped[2].begin(), flipped[2].end());
  expectRejected([&] { ConvexPolyhedron(cube_nodes, flipped); }, "same direction");
  // All faces reversed: inverted.
  auto inverted = cube_faces;
  for (auto& f : inverted) std::reverse(f.begin(), f.end());
  expectRejected([&] { ConvexPolyhedron(cube_nodes, inverted); }, "inverted");
  expectRejected(
      [] {
        ConvexPolyhedron::hexahedron({Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(1, 1, 1), Vec3(0, 1, 1),
                                      Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)});
      },
      "inverted");
  expectRejected(
      [] { ConvexPolyhedron::tetrahedron(Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)); },
      "inverted");
  // Non-planar face: one corner lifted.
  auto lifted = cube_nodes;
  lifted[6].z() += 0.1;
  expectRejected([&] { ConvexPolyhedron(lifted, cube_faces); }, "not planar");
  // Non-convex: a triangulated octahedron with its top node pushed below the equator (a dent).
  std::vector<Vec3> octa{Vec3(1, 0, 0),  Vec3(0, 1, 0),    Vec3(-1, 0, 0),
                         Vec3(0, -1, 0), Vec3(0, 0, -0.3), Vec3(0, 0, -1)};
  std::vector<ConvexPolyhedron::Face> octa_faces{{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4},
                                                 {1, 0, 5}, {2, 1, 5}, {3, 2, 5}, {0, 3, 5}};
  expectRejected([&] { ConvexPolyhedron(octa, octa_faces); }, "not convex");
  octa[4].z() = 1.0;
  EXPECT_NO_THROW(ConvexPolyhedron(octa, octa_faces));
  // Bad indices, unused nodes, coplanar hulls.
  expectRejected(
      [&] {
        ConvexPolyhedron(cube_nodes, {{0, 1, 2}, {0, 1, 9}, {0, 2, 3}, {1, 2, 3}});
      },
      "references node 9");
  auto extra = cube_nodes;
  extra.emplace_back(0.5, 0.5, 0.5);
  expectRejected([&] { ConvexPolyhedron(extra, cube_faces); }, "node 8 is on no face");
  expectRejected(
      [] {
        ConvexPolyhedron::convexHull({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)});
      },
      "coplanar");
  // A given triangulation must tile its face.
  std::vector<std::vector<ConvexPolyhedron::Triangle>> tris;
  for (const auto& f : cube_faces) tris.push_back({{f[0], f[1], f[2]}});
  expectRejected([&] { ConvexPolyhedron(cube_nodes, cube_faces, tris); }, "does not tile");
}

TEST(MeanValueCoordinates, PartitionOfUnityLinearPrecisionPositivity) {
  for (const auto& [name, element] : testElements()) {
    const MeanValueCoordinates mvc(element);
    Eigen::VectorXd lambda;
    Eigen::Matrix<double, Eigen::Dynamic, 3> grad;
    double worst_sum = 0.0, worst_position = 0.0, smallest = INFINITY;
    for (const Vec3& x : randomInteriorPoints(element, 300, 3)) {
      EXPECT_EQ(mvc.evaluate(x, lambda, grad), BoundaryContact::kInterior);
      worst_sum = std::max(worst_sum, std::abs(lambda.sum() - 1.0));
      worst_position =
          std::max(worst_position, (interpolatedPosition(element, lambda) - x).norm() / element.scale());
      smallest = std::min(smallest, lambda.minCoeff());
    }
    std::printf("[ stats    ] %-12s |sum-1| %.1e  |x-sum x_i phi_i|/scale %.1e  min phi %.2e\n", name.c_str(),
                worst_sum, worst_position, smallest);
    EXPECT_LT(worst_sum, 1e-12) << name;
    EXPECT_LT(worst_position, 1e-12) << name;  // (9.11)
    EXPECT_GT(smallest, 0.0) << name;
  }
}

TEST(MeanValueCoordinates, TetrahedronEqualsBarycentric) {
  const ConvexPolyhedron tet = skewTetrahedron();
  MeanValueCoordinates::Options general;
  general.tetrahedron_shortcut = false;
  const MeanValueCoordinates linear(tet), mvc(tet, general);
  Eigen::VectorXd a, b;
  Eigen::Matrix<double, Eigen::Dynamic, 3> ga, gb;
  double worst_value = 0.0, worst_gradient = 0.0;
  for (const Vec3& x : randomInteriorPoints(tet, 300, 5)) {
    linear.evaluate(x, a, ga);
    mvc.evaluate(x, b, gb);
    // Barycentric coordinates as volume ratios.
    for (int i = 0; i < 4; ++i) {
      std::array<Vec3, 4> v{tet.node(0), tet.node(1), tet.node(2), tet.node(3)};
      v[i] = x;
      const double sub = (v[1] - v[0]).dot((v[2] - v[0]).cross(v[3] - v[0])) / 6.0;
      EXPECT_NEAR(a[i], sub / tet.volume(), 1e-13);
    }
    worst_value = std::max(worst_value, (a - b).cwiseAbs().maxCoeff());
    worst_gradient = std::max(worst_gradient, (ga - gb).cwiseAbs().maxCoeff() / ga.cwiseAbs().maxCoeff());
  }
  std::printf("[ stats    ] MVC vs barycentric on a tetrahedron: values %.1e, gradients (relative) %.1e\n",
              worst_value, worst_gradient);
  EXPECT_LT(worst_value, 1e-12);
  EXPECT_LT(worst_gradient, 1e-10);
}

TEST(MeanValueCoordinates, GradientsMatchFiniteDifferencesAndIdentities) {
  for (const auto& [name, element] : testElements()) {
    MeanValueCoordinates::Options general;
    general.tetrahedron_shortcut = false;
    const MeanValueCoordinates mvc(element, general);
    const int n = element.numNodes();
    const double h = 1e-5 * element.scale();
    Eigen::VectorXd lambda, plus, minus;
    Eigen::Matrix<double, Eigen::Dynamic, 3> grad, unused;
    double worst_fd = 0.0, worst_sum = 0.0, worst_identity = 0.0;
    for (const Vec3& x : randomInteriorPoints(element, 60, 9)) {
      if (element.maxFacePlaneDistance(x) > -2.0 * h) continue;
      mvc.evaluate(x, lambda, grad);
      Eigen::Matrix<double, Eigen::Dynamic, 3> fd(n, 3);
      for (int k = 0; k < 3; ++k) {
        mvc.evaluate(x + h * Vec3::Unit(k), plus, unused);
        mvc.evaluate(x - h * Vec3::Unit(k), minus, unused);
        fd.col(k) = (plus - minus) / (2.0 * h);
      }
      worst_fd = std::max(worst_fd, (grad - fd).norm() / grad.norm());
      worst_sum = std::max(worst_sum, grad.colwise().sum().norm() * element.scale());
      Eigen::Matrix3d identity = Eigen::Matrix3d::Zero();  // sum_i x_i grad phi_i^T = I
      for (int i = 0; i < n; ++i) identity += element.node(i) * grad.row(i);
      worst_identity =
          std::max(worst_identity, (identity - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff());
    }
    std::printf(
        "[ stats    ] %-12s gradient vs central FD %.1e, |sum grad| * scale %.1e, |sum x_i grad^T - I| "
        "%.1e\n",
        name.c_str(), worst_fd, worst_sum, worst_identity);
    EXPECT_LT(worst_fd, 1e-6) << name;
    EXPECT_LT(worst_sum, 1e-10) << name;
    EXPECT_LT(worst_identity, 1e-10) << name;
  }
}

// (9.8)-(9.9) literally: one-ring sums of signed tetrahedron volume ratios, V_{a,b,c} = V(x_a, x_b, x_c, x).
Eigen::VectorXd thesisCoordinates(const ConvexPolyhedron& e, const Vec3& x) {
  const int n = e.numNodes();
  auto volume = [&](int a, int b, int c) {
    return (e.node(b) - e.node(a)).dot((e.node(c) - e.node(a)).cross(x - e.node(a))) / 6.0;
  };
  auto edge_weight = [&](int a, int b) {
    const Vec3 da = e.node(a) - x, db = e.node(b) - x;
    return da.cross(db).norm() / 6.0 * std::acos(da.dot(db) / (da.norm() * db.norm()));
  };
  Eigen::VectorXd w = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n; ++i) {
    std::map<int, int> next;  // one ring: triangle (i, j, next[j])
    for (const auto& t : e.triangles())
      for (int k = 0; k < 3; ++k)
        if (t[k] == i) next[t[(k + 1) % 3]] = t[(k + 2) % 3];
    std::map<int, int> previous;
    for (const auto& [j, k] : next) previous[k] = j;
    for (const auto& [j, j_next] : next) {
      const int j_prev = previous.at(j);
      w[i] += edge_weight(j, j_next) / volume(i, j, j_next) +
              edge_weight(i, j) * volume(j_prev, j_next, j) / (volume(i, j_prev, j) * volume(i, j, j_next));
    }
  }
  return w / w.sum();
}

TEST(MeanValueCoordinates, EqualThesisOneRingFormula) {
  for (const auto& [name, element] : testElements()) {
    MeanValueCoordinates::Options general;
    general.tetrahedron_shortcut = false;
    const MeanValueCoordinates mvc(element, general);
    Eigen::VectorXd lambda;
    Eigen::Matrix<double, Eigen::Dynamic, 3> grad;
    double worst = 0.0;
    for (const Vec3& x : randomInteriorPoints(element, 50, 13)) {
      mvc.evaluate(x, lambda, grad);
      worst = std::max(worst, (lambda - thesisCoordinates(element, x)).cwiseAbs().maxCoeff());
    }
    std::printf("[ stats    ] %-12s vs (9.8) one-ring formula %.1e\n", name.c_str(), worst);
    EXPECT_LT(worst, 1e-11) << name;
  }
}

TEST(MeanValueCoordinates, ContinuousAtFacesEdgesAndVertices) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> uniform(0.05, 1.0);
  for (const auto& [name, element] : testElements()) {
    MeanValueCoordinates::Options general;
    general.tetrahedron_shortcut = false;
    const MeanValueCoordinates mvc(element, general);
    const int n = element.numNodes();
    Eigen::VectorXd on, near, expected;
    Eigen::Matrix<double, Eigen::Dynamic, 3> grad_on, grad_near;
    double worst_face = 0.0, worst_edge = 0.0, worst_vertex = 0.0, worst_gradient = 0.0;
    for (int t = 0; t < element.numTriangles(); ++t) {
      const auto& tri = element.triangles()[t];
      const Vec3 normal = element.faceNormal(element.triangleFace()[t]);
      Vec3 b(uniform(rng), uniform(rng), uniform(rng));
      b /= b.sum();
      // Face: on-face value is the triangle's barycentric coordinates; 1e-12 inside it converges to them.
      const Vec3 p = b[0] * element.node(tri[0]) + b[1] * element.node(tri[1]) + b[2] * element.node(tri[2]);
      EXPECT_EQ(mvc.evaluate(p, on, grad_on), BoundaryContact::kFace) << name;
      expected = Eigen::VectorXd::Zero(n);
      for (int k = 0; k < 3; ++k) expected[tri[k]] = b[k];
      EXPECT_LT((on - expected).cwiseAbs().maxCoeff(), 1e-13) << name;
      EXPECT_EQ(mvc.evaluate(p - 1e-12 * element.scale() * normal, near, grad_near),
                BoundaryContact::kInterior);
      worst_face = std::max(worst_face, (near - on).cwiseAbs().maxCoeff());
      // The boundary gradient is the inward limit: compare with the analytic gradient 1e-7 inside.
      const Vec3 inward = (element.centroid() - p).normalized();
      mvc.evaluate(p + 1e-7 * element.scale() * inward, near, grad_near);
      worst_gradient = std::max(worst_gradient, (grad_on - grad_near).norm() / grad_on.norm());
      // Edge (tri[0], tri[1]): linear along the edge.
      const double s = b[0] / (b[0] + b[1]);
      const Vec3 q = s * element.node(tri[0]) + (1.0 - s) * element.node(tri[1]);
      const BoundaryContact edge_contact = mvc.evaluate(q, on, grad_on);
      EXPECT_EQ(edge_contact, BoundaryContact::kEdge) << name;
      expected = Eigen::VectorXd::Zero(n);
      expected[tri[0]] = s;
      expected[tri[1]] = 1.0 - s;
      EXPECT_LT((on - expected).cwiseAbs().maxCoeff(), 1e-13) << name;
      mvc.evaluate(q + 1e-12 * element.scale() * (element.centroid() - q).normalized(), near, grad_near);
      worst_edge = std::max(worst_edge, (near - expected).cwiseAbs().maxCoeff());
      // Vertex: Kronecker delta.
      const Vec3& v = element.node(tri[2]);
      EXPECT_EQ(mvc.evaluate(v, on, grad_on), BoundaryContact::kVertex) << name;
      expected = Eigen::VectorXd::Unit(n, tri[2]);
      EXPECT_EQ(on, expected) << name;
      mvc.evaluate(v + 1e-12 * element.scale() * (element.centroid() - v).normalized(), near, grad_near);
      worst_vertex = std::max(worst_vertex, (near - expected).cwiseAbs().maxCoeff());
    }
    std::printf(
        "[ stats    ] %-12s 1e-12 from face %.1e, edge %.1e, node %.1e; boundary gradient vs 1e-7 inside "
        "%.1e\n",
        name.c_str(), worst_face, worst_edge, worst_vertex, worst_gradient);
    EXPECT_LT(worst_face, 1e-8) << name;
    EXPECT_LT(worst_edge, 1e-8) << name;
    EXPECT_LT(worst_vertex, 1e-8) << name;
    EXPECT_LT(worst_gradient, 1e-4) << name;
  }
}

TEST(MeanValueCoordinates, ZeroAreaTrianglesAreSkipped) {
  // Box with mid-edge nodes triangulated by fans from a corner: each face has two zero-area triangles.
  std::vector<Vec3> points;
  for (int x = 0; x <= 2; ++x)
    for (int y = 0; y <= 2; ++y)
      for (int z = 0; z <= 2; ++z)
        if ((x == 1) + (y == 1) + (z == 1) <= 1) points.emplace_back(0.5 * x, 0.7 * y, 0.4 * z);
  const ConvexPolyhedron hull = ConvexPolyhedron::convexHull(points);
  std::vector<std::vector<ConvexPolyhedron::Triangle>> corner_fans;
  int zero_area = 0;
  for (const auto& face : hull.faces()) {
    int corner = 0;  // a face node that is a box corner: not collinear with its neighbours
    const int k = static_cast<int>(face.size());
    for (int c = 0; c < k; ++c) {
      const Vec3 &a = hull.node(face[(c + k - 1) % k]), &b = hull.node(face[c]),
                 &d = hull.node(face[(c + 1) % k]);
      if ((b - a).cross(d - b).norm() > 1e-9) corner = c;
    }
    std::vector<ConvexPolyhedron::Triangle> fan;
    for (int j = 1; j + 1 < k; ++j) {
      fan.push_back({face[corner], face[(corner + j) % k], face[(corner + j + 1) % k]});
      const auto& t = fan.back();
      if ((hull.node(t[1]) - hull.node(t[0])).cross(hull.node(t[2]) - hull.node(t[0])).norm() < 1e-12)
        ++zero_area;
    }
    corner_fans.push_back(fan);
  }
  EXPECT_EQ(zero_area, 12);
  const ConvexPolyhedron fanned(hull.nodes(), hull.faces(), corner_fans);
  // Nodes only on zero-area triangles (here the mid-edge node on the box edge where both faces' corner fans
  // degenerate) get phi = 0; all others stay positive.
  std::vector<bool> on_area(fanned.numNodes(), false);
  for (const auto& t : fanned.triangles())
    if ((fanned.node(t[1]) - fanned.node(t[0])).cross(fanned.node(t[2]) - fanned.node(t[0])).norm() > 1e-12)
      for (int v : t) on_area[v] = true;
  const int zero_nodes = static_cast<int>(std::count(on_area.begin(), on_area.end(), false));
  EXPECT_GE(zero_nodes, 1);
  const MeanValueCoordinates mvc(fanned);
  Eigen::VectorXd lambda;
  Eigen::Matrix<double, Eigen::Dynamic, 3> grad;
  for (const Vec3& x : randomInteriorPoints(fanned, 100, 21)) {
    mvc.evaluate(x, lambda, grad);
    EXPECT_NEAR(lambda.sum(), 1.0, 1e-12);
    EXPECT_LT((interpolatedPosition(fanned, lambda) - x).norm(), 1e-12);
    EXPECT_LT(grad.colwise().sum().norm(), 1e-10);
    for (int i = 0; i < fanned.numNodes(); ++i) {
      if (on_area[i]) {
        EXPECT_GT(lambda[i], 0.0);
      } else {
        EXPECT_EQ(lambda[i], 0.0);
      }
    }
  }
}

TEST(MeanValueCoordinates, RejectsPointsOutside) {
  const MeanValueCoordinates mvc(unitCube());
  std::vector<double> lambda(8);
  EXPECT_THROW(mvc.evaluate(Vec3(0.5, 0.5, 1.001), lambda.data()), std::domain_error);
  EXPECT_NO_THROW(mvc.evaluate(Vec3(0.5, 0.5, 1.0), lambda.data()));
}

TEST(MeanValueCoordinates, MatchesVtkMeanValueCoordinatesInterpolator) {
#if defined(RC_HAVE_VTK)
  double worst_vtk_tet = 0.0, worst_ours_tet = 0.0;
  for (const auto& [name, element] : testElements()) {
    const MeanValueCoordinates mvc(element);
    vtkNew<vtkPoints> points;
    for (const Vec3& p : element.nodes()) points->InsertNextPoint(p.x(), p.y(), p.z());
    vtkNew<vtkIdList> triangles;
    for (const auto& t : element.triangles())
      for (int v : t) triangles->InsertNextId(v);
    Eigen::VectorXd lambda, reference(element.numNodes());
    Eigen::Matrix<double, Eigen::Dynamic, 3> grad;
    double worst = 0.0;
    for (const Vec3& x : randomInteriorPoints(element, 100, 23)) {
      mvc.evaluate(x, lambda, grad);
      vtkMeanValueCoordinatesInterpolator::ComputeInterpolationWeights(x.data(), points, triangles,
                                                                       reference.data());
      worst = std::max(worst, (lambda - reference).cwiseAbs().maxCoeff());
      if (element.isTetrahedron()) {
        Eigen::Matrix4d system;
        for (int i = 0; i < 4; ++i) system.col(i) << element.node(i), 1.0;
        const Eigen::Vector4d exact = system.inverse() * Eigen::Vector4d(x.x(), x.y(), x.z(), 1.0);
        worst_vtk_tet = std::max(worst_vtk_tet, (reference - exact).cwiseAbs().maxCoeff());
        worst_ours_tet = std::max(worst_ours_tet, (lambda - exact).cwiseAbs().maxCoeff());
      }
    }
    std::printf("[ stats    ] %-12s vs vtkMeanValueCoordinatesInterpolator %.1e\n", name.c_str(), worst);
    // VTK's acos-based evaluation loses digits near nodes: on the tetrahedron its own distance to the exact
    // barycentric coordinates is of the same size as the difference (ours is at rounding there).
    EXPECT_LT(worst, 1e-5) << name;
  }
  std::printf("[ stats    ] tetrahedron: VTK vs exact barycentric %.1e, ours %.1e\n", worst_vtk_tet,
              worst_ours_tet);
  EXPECT_LT(worst_ours_tet, 1e-14);
  EXPECT_LT(worst_ours_tet, worst_vtk_tet);
#else
  GTEST_SKIP() << "VTK not linked (configure with RC_HAVE_VTK and VTK::CommonDataModel to compare)";
#endif
}

}  // namespace
}  // namespace rc
