#include "relaxed_connectivity/surface/radius_estimation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/core/kd_tree.h"

namespace rc {

namespace {

using Vec2 = Eigen::Vector2d;

/// Clips a convex polygon by the half-plane {y : y.a <= b} (Sutherland-Hodgman).
void clipHalfPlane(const std::vector<Vec2>& in, const Vec2& a, double b, std::vector<Vec2>& out) {
  out.clear();
  const size_t m = in.size();
  for (size_t i = 0; i < m; ++i) {
    const Vec2& p = in[i];
    const Vec2& q = in[(i + 1) % m];
    const double fp = p.dot(a) - b, fq = q.dot(a) - b;
    if (fp <= 0) out.push_back(p);
    if ((fp < 0 && fq > 0) || (fp > 0 && fq < 0)) out.push_back(p + (q - p) * (fp / (fp - fq)));
  }
}

}  // namespace

// Rule: project the k nearest neighbours into the surfel's tangent plane and clip the square |y|_inf <= d_k
// (d_k: distance to the k-th neighbour, bounding cells at open borders) by the perpendicular bisectors to
// each neighbour. This polygon contains the surfel's tangent-plane Voronoi cell (fewer neighbours only
// enlarge it), so the radius to its farthest vertex reaches every surface point whose nearest sample is this
// surfel: the discs cover the surface (3.3). `scale` >= 1 adds margin against curvature between the tangent
// plane and the surface.
void estimateRadii(SurfelCloud& cloud, const RadiusEstimationConfig& config) {
  if (!cloud.hasNormals()) throw std::invalid_argument("estimateRadii: the cloud has no normals");
  if (config.k < 2) throw std::invalid_argument("estimateRadii: k must be >= 2");
  if (!(config.scale > 0)) throw std::invalid_argument("estimateRadii: scale must be positive");
  cloud.validate();
  const size_t n = cloud.size();
  cloud.radii.assign(n, 0.0);
  if (n < 2) return;
  const size_t k = std::min<size_t>(config.k + 1, n);
  KdTree tree(cloud.positions);
  std::vector<Neighbor> rows;
  tree.knnBatch(cloud.positions, k, rows);
#pragma omp parallel
  {
    std::vector<Vec2> poly, tmp;
#pragma omp for schedule(static)
    for (long i = 0; i < static_cast<long>(n); ++i) {
      const Vec3& p = cloud.positions[i];
      Vec3 nrm = cloud.normals[i];
      if (!(nrm.squaredNorm() > 0)) nrm = Vec3::UnitZ();
      nrm.normalize();
      const Vec3 a = std::abs(nrm.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
      const Vec3 t1 = nrm.cross(a).normalized(), t2 = nrm.cross(t1);
      double dk = 0;
      for (size_t j = 0; j < k; ++j) {
        const Neighbor& nb = rows[i * k + j];
        if (nb.index != std::numeric_limits<uint32_t>::max()) dk = std::max(dk, std::sqrt(nb.sq_dist));
      }
      if (!(dk > 0)) continue;
      poly = {Vec2(-dk, -dk), Vec2(dk, -dk), Vec2(dk, dk), Vec2(-dk, dk)};
      for (size_t j = 0; j < k && poly.size() >= 3; ++j) {
        const Neighbor& nb = rows[i * k + j];
        if (nb.index == std::numeric_limits<uint32_t>::max() || nb.index == static_cast<uint32_t>(i))
          continue;
        const Vec3 d = cloud.positions[nb.index] - p;
        const Vec2 d2(d.dot(t1), d.dot(t2));
        const double len2 = d2.squaredNorm();
        if (len2 < 1e-24 * dk * dk) continue;  // duplicate sample: no bisector
        clipHalfPlane(poly, d2, 0.5 * len2, tmp);
        poly.swap(tmp);
      }
      double r2 = 0;
      for (const Vec2& v : poly) r2 = std::max(r2, v.squaredNorm());
      double r = std::sqrt(r2) * config.scale;
      if (config.max_radius > 0) r = std::min(r, config.max_radius);
      cloud.radii[i] = r;
    }
  }
}

double sampleSpacing(const std::vector<Vec3>& positions) {
  if (positions.size() < 7)
    throw std::invalid_argument("sampleSpacing: " + std::to_string(positions.size()) +
                                " points (at least 7 needed)");
  KdTree tree(positions);
  std::vector<Neighbor> rows;
  tree.knnBatch(positions, 7, rows);
  double sum = 0;
  for (size_t i = 0; i < positions.size(); ++i) sum += std::sqrt(rows[i * 7 + 6].sq_dist);
  return sum / static_cast<double>(positions.size()) * std::sqrt(M_PI / 6.0);
}

}  // namespace rc
