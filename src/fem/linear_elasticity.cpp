#include "relaxed_connectivity/fem/linear_elasticity.h"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

namespace rc {

namespace {

std::uint64_t mixHash(std::uint64_t h, std::uint64_t v) {
  v *= 0xff51afd7ed558ccdULL;
  v ^= v >> 33;
  h ^= v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
  return h;
}

std::uint64_t doubleBits(double x) {
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  return bits;
}

bool sameOptions(const ElementQuadratureOptions& a, const ElementQuadratureOptions& b) {
  return a.vertex_sample_blend == b.vertex_sample_blend && a.face_sample_blend == b.face_sample_blend &&
         a.exact_gradient_correction == b.exact_gradient_correction &&
         a.tetrahedron_shortcut == b.tetrahedron_shortcut;
}

// Below this many elements the loops run serially (thread start-up dominates).
constexpr int kParallelElements = 512;

}  // namespace

std::uint64_t elementGeometryHash(const ConvexPolyhedron& element) {
  std::uint64_t h = static_cast<std::uint64_t>(element.numNodes());
  for (const Vec3& x : element.nodes())
    for (int k = 0; k < 3; ++k) h = mixHash(h, doubleBits(x[k]));
  for (const auto& face : element.faces()) {
    h = mixHash(h, face.size());
    for (int v : face) h = mixHash(h, static_cast<std::uint64_t>(v));
  }
  for (int t = 0; t < element.numTriangles(); ++t) {
    const auto& tri = element.triangles()[t];
    h = mixHash(h, static_cast<std::uint64_t>(tri[0]) | static_cast<std::uint64_t>(tri[1]) << 16 |
                       static_cast<std::uint64_t>(tri[2]) << 32 |
                       static_cast<std::uint64_t>(element.triangleFace()[t]) << 48);
  }
  return h;
}

bool sameElementGeometry(const ConvexPolyhedron& a, const ConvexPolyhedron& b) {
  auto sameBits = [](const Vec3& x, const Vec3& y) {
    return doubleBits(x[0]) == doubleBits(y[0]) && doubleBits(x[1]) == doubleBits(y[1]) &&
           doubleBits(x[2]) == doubleBits(y[2]);
  };
  if (a.numNodes() != b.numNodes() || a.numFaces() != b.numFaces()) return false;
  for (int i = 0; i < a.numNodes(); ++i)
    if (!sameBits(a.node(i), b.node(i))) return false;
  if (a.faces() != b.faces() || a.triangles() != b.triangles() || a.triangleFace() != b.triangleFace())
    return false;
  // Derived data read by the quadrature (the same function of the above; checked for safety).
  if (doubleBits(a.volume()) != doubleBits(b.volume()) || !sameBits(a.centroid(), b.centroid()) ||
      doubleBits(a.scale()) != doubleBits(b.scale()))
    return false;
  for (int f = 0; f < a.numFaces(); ++f)
    if (!sameBits(a.faceNormal(f), b.faceNormal(f)) ||
        doubleBits(a.faceOffset(f)) != doubleBits(b.faceOffset(f)))
      return false;
  return true;
}

LinearElasticModel::LinearElasticModel(PolyhedralMesh mesh, double youngs_modulus, double poisson_ratio,
                                       double density, const ElementQuadratureOptions& quadrature_options)
    : LinearElasticModel(std::move(mesh), youngs_modulus, poisson_ratio, density, quadrature_options,
                         nullptr) {}

LinearElasticModel::LinearElasticModel(PolyhedralMesh mesh, double youngs_modulus, double poisson_ratio,
                                       double density, const ElementQuadratureOptions& quadrature_options,
                                       const LinearElasticModel* donor)
    : mesh_(std::move(mesh)),
      elasticity_(isotropicElasticity(youngs_modulus, poisson_ratio)),
      quadrature_options_(quadrature_options) {
  if (!(density > 0.0) || !std::isfinite(density))
    throw std::invalid_argument("LinearElasticModel: density must be positive and finite, got " +
                                std::to_string(density));
  build(density, donor);
}

void LinearElasticModel::build(double density, const LinearElasticModel* donor) {
  const int num_elements = mesh_.numElements();
  integration_.assign(num_elements, nullptr);

  // Elements the cut left unchanged: shared with the donor.
  if (donor && donor->elasticity_ == elasticity_ &&
      sameOptions(donor->quadrature_options_, quadrature_options_)) {
    const int num_donor = donor->mesh_.numElements();
    std::vector<std::uint64_t> donor_hash(num_donor), hash(num_elements);
#pragma omp parallel for schedule(static) if (num_donor >= kParallelElements)
    for (int d = 0; d < num_donor; ++d) donor_hash[d] = elementGeometryHash(donor->mesh_.element(d));
#pragma omp parallel for schedule(static) if (num_elements >= kParallelElements)
    for (int e = 0; e < num_elements; ++e) hash[e] = elementGeometryHash(mesh_.element(e));
    std::unordered_multimap<std::uint64_t, int> by_hash;
    by_hash.reserve(num_donor);
    for (int d = 0; d < num_donor; ++d) by_hash.emplace(donor_hash[d], d);
    for (int e = 0; e < num_elements; ++e) {
      const auto range = by_hash.equal_range(hash[e]);
      for (auto it = range.first; it != range.second; ++it)
        if (sameElementGeometry(mesh_.element(e), donor->mesh_.element(it->second))) {
          integration_[e] = donor->integration_[it->second];
          break;
        }
    }
  }
  int recomputed = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : recomputed) if (num_elements >= kParallelElements)
  for (int e = 0; e < num_elements; ++e) {
    if (integration_[e]) continue;
    auto data = std::make_shared<ElementIntegration>();
    data->quadrature = elementQuadrature(mesh_.element(e), quadrature_options_);
    data->stiffness = rc::elementStiffness(data->quadrature, elasticity_);
    integration_[e] = std::move(data);
    ++recomputed;
  }
  num_recomputed_ = recomputed;

