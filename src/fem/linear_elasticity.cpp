#include "fem/linear_elasticity.h"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace rc {

LinearElasticModel::LinearElasticModel(PolyhedralMesh mesh, double youngs_modulus, double poisson_ratio,
                                       double density, const ElementQuadratureOptions& quadrature_options)
    : mesh_(std::move(mesh)), elasticity_(isotropicElasticity(youngs_modulus, poisson_ratio)) {
  if (!(density > 0.0) || !std::isfinite(density))
    throw std::invalid_argument("LinearElasticModel: density must be positive and finite, got " +
                                std::to_string(density));
  const int num_elements = mesh_.numElements();
  quadratures_.resize(num_elements);
  element_stiffness_.resize(num_elements);
#pragma omp parallel for schedule(dynamic, 16)
  for (int e = 0; e < num_elements; ++e) {
    quadratures_[e] = elementQuadrature(mesh_.element(e), quadrature_options);
    element_stiffness_[e] = rc::elementStiffness(quadratures_[e], elasticity_);
  }

  std::vector<Eigen::Triplet<double>> triplets;
  lumped_masses_ = Eigen::VectorXd::Zero(mesh_.numNodes());
  for (int e = 0; e < num_elements; ++e) {
    const auto& ids = mesh_.element(e).globalNodeIds();
    const Eigen::MatrixXd& k = element_stiffness_[e];
    const int n = static_cast<int>(ids.size());
    for (int a = 0; a < n; ++a) {
      lumped_masses_[ids[a]] += quadratures_[e].node_volume_fractions[a] * quadratures_[e].volume * density;
      for (int b = 0; b < n; ++b)
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            triplets.emplace_back(3 * ids[a] + r, 3 * ids[b] + c, k(3 * a + r, 3 * b + c));
    }
  }
  stiffness_.resize(numDofs(), numDofs());
  stiffness_.setFromTriplets(triplets.begin(), triplets.end());
}

Eigen::VectorXd LinearElasticModel::solveStatic(
    const Eigen::VectorXd& forces, const std::vector<DisplacementConstraint>& constraints) const {
  const int dofs = numDofs();
  if (forces.size() != dofs)
    throw std::invalid_argument("solveStatic: forces has " + std::to_string(forces.size()) + " entries for " +
                                std::to_string(dofs) + " dofs");
  Eigen::VectorXd u = Eigen::VectorXd::Zero(dofs);
  std::vector<char> fixed(mesh_.numNodes(), 0);
  for (const DisplacementConstraint& c : constraints) {
    if (c.node < 0 || c.node >= mesh_.numNodes())
      throw std::invalid_argument("solveStatic: constraint on node " + std::to_string(c.node) +
                                  " (mesh has " + std::to_string(mesh_.numNodes()) + " nodes)");
    if (fixed[c.node])
      throw std::invalid_argument("solveStatic: node " + std::to_string(c.node) + " constrained twice");
    if (!c.displacement.allFinite())
      throw std::invalid_argument("solveStatic: constraint on node " + std::to_string(c.node) +
                                  " is not finite");
    fixed[c.node] = 1;
    u.segment<3>(3 * c.node) = c.displacement;
  }
  std::vector<int> free_index(dofs, -1);
  int num_free = 0;
  for (int d = 0; d < dofs; ++d)
    if (!fixed[d / 3]) free_index[d] = num_free++;
  if (num_free == 0) return u;

  // K_ff u_f = f_f - K_fc u_c.
  Eigen::VectorXd rhs(num_free);
  for (int d = 0; d < dofs; ++d)
    if (free_index[d] >= 0) rhs[free_index[d]] = forces[d];
  std::vector<Eigen::Triplet<double>> triplets;
  for (int col = 0; col < stiffness_.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(stiffness_, col); it; ++it) {
      const int r = free_index[it.row()], c = free_index[it.col()];
      if (r < 0) continue;
      if (c >= 0)
        triplets.emplace_back(r, c, it.value());
      else
        rhs[r] -= it.value() * u[it.col()];
    }
  Eigen::SparseMatrix<double> k_free(num_free, num_free);
  k_free.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(k_free);
  const Eigen::VectorXd pivots = solver.info() == Eigen::Success ? solver.vectorD() : Eigen::VectorXd();
  if (pivots.size() == 0 || !(pivots.minCoeff() > 1e-12 * pivots.cwiseAbs().maxCoeff()))
    throw std::runtime_error(
        "solveStatic: the stiffness of the free dofs is singular (constraints do not remove all rigid "
        "motions)");
  const Eigen::VectorXd u_free = solver.solve(rhs);
  for (int d = 0; d < dofs; ++d)
    if (free_index[d] >= 0) u[d] = u_free[free_index[d]];
  return u;
}

std::vector<Vector6d> LinearElasticModel::elementStresses(int e, const Eigen::VectorXd& displacements) const {
  if (e < 0 || e >= mesh_.numElements())
    throw std::invalid_argument("elementStresses: element " + std::to_string(e) + " out of range");
  if (displacements.size() != numDofs())
    throw std::invalid_argument("elementStresses: displacements has " + std::to_string(displacements.size()) +
                                " entries for " + std::to_string(numDofs()) + " dofs");
  const auto& ids = mesh_.element(e).globalNodeIds();
  Eigen::VectorXd u_e(3 * ids.size());
  for (size_t a = 0; a < ids.size(); ++a) u_e.segment<3>(3 * a) = displacements.segment<3>(3 * ids[a]);
  std::vector<Vector6d> stresses;
  for (const NodeGradients& g : quadratures_[e].gradients)
    stresses.push_back(elasticity_ * (strainDisplacement(g) * u_e));
  return stresses;
}

Eigen::VectorXd LinearElasticModel::tractionLoads(const std::vector<PolyhedralMesh::Triangle>& triangles,
                                                  const Vec3& traction) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(numDofs());
  for (const auto& t : triangles) {
    for (int v : t)
      if (v < 0 || v >= mesh_.numNodes())
        throw std::invalid_argument("tractionLoads: triangle node " + std::to_string(v) + " out of range");
    const double area =
        0.5 * (mesh_.node(t[1]) - mesh_.node(t[0])).cross(mesh_.node(t[2]) - mesh_.node(t[0])).norm();
    for (int v : t) f.segment<3>(3 * v) += traction * (area / 3.0);
  }
  return f;
}

}  // namespace rc
