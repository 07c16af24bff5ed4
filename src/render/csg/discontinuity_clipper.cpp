#include "relaxed_connectivity/render/csg/discontinuity_clipper.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/core/kd_tree.h"

namespace rc {
namespace {

// Bounding radius of surfel i: radii, else the longer tangent axis.
double boundingRadius(const SurfelCloud& cloud, size_t i) {
  if (cloud.hasRadii()) return cloud.radii[i];
  return std::max(cloud.axes1[i].norm(), cloud.axes2[i].norm());
}

}  // namespace

DiscontinuityClipper::DiscontinuityClipper(const SurfelCloud& surface, const SurfelCloud& discontinuities) {
  if (!surface.hasRadii() && !surface.hasAxes())
    throw std::invalid_argument("DiscontinuityClipper: the surface surfels need radii or tangent axes");
  const SurfelCloud& d = discontinuities;
  if (!d.empty() && ((!d.hasNormals() && !d.hasAxes()) || (!d.hasRadii() && !d.hasAxes())))
    throw std::invalid_argument(
        "DiscontinuityClipper: the discontinuity surfels need normals and radii (or axes)");
  double max_disc = 0.0;
  for (size_t k = 0; k < d.size(); ++k) {
    const Vec3 n = d.hasNormals() ? d.normals[k] : Vec3(d.axes1[k].cross(d.axes2[k]));
    const double r = boundingRadius(d, k);
    if (!d.positions[k].allFinite() || !(n.norm() > 0.0) || !n.allFinite() || !(r > 0.0) || !std::isfinite(r))
      throw std::invalid_argument("DiscontinuityClipper: discontinuity surfel " + std::to_string(k) +
                                  " has a non-finite position, a zero normal or a bad radius");
    centers_.push_back(d.positions[k]);
    normals_.push_back(n.normalized());
    radii_.push_back(r);
    max_disc = std::max(max_disc, r);
  }
  offsets_.assign(1, 0);
  if (centers_.empty()) {
    offsets_.resize(surface.size() + 1, 0);
    return;
  }
  const KdTree tree(centers_);
  std::vector<Neighbor> near;
  for (size_t s = 0; s < surface.size(); ++s) {
    const Vec3& p = surface.positions[s];
    const double r = boundingRadius(surface, s);
    if (p.allFinite() && std::isfinite(r)) {
      tree.radius(p, r + max_disc, near);
      for (const Neighbor& nb : near) {
        const uint32_t k = uint32_t(nb.index);
        const Vec3 e = p - centers_[k];
        if (e.dot(normals_[k]) > 0.0) continue;               // centre in front: the partner disc's
        if (std::sqrt(nb.sq_dist) > r + radii_[k]) continue;  // discs apart
        if (std::abs(e.dot(normals_[k])) > r) continue;       // surfel does not reach the plane
        ids_.push_back(k);
      }
    }
    offsets_.push_back(uint32_t(ids_.size()));
  }
}

bool DiscontinuityClipper::needsClipping(uint32_t surfel) const {
  return offsets_[surfel + 1] > offsets_[surfel];
}

bool DiscontinuityClipper::keepFragment(uint32_t surfel, const Vec3& x) const {
  for (uint32_t q = offsets_[surfel]; q < offsets_[surfel + 1]; ++q) {
    const uint32_t k = ids_[q];
    const Vec3 e = x - centers_[k];
    const double h = e.dot(normals_[k]);
    if (h > 0.0 && (e - h * normals_[k]).squaredNorm() <= radii_[k] * radii_[k]) return false;  // (4.3)
  }
  return true;
}

size_t DiscontinuityClipper::clippedSurfels() const {
  size_t n = 0;
  for (size_t s = 0; s + 1 < offsets_.size(); ++s) n += offsets_[s + 1] > offsets_[s] ? 1 : 0;
  return n;
}

}  // namespace rc
