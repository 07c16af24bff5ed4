#include "relaxed_connectivity/shell/shell_nodes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/core/hash_grid.h"
#include "relaxed_connectivity/core/kd_tree.h"

namespace rc {
namespace {

using Vec2 = Eigen::Vector2d;

void tangentFrame(const Vec3& n, Vec3* u, Vec3* v) {
  const Vec3 a = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  *u = n.cross(a).normalized();
  *v = n.cross(*u);
}

// Greedy Poisson-disc pick in index order (deterministic).
std::vector<uint32_t> greedyPick(const std::vector<Vec3>& points, double spacing) {
  HashGrid grid(spacing, points.size() / 8 + 16);
  std::vector<uint32_t> picked;
  std::vector<Neighbor> found;
  for (size_t i = 0; i < points.size(); ++i) {
    if (grid.radius(points[i], spacing, found) > 0) continue;
    grid.insert(static_cast<uint32_t>(picked.size()), points[i]);
    picked.push_back(static_cast<uint32_t>(i));
  }
  return picked;
}

// Area of the node's Voronoi cell in its tangent plane, bounded by a disc-like 16-gon. At an open boundary
// (an angular gap of more than 120 degrees between neighbours) virtual neighbours at the nearest distance
// fill the gap, one per 90 degrees of it: the cell ends half a spacing beyond the node, as the surface its
// samples cover (a grid's edge node gets h^2, its corner h^2; the 16-gon alone gave them 1.35 and 2.3 h^2).
double tangentVoronoiArea(const Vec3& x, const Vec3& n, const std::vector<Vec3>& others) {
  Vec3 u, v;
  tangentFrame(n, &u, &v);
  std::vector<Vec2> proj;
  for (const Vec3& p : others) proj.emplace_back((p - x).dot(u), (p - x).dot(v));
  std::vector<double> d;
  for (const Vec2& p : proj) d.push_back(p.norm());
  std::sort(d.begin(), d.end());
  if (!d.empty() && d[0] > 0.0) {
    std::vector<double> angles;
    for (const Vec2& p : proj) angles.push_back(std::atan2(p.y(), p.x()));
    std::sort(angles.begin(), angles.end());
    const size_t count = angles.size();
    for (size_t k = 0; k < count; ++k) {
      const double from = angles[k];
      double gap = (k + 1 < count ? angles[k + 1] : angles[0] + 2.0 * M_PI) - from;
      if (count == 1) gap = 2.0 * M_PI;
      if (gap <= 2.0 * M_PI / 3.0) continue;
      const int fill = int(std::ceil(gap / (0.5 * M_PI) - 1e-9)) - 1;
      for (int m = 1; m <= fill; ++m) {
        const double a = from + gap * m / (fill + 1);
        proj.emplace_back(d[0] * std::cos(a), d[0] * std::sin(a));
      }
    }
  }
  const size_t near = std::min<size_t>(6, d.size());
  double mean_near = 0.0;
  for (size_t k = 0; k < near; ++k) mean_near += d[k] / near;
  const double bound = 0.7 * mean_near;
  std::vector<Vec2> poly, next;
  for (int k = 0; k < 16; ++k) {
    const double a = 2.0 * M_PI * k / 16.0;
    poly.emplace_back(bound * std::cos(a), bound * std::sin(a));
  }
  for (const Vec2& e : proj) {  // keep p . e <= |e|^2 / 2
    const double c = 0.5 * e.squaredNorm();
    if (c <= 0.0) continue;
    next.clear();
    for (size_t k = 0; k < poly.size(); ++k) {
      const Vec2& p = poly[k];
      const Vec2& q = poly[(k + 1) % poly.size()];
      const double fp = p.dot(e) - c, fq = q.dot(e) - c;
      if (fp <= 0.0) next.push_back(p);
      if ((fp < 0.0) != (fq < 0.0) && fp != fq) next.push_back(p + (q - p) * (fp / (fp - fq)));
    }
    poly.swap(next);
    if (poly.size() < 3) return 0.0;
  }
  double area = 0.0;
  for (size_t k = 0; k < poly.size(); ++k) {
    const Vec2& p = poly[k];
    const Vec2& q = poly[(k + 1) % poly.size()];
    area += 0.5 * (p.x() * q.y() - p.y() * q.x());
  }
  return area;
}

// sqrt(lambda_max / lambda_min) of M = sum e e^T / |e|^4 (ShellNodes::sampling_anisotropy).
double samplingAnisotropy(const std::vector<Vec2>& offsets) {
  double mxx = 0.0, mxy = 0.0, myy = 0.0;
  for (const Vec2& e : offsets) {
    const double q = e.squaredNorm();
    if (q <= 0.0) continue;
    const double w = 1.0 / (q * q);
    mxx += w * e.x() * e.x(), mxy += w * e.x() * e.y(), myy += w * e.y() * e.y();
  }
  const double mean = 0.5 * (mxx + myy);
  const double dev = std::hypot(0.5 * (mxx - myy), mxy);
  const double lo = mean - dev, hi = mean + dev;
  if (!(hi > 0.0)) return std::numeric_limits<double>::infinity();
  if (lo <= 1e-12 * hi) return std::numeric_limits<double>::infinity();
  return std::sqrt(hi / lo);
}

// Tangent Voronoi area of every surfel among its 16 nearest (the surface each surfel stands for).
std::vector<double> surfelTangentAreas(const SurfelCloud& cloud) {
  const size_t n = cloud.size();
  std::vector<double> area(n, 0.0);
  if (n < 2) return area;
  KdTree tree(cloud.positions);
  const size_t k = std::min<size_t>(n - 1, 16);
#pragma omp parallel
  {
    std::vector<Neighbor> found(k + 1);
    std::vector<Vec3> others;
#pragma omp for schedule(static)
    for (size_t s = 0; s < n; ++s) {
      const size_t got = tree.knn(cloud.positions[s], k + 1, found.data());
      others.clear();
      for (size_t m = 0; m < got; ++m)
        if (found[m].index != s) others.push_back(cloud.positions[found[m].index]);
      area[s] = tangentVoronoiArea(cloud.positions[s], cloud.normals[s].normalized(), others);
    }
  }
  return area;
}

void buildNeighborhoods(ShellNodes& nodes, size_t k) {
  const size_t n = nodes.size();
  if (k < 4 || k > 255) throw std::invalid_argument("ShellNodeOptions::neighbor_count must be in [4, 255]");
  if (n < k + 1) {
    throw std::invalid_argument("shell nodes: " + std::to_string(n) +
                                " nodes are too few for neighbourhoods of " + std::to_string(k));
  }
  KdTree tree(nodes.rest_positions);
  const size_t k_area = std::min<size_t>(n - 1, std::max<size_t>(16, k));  // neighbours and area clippers
  nodes.neighbor_offsets.assign(n + 1, 0);
  nodes.neighbors.assign(n * k, 0);
  nodes.fan_offsets.assign(n + 1, 0);
  nodes.rest_areas.assign(n, 0.0);
  nodes.sampling_anisotropy.assign(n, 0.0);
  std::vector<std::vector<std::pair<uint8_t, uint8_t>>> fans(n);
  std::vector<double> nearest(n, 0.0);
  bool duplicate = false;
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; ++i) {
    std::vector<Neighbor> found(k_area + 1);
    const size_t got = tree.knn(nodes.rest_positions[i], k_area + 1, found.data());
    std::vector<uint32_t> ids;
    std::vector<Vec3> others;
    for (size_t m = 0; m < got; ++m) {
      if (found[m].index == i) continue;
      if (found[m].sq_dist == 0.0) duplicate = true;
      if (ids.size() < k) ids.push_back(found[m].index);
      others.push_back(nodes.rest_positions[found[m].index]);
    }
    ids.resize(k);
    nearest[i] = std::sqrt(found[1].sq_dist);
    const Vec3& x = nodes.rest_positions[i];
    const Vec3& nrm = nodes.rest_normals[i];
    Vec3 u, v;
    tangentFrame(nrm, &u, &v);
    std::vector<std::pair<double, uint32_t>> by_angle;
    std::vector<Vec2> offsets;
    for (uint32_t j : ids) {
      const Vec3 e = nodes.rest_positions[j] - x;
      offsets.emplace_back(e.dot(u), e.dot(v));
      by_angle.emplace_back(std::atan2(e.dot(v), e.dot(u)), j);
    }
    nodes.sampling_anisotropy[i] = samplingAnisotropy(offsets);
    std::sort(by_angle.begin(), by_angle.end());
    for (size_t m = 0; m < k; ++m) nodes.neighbors[i * k + m] = by_angle[m].second;
    for (size_t m = 0; m < k; ++m) {
      const size_t m1 = (m + 1) % k;
      double gap = by_angle[m1].first - by_angle[m].first;
      if (gap <= 0.0) gap += 2.0 * M_PI;
      if (gap < 2.0 * M_PI / 3.0) fans[i].emplace_back(static_cast<uint8_t>(m), static_cast<uint8_t>(m1));
    }
    nodes.rest_areas[i] = tangentVoronoiArea(x, nrm, others);
  }
  if (duplicate) throw std::invalid_argument("shell nodes: two nodes share a position");
  double mean_nearest = 0.0;
  for (size_t i = 0; i < n; ++i) {
    nodes.neighbor_offsets[i + 1] = (i + 1) * k;
    nodes.fan_offsets[i + 1] = nodes.fan_offsets[i] + fans[i].size();
    if (fans[i].empty()) {
      char what[64];
      std::snprintf(what, sizeof what, "%.3g", nodes.sampling_anisotropy[i]);
      throw std::invalid_argument("shell nodes: node " + std::to_string(i) +
                                  " has no fan (every angle between consecutive neighbours is 120 degrees or "
                                  "more; sampling anisotropy " +
                                  what + ", the sampling is too irregular)");
    }
    mean_nearest += nearest[i] / n;
  }
  nodes.fan_pairs.clear();
  for (auto& f : fans) nodes.fan_pairs.insert(nodes.fan_pairs.end(), f.begin(), f.end());
  nodes.spacing = mean_nearest;
  const ShellNodeOptions defaults;
  nodes.sampling = summarizeShellSampling(nodes, defaults.anisotropy_threshold, defaults.irregular_fraction);
}

void checkNormals(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals, const char* what) {
  if (positions.empty()) throw std::invalid_argument(std::string(what) + ": no points");
  if (normals.size() != positions.size()) {
    throw std::invalid_argument(std::string(what) + ": normals are required, one per point");
  }
  for (size_t i = 0; i < positions.size(); ++i) {
    if (!positions[i].allFinite() || !normals[i].allFinite() || normals[i].norm() < 1e-12) {
      throw std::invalid_argument(std::string(what) + ": point " + std::to_string(i) +
                                  " has a non-finite position or a zero normal");
    }
  }
}

}  // namespace

