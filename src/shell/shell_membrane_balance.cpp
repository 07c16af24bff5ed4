#include "relaxed_connectivity/shell/shell_membrane_balance.h"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace rc {
namespace {

// Tangential force columns: per fiber, the force it puts on each node under a uniform stretch (common factor
// 2 K_s (sigma^2 - 1) sigma dropped), at factor c = 1.
struct ForceColumns {
  std::vector<size_t> offsets;                   // fibers + 1
  std::vector<std::pair<uint32_t, Vec3>> force;  // (node, force)
};

// Interior nodes (row index >= 0) with a tangent basis; -1 for boundary nodes.
struct TangentRows {
  std::vector<long> row;
  std::vector<std::array<Vec3, 2>> basis;
  size_t count = 0;
};

TangentRows interiorRows(const ShellNodes& nodes, double boundary_gap) {
  TangentRows rows;
  rows.row.assign(nodes.size(), -1);
  rows.basis.resize(nodes.size());
  std::vector<double> angles;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Vec3 n = nodes.rest_normals[i].normalized();
    const Vec3 t1 = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
    const Vec3 t2 = n.cross(t1);
    rows.basis[i] = {t1, t2};
    angles.clear();
    const uint32_t* nb = nodes.neighborsOf(i);
    for (size_t m = 0; m < nodes.neighborCount(i); ++m) {
      const Vec3 d = nodes.rest_positions[nb[m]] - nodes.rest_positions[i];
      angles.push_back(std::atan2(d.dot(t2), d.dot(t1)));
    }
    if (angles.size() < 3) continue;
    std::sort(angles.begin(), angles.end());
    double gap = angles.front() + 2.0 * M_PI - angles.back();
    for (size_t m = 1; m < angles.size(); ++m) gap = std::max(gap, angles[m] - angles[m - 1]);
    if (gap > boundary_gap) continue;
    rows.row[i] = static_cast<long>(rows.count++);
  }
  return rows;
}

// Force columns of every fiber at the rest positions, scaled by its current stretch factor:
// fiber m at node i (weight w_m, rest length l_m, Voronoi area a_i) pulls with
// a_i w_m s_m [grad l_m / l_m + (1 / s0_i) sum_k w_k l_k grad l_k], s0_i = sum_k w_k l_k^2 (7.5-7.7).
ForceColumns forceColumns(const ShellNodes& nodes, const ShellFibers& fibers) {
  ForceColumns cols;
  cols.offsets.assign(1, 0);
  const std::vector<Vec3>& x = nodes.rest_positions;
  std::vector<std::array<Vec3, 3>> grad;
  std::vector<std::pair<uint32_t, Vec3>> aggregate;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const size_t f0 = fibers.node_offsets[i], f1 = fibers.node_offsets[i + 1];
    grad.resize(f1 - f0);
    aggregate.clear();
    double s0 = 0.0;
    for (size_t q = f0; q < f1; ++q) {
      const Fiber& f = fibers.fibers[q];
      fiberArcLength(x[f.end1], x[i], x[f.end2], &grad[q - f0]);
      s0 += f.weight * f.rest_length * f.rest_length;
      const double c = f.weight * f.rest_length;
      aggregate.emplace_back(f.end1, c * grad[q - f0][0]);
      aggregate.emplace_back(static_cast<uint32_t>(i), c * grad[q - f0][1]);
      aggregate.emplace_back(f.end2, c * grad[q - f0][2]);
    }
    for (size_t q = f0; q < f1; ++q) {
      const Fiber& f = fibers.fibers[q];
      const double scale = nodes.rest_areas[i] * f.weight * f.stretch_scale;
      const double own = scale / f.rest_length;
      cols.force.emplace_back(f.end1, own * grad[q - f0][0]);
      cols.force.emplace_back(static_cast<uint32_t>(i), own * grad[q - f0][1]);
      cols.force.emplace_back(f.end2, own * grad[q - f0][2]);
      if (s0 > 0.0)
        for (const auto& a : aggregate) cols.force.emplace_back(a.first, (scale / s0) * a.second);
      cols.offsets.push_back(cols.force.size());
    }
  }
  return cols;
}

Eigen::SparseMatrix<double> tangentialMatrix(const ForceColumns& cols, const TangentRows& rows) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(2 * cols.force.size());
  const size_t m = cols.offsets.size() - 1;
  for (size_t q = 0; q < m; ++q) {
    for (size_t e = cols.offsets[q]; e < cols.offsets[q + 1]; ++e) {
      const auto& [node, f] = cols.force[e];
      const long r = rows.row[node];
      if (r < 0) continue;
      t.emplace_back(2 * r, q, rows.basis[node][0].dot(f));
      t.emplace_back(2 * r + 1, q, rows.basis[node][1].dot(f));
    }
  }
  Eigen::SparseMatrix<double> a(2 * rows.count, m);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