  // Lumped masses (9.21).
  const int num_nodes = mesh_.numNodes();
  lumped_masses_ = Eigen::VectorXd::Zero(num_nodes);
  for (int e = 0; e < num_elements; ++e) {
    const auto& ids = mesh_.element(e).globalNodeIds();
    const ElementQuadrature& q = integration_[e]->quadrature;
    for (size_t a = 0; a < ids.size(); ++a)
      lumped_masses_[ids[a]] += q.node_volume_fractions[a] * q.volume * density;
  }

  // Pattern: node j's neighbours (nodes sharing an element, sorted), dense 3 x 3 blocks.
  std::vector<int> neighbour_start(num_nodes + 1, 0);
  for (int e = 0; e < num_elements; ++e)
    for (int j : mesh_.element(e).globalNodeIds()) neighbour_start[j + 1] += mesh_.element(e).numNodes();
  for (int j = 0; j < num_nodes; ++j) neighbour_start[j + 1] += neighbour_start[j];
  std::vector<int> neighbours(neighbour_start[num_nodes]),
      fill(neighbour_start.begin(), neighbour_start.end() - 1);
  for (int e = 0; e < num_elements; ++e) {
    const auto& ids = mesh_.element(e).globalNodeIds();
    for (int j : ids)
      for (int i : ids) neighbours[fill[j]++] = i;
  }
  std::vector<int> degree(num_nodes);
  for (int j = 0; j < num_nodes; ++j) {
    int* begin = neighbours.data() + neighbour_start[j];
    int* end = neighbours.data() + neighbour_start[j + 1];
    std::sort(begin, end);
    degree[j] = static_cast<int>(std::unique(begin, end) - begin);
  }
  const int dofs = numDofs();
  column_length_.resize(num_nodes);
  std::vector<int> node_value_start(num_nodes + 1, 0);
  for (int j = 0; j < num_nodes; ++j) {
    column_length_[j] = 3 * degree[j];
    node_value_start[j + 1] = node_value_start[j] + 9 * degree[j];
  }
  const int nnz = node_value_start[num_nodes];
  stiffness_ = Eigen::SparseMatrix<double>(dofs, dofs);
  stiffness_.resizeNonZeros(nnz);
  int* outer = stiffness_.outerIndexPtr();
  int* inner = stiffness_.innerIndexPtr();
  double* values = stiffness_.valuePtr();
  for (int j = 0; j < num_nodes; ++j)
    for (int c = 0; c < 3; ++c) {
      int k = outer[3 * j + c] = node_value_start[j] + c * column_length_[j];
      for (int p = 0; p < degree[j]; ++p)
        for (int r = 0; r < 3; ++r) inner[k++] = 3 * neighbours[neighbour_start[j] + p] + r;
    }
  outer[dofs] = nnz;
  std::fill(values, values + nnz, 0.0);