ShellSamplingStats summarizeShellSampling(const ShellNodes& nodes, double threshold,
                                          double irregular_fraction) {
  if (!(threshold >= 1.0)) {
    throw std::invalid_argument("ShellNodeOptions::anisotropy_threshold must be >= 1 (1 is isotropic)");
  }
  if (!(irregular_fraction >= 0.0 && irregular_fraction <= 1.0)) {
    throw std::invalid_argument("ShellNodeOptions::irregular_fraction must be in [0, 1]");
  }
  ShellSamplingStats stats;
  stats.threshold = threshold;
  std::vector<double> values = nodes.sampling_anisotropy;
  if (values.empty()) return stats;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  stats.median = values[mid];
  if (values.size() % 2 == 0)
    stats.median = 0.5 * (stats.median + *std::max_element(values.begin(), values.begin() + mid));
  size_t above = 0;
  for (double a : values) {
    stats.worst = std::max(stats.worst, a);
    above += a > threshold;
  }
  stats.fraction_above = double(above) / values.size();
  if (stats.fraction_above > irregular_fraction) {
    char text[320];
    std::snprintf(text, sizeof text,
                  "highly irregular sampling: %.1f %% of the %zu nodes have a sampling anisotropy above %.3g "
                  "(median %.3g, worst %.3g; 1 is isotropic); fibers follow the sampling, so the material "
                  "behaves anisotropically there (thesis 7.6)",
                  100.0 * stats.fraction_above, values.size(), threshold, stats.median, stats.worst);
    stats.warning = text;
  }
  return stats;
}

