#include "relaxed_connectivity/shell/shell_crack.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/core/kd_tree.h"

namespace rc {

int crackSide(const ShellCrack& crack, const Vec3& p) {
  return (p - crack.center).dot(crack.normal) >= 0.0 ? 1 : -1;
}

bool crackSeparates(const ShellCrack& crack, const Vec3& a, const Vec3& b) {
  const double da = (a - crack.center).dot(crack.normal), db = (b - crack.center).dot(crack.normal);
  if ((da >= 0.0) == (db >= 0.0)) return false;
  const Vec3 hit = a + (b - a) * (da / (da - db));  // da != db since the signs differ
  return (hit - crack.center).squaredNorm() <= crack.radius * crack.radius;
}

bool crackVisible(const std::vector<ShellCrack>& cracks, const Vec3& a, const Vec3& b) {
  for (const ShellCrack& c : cracks) {
    if (crackSeparates(c, a, b)) return false;
  }
  return true;
}

std::vector<uint32_t> recomputeVisibleNeighborhoods(ShellNodes& nodes, const std::vector<ShellCrack>& cracks,
                                                    size_t neighbor_count, size_t first_new_crack) {
  const size_t n = nodes.size();
  if (neighbor_count < 3 || neighbor_count > 255) {
    throw std::invalid_argument("recomputeVisibleNeighborhoods: neighbor_count must be in [3, 255]");
  }
  const std::vector<Vec3>& x = nodes.rest_positions;
  std::vector<uint32_t> dirty;
  const size_t first = std::min(first_new_crack, cracks.size());
  for (size_t i = 0; i < n; ++i) {
    const uint32_t* nb = nodes.neighborsOf(i);
    bool cut = false;
    for (size_t m = 0; m < nodes.neighborCount(i) && !cut; ++m) {
      for (size_t c = first; c < cracks.size() && !cut; ++c) cut = crackSeparates(cracks[c], x[i], x[nb[m]]);
    }
    if (cut) dirty.push_back(static_cast<uint32_t>(i));
  }
  if (dirty.empty()) return dirty;

  KdTree tree(x);
  const size_t candidates = std::min(n, 4 * neighbor_count + 1);
  // New lists of the dirty nodes only; the others are copied over unchanged below.
  std::vector<std::vector<uint32_t>> lists(dirty.size());
  std::vector<std::vector<std::pair<uint8_t, uint8_t>>> fans(dirty.size());
#pragma omp parallel for schedule(dynamic, 16)
  for (size_t d = 0; d < dirty.size(); ++d) {
    const size_t i = dirty[d];
    std::vector<Neighbor> found(candidates);
    const size_t got = tree.knn(x[i], candidates, found.data());
    const Vec3& nrm = nodes.rest_normals[i];
    const Vec3 u = nrm.cross(std::abs(nrm.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).normalized();
    const Vec3 v = nrm.cross(u);
    // Only cracks within radius + (farthest candidate) of the node can cut a segment to a candidate.
    std::vector<const ShellCrack*> near;
    const double far_candidate = got > 0 ? std::sqrt(found[got - 1].sq_dist) : 0.0;
    for (const ShellCrack& c : cracks) {
      const double reach = (c.radius + far_candidate) * (1.0 + 1e-9);
      if ((c.center - x[i]).squaredNorm() <= reach * reach) near.push_back(&c);
    }
    std::vector<std::pair<double, uint32_t>> by_angle;
    for (size_t m = 0; m < got && by_angle.size() < neighbor_count; ++m) {
      const uint32_t j = found[m].index;
      bool visible = j != i;
      for (size_t c = 0; c < near.size() && visible; ++c) visible = !crackSeparates(*near[c], x[i], x[j]);
      if (!visible) continue;
      const Vec3 e = x[j] - x[i];
      by_angle.emplace_back(std::atan2(e.dot(v), e.dot(u)), j);
    }
    std::sort(by_angle.begin(), by_angle.end());
    const size_t k = by_angle.size();
    for (const auto& p : by_angle) lists[d].push_back(p.second);
    for (size_t m = 0; k >= 2 && m < k; ++m) {  // fan pairs as in selectShellNodes (gaps < 120 degrees)
      const size_t m1 = (m + 1) % k;
      double gap = by_angle[m1].first - by_angle[m].first;
      if (gap <= 0.0) gap += 2.0 * M_PI;
      if (gap < 2.0 * M_PI / 3.0) fans[d].emplace_back(static_cast<uint8_t>(m), static_cast<uint8_t>(m1));
    }
  }
  // CSR arrays rebuilt in node order.
  const std::vector<uint32_t> old_neighbors = std::move(nodes.neighbors);
  const std::vector<std::pair<uint8_t, uint8_t>> old_fans = std::move(nodes.fan_pairs);
  const std::vector<size_t> old_offsets = nodes.neighbor_offsets, old_fan_offsets = nodes.fan_offsets;
  nodes.neighbors.clear();
  nodes.fan_pairs.clear();
  size_t d = 0;
  for (size_t i = 0; i < n; ++i) {
    if (d < dirty.size() && dirty[d] == i) {
      nodes.neighbors.insert(nodes.neighbors.end(), lists[d].begin(), lists[d].end());
      nodes.fan_pairs.insert(nodes.fan_pairs.end(), fans[d].begin(), fans[d].end());
      ++d;
    } else {
      nodes.neighbors.insert(nodes.neighbors.end(), old_neighbors.begin() + old_offsets[i],
                             old_neighbors.begin() + old_offsets[i + 1]);
      nodes.fan_pairs.insert(nodes.fan_pairs.end(), old_fans.begin() + old_fan_offsets[i],
                             old_fans.begin() + old_fan_offsets[i + 1]);
    }
    nodes.neighbor_offsets[i + 1] = nodes.neighbors.size();
    nodes.fan_offsets[i + 1] = nodes.fan_pairs.size();
  }
  return dirty;
}

}  // namespace rc