  // Block value indices and K (9.16).
  block_offset_.resize(num_elements + 1);
  block_offset_[0] = 0;
  for (int e = 0; e < num_elements; ++e) {
    const int n = mesh_.element(e).numNodes();
    block_offset_[e + 1] = block_offset_[e] + n * n;
  }
  block_index_.resize(block_offset_[num_elements]);
  for (int e = 0; e < num_elements; ++e) {
    const auto& ids = mesh_.element(e).globalNodeIds();
    const int n = static_cast<int>(ids.size());
    const Eigen::MatrixXd& k = integration_[e]->stiffness;
    int* index = block_index_.data() + block_offset_[e];
    for (int b = 0; b < n; ++b) {
      const int j = ids[b];
      const int* begin = neighbours.data() + neighbour_start[j];
      for (int a = 0; a < n; ++a) {
        const int p = static_cast<int>(std::lower_bound(begin, begin + degree[j], ids[a]) - begin);
        const int base = index[b * n + a] = node_value_start[j] + 3 * p;
        for (int c = 0; c < 3; ++c)
          for (int r = 0; r < 3; ++r) values[base + c * column_length_[j] + r] += k(3 * a + r, 3 * b + c);
      }
    }
  }
}

Eigen::VectorXd LinearElasticModel::solveStatic(
    const Eigen::VectorXd& forces, const std::vector<DisplacementConstraint>& constraints) const {
  const int dofs = numDofs();
  if (forces.size() != dofs)
    throw std::invalid_argument("solveStatic: forces has " + std::to_string(forces.size()) + " entries for " +
                                std::to_string(dofs) + " dofs");
  Eigen::VectorXd u = Eigen::VectorXd::Zero(dofs);
  std::vector<char> fixed(dofs, 0);
  for (const DisplacementConstraint& c : constraints) {
    if (c.node < 0 || c.node >= mesh_.numNodes())
      throw std::invalid_argument("solveStatic: constraint on node " + std::to_string(c.node) +
                                  " (mesh has " + std::to_string(mesh_.numNodes()) + " nodes)");
    for (int k = 0; k < 3; ++k) {
      if (!c.held[k]) continue;
      if (fixed[3 * c.node + k])
        throw std::invalid_argument("solveStatic: component " + std::string(1, char('x' + k)) + " of node " +
                                    std::to_string(c.node) + " constrained twice");
      if (!std::isfinite(c.displacement[k]))
        throw std::invalid_argument("solveStatic: constraint on node " + std::to_string(c.node) +
                                    " is not finite");
      fixed[3 * c.node + k] = 1;
      u[3 * c.node + k] = c.displacement[k];
    }
  }
  std::vector<int> free_index(dofs, -1);
  int num_free = 0;
  for (int d = 0; d < dofs; ++d)
    if (!fixed[d]) free_index[d] = num_free++;
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

Eigen::VectorXd LinearElasticModel::reactions(const Eigen::VectorXd& displacements,
                                              const Eigen::VectorXd& forces) const {
  if (displacements.size() != numDofs() || forces.size() != numDofs())
    throw std::invalid_argument("reactions: displacements and forces need " + std::to_string(numDofs()) +
                                " entries");
  return stiffness_ * displacements - forces;
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
  for (const NodeGradients& g : quadrature(e).gradients)
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