// |tangential force| / (sum of the individual fiber force magnitudes), RMS over the constrained nodes.
double relativeImbalance(const ForceColumns& cols, const TangentRows& rows, const Eigen::VectorXd& c) {
  std::vector<Vec3> net(rows.row.size(), Vec3::Zero());
  std::vector<double> scale(rows.row.size(), 0.0);
  for (size_t q = 0; q + 1 < cols.offsets.size(); ++q) {
    for (size_t e = cols.offsets[q]; e < cols.offsets[q + 1]; ++e) {
      net[cols.force[e].first] += c[q] * cols.force[e].second;
      scale[cols.force[e].first] += std::abs(c[q]) * cols.force[e].second.norm();
    }
  }
  double num = 0.0, den = 0.0;
  for (size_t j = 0; j < rows.row.size(); ++j) {
    if (rows.row[j] < 0) continue;
    const std::array<Vec3, 2>& b = rows.basis[j];
    num += std::pow(b[0].dot(net[j]), 2) + std::pow(b[1].dot(net[j]), 2);
    den += scale[j] * scale[j];
  }
  return den > 0.0 ? std::sqrt(num / den) : 0.0;
}

void checkInputs(const ShellNodes& nodes, const ShellFibers& fibers, const ShellMembraneBalanceOptions& o) {
  if (fibers.node_offsets.size() != nodes.size() + 1)
    throw std::invalid_argument("balanceMembraneStiffness: the fibers were built for another node set");
  if (!(o.min_factor > 0.0) || !(o.max_factor >= o.min_factor) || !(o.min_factor <= 1.0) ||
      !(o.max_factor >= 1.0) || !(o.boundary_gap > 0.0) || o.iterations < 1 || !(o.step_penalty > 0.0))
    throw std::invalid_argument(
        "ShellMembraneBalanceOptions: need 0 < min_factor <= 1 <= max_factor, boundary_gap > 0, "
        "iterations >= 1, step_penalty > 0");
}

}  // namespace

double membraneImbalance(const ShellNodes& nodes, const ShellFibers& fibers,
                         const ShellMembraneBalanceOptions& options) {
  checkInputs(nodes, fibers, options);
  const TangentRows rows = interiorRows(nodes, options.boundary_gap);
  return relativeImbalance(forceColumns(nodes, fibers), rows, Eigen::VectorXd::Ones(fibers.size()));
}

ShellMembraneBalanceReport balanceMembraneStiffness(const ShellNodes& nodes, ShellFibers& fibers,
                                                    const ShellMembraneBalanceOptions& options) {
  checkInputs(nodes, fibers, options);
  ShellMembraneBalanceReport report;
  const TangentRows rows = interiorRows(nodes, options.boundary_gap);
  report.constrained_nodes = rows.count;
  const ForceColumns cols = forceColumns(nodes, fibers);
  const size_t m = fibers.size();
  Eigen::VectorXd c = Eigen::VectorXd::Ones(m);
  report.residual_before = relativeImbalance(cols, rows, c);
  if (rows.count == 0 || m == 0) return report;

  const Eigen::SparseMatrix<double> f = tangentialMatrix(cols, rows);
  // Proximal iterations: c += F_free^T y with (F_free F_free^T + mu I) y = -F c, i.e. the least change of
  // the free factors that reduces |F c| with a step penalty mu (converges to the least-change balance;
  // mu keeps each step bounded where the constraints are nearly dependent). Factors leaving the bounds are
  // clamped and fixed, and the matrix is factorised again.
  std::vector<char> fixed(m, 0);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  Eigen::SparseMatrix<double> f_free;
  bool factorised = false;
  for (int it = 0; it < options.iterations; ++it) {
    if (!factorised) {
      Eigen::VectorXd free_mask(m);
      for (size_t q = 0; q < m; ++q) free_mask[q] = fixed[q] ? 0.0 : 1.0;
      f_free = f * free_mask.asDiagonal();
      Eigen::SparseMatrix<double> normal = f_free * f_free.transpose();
      double mean_diag = 0.0;
      for (Eigen::Index k = 0; k < normal.rows(); ++k) mean_diag += normal.coeff(k, k);
      mean_diag /= std::max<Eigen::Index>(1, normal.rows());
      Eigen::SparseMatrix<double> reg(normal.rows(), normal.cols());
      reg.setIdentity();
      normal += (options.step_penalty * mean_diag) * reg;
      ldlt.compute(normal);
      if (ldlt.info() != Eigen::Success) break;
      factorised = true;
    }
    const Eigen::VectorXd residual = f * c;
    const Eigen::VectorXd step = f_free.transpose() * ldlt.solve(-residual);
    for (size_t q = 0; q < m; ++q) {
      if (fixed[q]) continue;
      c[q] += step[q];
      if (c[q] < options.min_factor || c[q] > options.max_factor) {
        c[q] = std::clamp(c[q], options.min_factor, options.max_factor);
        fixed[q] = 1;
        factorised = false;
      }
    }
  }
  // A common factor keeps F c = 0: restore the energy of a uniform stretch, sum_q a_i w_q s_q (7.7).
  double before = 0.0, after = 0.0;
  for (size_t i = 0; i < nodes.size(); ++i) {
    for (size_t q = fibers.node_offsets[i]; q < fibers.node_offsets[i + 1]; ++q) {
      const double e = nodes.rest_areas[i] * fibers.fibers[q].weight * fibers.fibers[q].stretch_scale;
      before += e;
      after += e * c[q];
    }
  }
  if (after > 0.0) c *= before / after;
  report.residual_after = relativeImbalance(cols, rows, c);
  report.min_factor = c.minCoeff();
  report.max_factor = c.maxCoeff();
  for (size_t q = 0; q < m; ++q) {
    report.clamped_fibers += fixed[q] ? 1 : 0;
    fibers.fibers[q].stretch_scale *= c[q];
  }
  return report;
}

}  // namespace rc