ShellNodes shellNodesFromPoints(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                                size_t neighbor_count) {
  checkNormals(positions, normals, "shellNodesFromPoints");
  ShellNodes nodes;
  nodes.rest_positions = positions;
  nodes.rest_normals.reserve(normals.size());
  for (const Vec3& n : normals) nodes.rest_normals.push_back(n.normalized());
  buildNeighborhoods(nodes, neighbor_count);
  return nodes;
}

ShellNodes selectShellNodes(const SurfelCloud& cloud, const ShellNodeOptions& options) {
  checkNormals(cloud.positions, cloud.normals, "selectShellNodes");
  if (!(options.spacing >= 0.0) || (options.spacing == 0.0 && options.target_count == 0)) {
    throw std::invalid_argument("ShellNodeOptions: give spacing > 0 or target_count > 0");
  }
  summarizeShellSampling(ShellNodes(), options.anisotropy_threshold, options.irregular_fraction);  // checks
  const std::vector<Vec3>& pts = cloud.positions;
  double spacing = options.spacing;
  std::vector<uint32_t> picked;
  if (spacing > 0.0) {
    picked = greedyPick(pts, spacing);
  } else {  // bisect the spacing (count decreases with spacing)
    if (options.target_count > pts.size()) {
      throw std::invalid_argument("ShellNodeOptions::target_count exceeds the number of surfels");
    }
    Vec3 lo, hi;
    cloud.bounds(&lo, &hi);
    double a = 0.0, b = (hi - lo).norm();
    for (int it = 0; it < 40; ++it) {
      spacing = 0.5 * (a + b);
      picked = greedyPick(pts, spacing);
      const double rel =
          (double(picked.size()) - double(options.target_count)) / double(options.target_count);
      if (std::abs(rel) <= 0.02) break;
      (rel > 0 ? a : b) = spacing;
    }
  }
  std::vector<uint32_t> cluster(pts.size(), 0);
  for (int it = 0; it <= options.relax_iterations; ++it) {
    std::vector<Vec3> centers;
    for (uint32_t s : picked) centers.push_back(pts[s]);
    KdTree tree(centers);
#pragma omp parallel for schedule(static)
    for (size_t s = 0; s < pts.size(); ++s) {
      Neighbor nb;
      tree.knn(pts[s], 1, &nb);
      cluster[s] = nb.index;
    }
    if (it == options.relax_iterations) break;
    std::vector<Vec3> centroid(picked.size(), Vec3::Zero());
    std::vector<size_t> count(picked.size(), 0);
    for (size_t s = 0; s < pts.size(); ++s) centroid[cluster[s]] += pts[s], ++count[cluster[s]];
    std::vector<double> best(picked.size(), INFINITY);
    std::vector<uint32_t> moved = picked;
    for (size_t c = 0; c < picked.size(); ++c) centroid[c] /= double(std::max<size_t>(count[c], 1));
    for (size_t s = 0; s < pts.size(); ++s) {  // index order: ties go to the lowest surfel index
      const double d = (pts[s] - centroid[cluster[s]]).squaredNorm();
      if (d < best[cluster[s]]) best[cluster[s]] = d, moved[cluster[s]] = static_cast<uint32_t>(s);
    }
    picked = moved;
  }
  ShellNodes nodes;
  for (uint32_t s : picked) {
    nodes.rest_positions.push_back(pts[s]);
    nodes.rest_normals.push_back(cloud.normals[s].normalized());
  }
  nodes.source_surfel = picked;
  nodes.surfel_cluster = cluster;
  buildNeighborhoods(nodes, options.neighbor_count);
  // A node stands for the surface of its cluster: the sum of its surfels' areas, which ends where the
  // surfels end (the nodes' own Voronoi cells reach half a node spacing beyond an open boundary).
  const std::vector<double> surfel_area = surfelTangentAreas(cloud);
  std::vector<double> cluster_area(nodes.size(), 0.0);
  for (size_t s = 0; s < pts.size(); ++s) cluster_area[cluster[s]] += surfel_area[s];
  for (size_t i = 0; i < nodes.size(); ++i)
    if (cluster_area[i] > 0.0) nodes.rest_areas[i] = cluster_area[i];
  nodes.sampling = summarizeShellSampling(nodes, options.anisotropy_threshold, options.irregular_fraction);
  return nodes;
}

Vec3 fanNormal(const ShellNodes& nodes, size_t i, const std::vector<Vec3>& x, double* length) {
  const uint32_t* nb = nodes.neighborsOf(i);
  Vec3 sum = Vec3::Zero();
  for (size_t f = nodes.fan_offsets[i]; f < nodes.fan_offsets[i + 1]; ++f) {
    const auto& pr = nodes.fan_pairs[f];
    sum += (x[nb[pr.first]] - x[i]).cross(x[nb[pr.second]] - x[i]);
  }
  const double len = sum.norm();
  if (length) *length = len;
  return len > 0.0 ? Vec3(sum / len) : nodes.rest_normals[i];
}

}  // namespace rc
