// Shape function benchmark (thesis 9.1.1): time per evaluation of mean value coordinates (values, and values
// + analytic gradients) on a tetrahedron, a cube and 12/36-node convex polyhedra; single thread, median of 9
// runs over 4000 interior points. Prints a markdown table. `--quick`: 3 runs over 1000 points.
#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "relaxed_connectivity/fem/convex_polyhedron.h"
#include "relaxed_connectivity/fem/mean_value_coordinates.h"

namespace {

using rc::ConvexPolyhedron;
using rc::MeanValueCoordinates;
using rc::Vec3;

std::vector<Vec3> pointsOnEllipsoid(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<Vec3> points;
  while (static_cast<int>(points.size()) < n) {
    Vec3 p(normal(rng), normal(rng), normal(rng));
    if (p.norm() < 1e-3) continue;
    p.normalize();
    points.emplace_back(1.5 * p.x(), p.y(), 0.7 * p.z());
  }
  return points;
}

std::vector<Vec3> interiorPoints(const ConvexPolyhedron& e, int count, unsigned seed) {
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
    points.push_back(p / total);
  }
  return points;
}

// Median over runs of the time per evaluation in nanoseconds.
double nanosecondsPerEvaluation(const MeanValueCoordinates& mvc, const std::vector<Vec3>& points,
                                bool gradients, int runs, double* checksum) {
  std::vector<double> lambda(mvc.numNodes());
  std::vector<Vec3> grad(mvc.numNodes());
  std::vector<double> times;
  for (int r = 0; r < runs; ++r) {
    const auto start = std::chrono::steady_clock::now();
    for (const Vec3& x : points) {
      mvc.evaluate(x, lambda.data(), gradients ? grad.data() : nullptr);
      *checksum += lambda[0] + (gradients ? grad[0].x() : 0.0);
    }
    const auto stop = std::chrono::steady_clock::now();
    times.push_back(std::chrono::duration<double, std::nano>(stop - start).count() / points.size());
  }
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  return times[times.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int runs = quick ? 3 : 9, count = quick ? 1000 : 4000;

  struct Case {
    std::string name;
    ConvexPolyhedron element;
    bool shortcut;
  };
  const ConvexPolyhedron tet =
      ConvexPolyhedron::tetrahedron(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.2, 1, 0), Vec3(0.3, 0.3, 1));
  const ConvexPolyhedron cube =
      ConvexPolyhedron::hexahedron({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0), Vec3(0, 0, 1),
                                    Vec3(1, 0, 1), Vec3(1, 1, 1), Vec3(0, 1, 1)});
  std::vector<Case> cases{
      {"tetrahedron (linear)", tet, true},
      {"tetrahedron (MVC)", tet, false},
      {"cube", cube, false},
      {"hull of 12 points", ConvexPolyhedron::convexHull(pointsOnEllipsoid(12, 7)), false},
      {"hull of 36 points", ConvexPolyhedron::convexHull(pointsOnEllipsoid(36, 11)), false}};

  double checksum = 0.0;
  std::printf("Mean value shape functions, one thread, median of %d runs over %d interior points\n\n", runs,
              count);
  std::printf(
      "| element | nodes | triangles | values [ns] | values + gradients [ns] | per triangle [ns] |\n");
  std::printf("|---|---:|---:|---:|---:|---:|\n");
  for (const Case& c : cases) {
    MeanValueCoordinates::Options options;
    options.tetrahedron_shortcut = c.shortcut;
    const MeanValueCoordinates mvc(c.element, options);
    const std::vector<Vec3> points = interiorPoints(c.element, count, 3);
    const double values = nanosecondsPerEvaluation(mvc, points, false, runs, &checksum);
    const double both = nanosecondsPerEvaluation(mvc, points, true, runs, &checksum);
    std::printf("| %s | %d | %d | %.0f | %.0f | %.0f |\n", c.name.c_str(), c.element.numNodes(),
                c.element.numTriangles(), values, both, c.shortcut ? 0.0 : both / c.element.numTriangles());
  }
  std::printf("\n(checksum %.6g)\n", checksum);
  return 0;
}
