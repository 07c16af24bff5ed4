#include "relaxed_connectivity/shell/shell_hessian.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

/// S_i: the nodes node i's energy term reads (itself, its neighbours, the ends of its fibers), as CSR.
void energyStencils(const ShellEnergy& energy, std::vector<size_t>& offsets, std::vector<uint32_t>& members) {
  const ShellNodes& nodes = energy.nodes();
  const ShellFibers& fibers = energy.fibers();
  const size_t n = nodes.size();
  offsets.assign(n + 1, 0);
  members.clear();
  std::vector<uint32_t> row;
  for (size_t i = 0; i < n; ++i) {
    row.assign(1, uint32_t(i));
    row.insert(row.end(), nodes.neighborsOf(i), nodes.neighborsOf(i) + nodes.neighborCount(i));
    for (size_t f = fibers.node_offsets[i]; f < fibers.node_offsets[i + 1]; ++f) {
      row.push_back(fibers.fibers[f].end1);
      row.push_back(fibers.fibers[f].end2);
    }
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    members.insert(members.end(), row.begin(), row.end());
    offsets[i + 1] = members.size();
  }
}

}  // namespace

Eigen::SparseMatrix<double> shellEnergyHessian(const ShellEnergy& energy, const std::vector<Vec3>& x,
                                               double step, ShellHessianStats* stats) {
  const ShellNodes& nodes = energy.nodes();
  const size_t n = nodes.size();
  if (x.size() != n)
    throw std::invalid_argument("shellEnergyHessian: " + std::to_string(x.size()) + " positions for " +
                                std::to_string(n) + " nodes");
  for (size_t i = 0; i < n; ++i)
    if (!x[i].allFinite())
      throw std::invalid_argument("shellEnergyHessian: position " + std::to_string(i) + " is not finite");
  if (!(step >= 0.0) || !std::isfinite(step))
    throw std::invalid_argument("shellEnergyHessian: step must be >= 0 (0: automatic)");
  const double h = step > 0.0 ? step : 1e-6 * (nodes.spacing > 0.0 ? nodes.spacing : 1.0);

  // H_pq != 0 only where p and q share a stencil. A colour's nodes q own disjoint sets R(q) = union of the
  // stencils holding q, so the gradient change at p comes from p's owner alone.
  std::vector<size_t> offsets;
  std::vector<uint32_t> members;
  energyStencils(energy, offsets, members);
  std::vector<size_t> holder_offsets(n + 1, 0);
  for (uint32_t q : members) ++holder_offsets[q + 1];
  for (size_t q = 0; q < n; ++q) holder_offsets[q + 1] += holder_offsets[q];
  std::vector<uint32_t> holders(members.size());
  {
    std::vector<size_t> fill(holder_offsets.begin(), holder_offsets.end() - 1);
    for (size_t i = 0; i < n; ++i)
      for (size_t k = offsets[i]; k < offsets[i + 1]; ++k) holders[fill[members[k]]++] = uint32_t(i);
  }
  std::vector<std::vector<int32_t>>
      owner;  // per colour: owner[c][p] = the node q of colour c whose R(q) holds p
  std::vector<std::vector<uint32_t>> colour_nodes;
  std::vector<uint32_t> reach;
  std::vector<size_t> seen(n, SIZE_MAX);
  for (size_t q = 0; q < n; ++q) {
    reach.clear();
    for (size_t k = holder_offsets[q]; k < holder_offsets[q + 1]; ++k) {
      const uint32_t i = holders[k];
      for (size_t m = offsets[i]; m < offsets[i + 1]; ++m)
        if (seen[members[m]] != q) seen[members[m]] = q, reach.push_back(members[m]);
    }
    size_t c = 0;
    for (; c < owner.size(); ++c) {
      bool free = true;
      for (uint32_t p : reach)
        if (owner[c][p] >= 0) {
          free = false;
          break;
        }
      if (free) break;
    }
    if (c == owner.size()) {
      owner.emplace_back(n, -1);
      colour_nodes.emplace_back();
    }
    for (uint32_t p : reach) owner[c][p] = int32_t(q);
    colour_nodes[c].push_back(uint32_t(q));
  }

  std::vector<Eigen::Triplet<double>> triplets;
  std::vector<Vec3> plus = x, minus = x, g_plus, g_minus;
  for (size_t c = 0; c < owner.size(); ++c)
    for (int d = 0; d < 3; ++d) {
      for (uint32_t q : colour_nodes[c]) plus[q][d] += h, minus[q][d] -= h;
      energy.evaluate(plus, &g_plus);
      energy.evaluate(minus, &g_minus);
      for (uint32_t q : colour_nodes[c]) plus[q][d] = x[q][d], minus[q][d] = x[q][d];
      for (size_t p = 0; p < n; ++p) {
        const int32_t q = owner[c][p];
        if (q < 0) continue;
        const Vec3 column = (g_plus[p] - g_minus[p]) / (2.0 * h);
        for (int r = 0; r < 3; ++r) triplets.emplace_back(int(3 * p + r), int(3 * q + d), column[r]);
      }
    }
  Eigen::SparseMatrix<double> H(int(3 * n), int(3 * n));
  H.setFromTriplets(triplets.begin(), triplets.end());
  const Eigen::SparseMatrix<double> Ht = H.transpose();
  const Eigen::SparseMatrix<double> K = 0.5 * (H + Ht);
  if (stats) {
    stats->colors = owner.size();
    stats->gradients = 6 * owner.size();
    stats->step = h;
    double largest = 0.0;
    for (int k = 0; k < H.outerSize(); ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(H, k); it; ++it)
        largest = std::max(largest, std::abs(it.value()));
    const Eigen::SparseMatrix<double> difference = H - Ht;
    double worst = 0.0;
    for (int k = 0; k < difference.outerSize(); ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(difference, k); it; ++it)
        worst = std::max(worst, std::abs(it.value()));
    stats->asymmetry = largest > 0.0 ? worst / largest : 0.0;
  }
  return K;
}

}  // namespace rc
