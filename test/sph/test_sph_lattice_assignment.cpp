// The lattice assignment (8.21) against a brute-force reference: every neighbour takes its nearest lattice
// point of the transformed lattice, one particle per point (the closest; ties: the lower index), the centre's
// own point taken by nobody. Covers the stamped keeper table (reused across calls) and the hash table of far
// points.
#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"

namespace rc {
namespace {

void bruteForce(const SphLattice& lattice, const Eigen::Matrix3d& transform, const std::vector<Vec3>& offsets,
                std::vector<Eigen::Vector3i>& indices, std::vector<uint8_t>& assigned) {
  const size_t n = offsets.size();
  const Eigen::Matrix3d to_coordinates = lattice.inverseBasis() * transform.inverse();
  indices.resize(n);
  std::vector<double> d2(n);
  for (size_t k = 0; k < n; ++k)
    indices[k] = lattice.nearestIndexOfCoordinates(to_coordinates * offsets[k], &d2[k]);
  assigned.assign(n, 1);
  for (size_t k = 0; k < n; ++k) {
    if (indices[k].isZero()) assigned[k] = 0;
    for (size_t o = 0; o < n; ++o)
      if (o != k && indices[o] == indices[k] && (d2[o] < d2[k] || (d2[o] == d2[k] && o < k))) assigned[k] = 0;
  }
}

void compareRandom(int dimension, double stretch, int trials, size_t* far_calls) {
  const SphLattice lattice(dimension, 0.05);
  std::mt19937_64 rng(dimension * 100 + int(stretch * 10));
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  SphLatticeAssignment out;  // reused: the stamps must separate the calls
  std::vector<Eigen::Vector3i> indices;
  std::vector<uint8_t> assigned;
  for (int t = 0; t < trials; ++t) {
    Eigen::Matrix3d transform = Eigen::Matrix3d::Identity();
    Eigen::Vector3d axis(dimension == 3 ? uni(rng) : 0.0, dimension == 3 ? uni(rng) : 0.0, 1.0);
    transform = Eigen::AngleAxisd(3.0 * uni(rng), axis.normalized()).toRotationMatrix();
    transform(0, 0) *= 1.0 + 0.3 * uni(rng);
    transform(1, 1) *= 1.0 + 0.3 * uni(rng);
    transform /= stretch;  // a compressed lattice: many points per neighbourhood, far indices
    const size_t n = 20 + rng() % 60;
    std::vector<Vec3> offsets(n);
    for (Vec3& r : offsets) r = 0.1 * Vec3(uni(rng), uni(rng), dimension == 3 ? uni(rng) : 0.0);
    if (t % 3 == 0) offsets[n / 2] = offsets[n / 3];  // an exact tie
    assignLatticePoints(lattice, transform, offsets, out);
    bruteForce(lattice, transform, offsets, indices, assigned);
    bool far = false;
    for (size_t k = 0; k < n; ++k) {
      ASSERT_EQ(out.indices[k], indices[k]) << "trial " << t << " neighbour " << k;
      ASSERT_EQ(out.assigned[k], assigned[k]) << "trial " << t << " neighbour " << k;
      far = far || indices[k].cwiseAbs().maxCoeff() >= SphLatticeAssignment::kTableHalfWidth;
    }
    *far_calls += far;
  }
}

TEST(SphLatticeAssignment, MatchesBruteForceNearAndFar) {
  size_t far_3d = 0, far_2d = 0, near_3d = 0;
  compareRandom(3, 1.0, 300, &near_3d);
  compareRandom(3, 4.0, 300, &far_3d);
  compareRandom(2, 4.0, 300, &far_2d);
  EXPECT_EQ(near_3d, 0u);  // offsets of 0.1 = 2 d: all in the table
  EXPECT_GT(far_3d, 50u);  // the hash table path is exercised
  EXPECT_GT(far_2d, 50u);
}

}  // namespace
}  // namespace rc
