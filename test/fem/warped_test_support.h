// Test support for the stiffness-warped system (warped_dynamics.h): random rotations and reference sums built
// element by element from the model's element matrices, for tests of the in-place assembly.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>

#include <functional>
#include <random>
#include <vector>

#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace rc {

/// Uniformly random rotation (normalised Gaussian quaternion).
inline Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  return q.normalized().toRotationMatrix();
}

struct WarpedElementSums {
  std::vector<Eigen::Triplet<double>> stiffness;  ///< entries of K_w = sum_e R_e K_e R_e^T
  Eigen::VectorXd forces;                         ///< f_int = -sum_e R_e K_e u_e
};

/// Element rest and current coordinates (3n each) and lumped-mass registration weights (n).
using ElementVisitor = std::function<void(int element, const Eigen::VectorXd& rest,
                                          const Eigen::VectorXd& current, const Eigen::VectorXd& weights)>;

/// The sums at positions x with the body's current rotations R_e; u_e from the lumped-mass centroids.
inline WarpedElementSums warpedElementSums(const LinearElasticModel& model, const WarpedDynamics& sim,
                                           const Eigen::VectorXd& x, const ElementVisitor& visit = {}) {
  WarpedElementSums sums;
  sums.forces = Eigen::VectorXd::Zero(sim.numDofs());
  for (int e = 0; e < model.mesh().numElements(); ++e) {
    const auto& ids = model.mesh().element(e).globalNodeIds();
    const int n = static_cast<int>(ids.size());
    const Eigen::Matrix3d& r = sim.rotations()[e];
    Eigen::MatrixXd rotation = Eigen::MatrixXd::Zero(3 * n, 3 * n);
    Eigen::VectorXd rest(3 * n), current(3 * n), weights(n);
    for (int a = 0; a < n; ++a) {
      rotation.block<3, 3>(3 * a, 3 * a) = r;
      rest.segment<3>(3 * a) = sim.restPositions().segment<3>(3 * ids[a]);
      current.segment<3>(3 * a) = x.segment<3>(3 * ids[a]);
      weights[a] = model.lumpedMasses()[ids[a]];
    }
    if (visit) visit(e, rest, current, weights);
    Vec3 rest_centroid = Vec3::Zero(), current_centroid = Vec3::Zero();
    for (int a = 0; a < n; ++a) {
      rest_centroid += weights[a] * rest.segment<3>(3 * a);
      current_centroid += weights[a] * current.segment<3>(3 * a);
    }
    rest_centroid /= weights.sum();
    current_centroid /= weights.sum();
    Eigen::VectorXd u(3 * n);
    for (int a = 0; a < n; ++a)
      u.segment<3>(3 * a) = r.transpose() * (current.segment<3>(3 * a) - current_centroid) -
                            (rest.segment<3>(3 * a) - rest_centroid);
    const Eigen::MatrixXd rk = rotation * model.elementStiffness(e) * rotation.transpose();
    const Eigen::VectorXd fe = -rotation * (model.elementStiffness(e) * u);
    for (int a = 0; a < n; ++a) {
      sums.forces.segment<3>(3 * ids[a]) += fe.segment<3>(3 * a);
      for (int b = 0; b < n; ++b)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            sums.stiffness.emplace_back(3 * ids[a] + i, 3 * ids[b] + j, rk(3 * a + i, 3 * b + j));
    }
  }
  return sums;
}

}  // namespace rc
