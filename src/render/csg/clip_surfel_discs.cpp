#include "relaxed_connectivity/render/csg/clip_surfel_discs.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

void tangentBasis(const Vec3& n, Vec3* u, Vec3* v) {
  const Vec3 helper = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  *u = n.cross(helper).normalized();
  *v = n.cross(*u);
}

[[noreturn]] void bad(const std::string& what) {
  throw std::invalid_argument("CSG surfels: " + what);
}

// Chord of disc (c, t1, t2) cut by the plane (p, n): false if the plane misses the disc or is parallel to it.
bool chord(const Vec3& c, const Vec3& t1, const Vec3& t2, const Vec3& p, const Vec3& n, Vec3* e0, Vec3* e1) {
  const double alpha = n.dot(t1), beta = n.dot(t2), h = n.dot(p - c);
  const double g2 = alpha * alpha + beta * beta;
  if (!(g2 > 0) || h * h > g2) return false;
  const double a0 = h * alpha / g2, b0 = h * beta / g2;
  const double half = std::sqrt(std::max(0.0, 1.0 - h * h / g2) / g2);  // half-length / g in (a, b) units
  *e0 = c + (a0 - half * beta) * t1 + (b0 + half * alpha) * t2;
  *e1 = c + (a0 + half * beta) * t1 + (b0 - half * alpha) * t2;
  return true;
}

}  // namespace

bool discsIntersect(const Vec3& c1, const Vec3& n1, const Vec3& t11, const Vec3& t12, const Vec3& c2,
                    const Vec3& n2, const Vec3& t21, const Vec3& t22) {
  const double r1 = std::max(t11.norm(), t12.norm()), r2 = std::max(t21.norm(), t22.norm());
  const Vec3 w = n1.cross(n2);
  if (w.squaredNorm() == 0.0) {  // exactly parallel planes: coplanar and overlapping bounding circles
    const double offset = std::abs(n1.dot(c2 - c1));
    return offset <= 1e-12 * (r1 + r2) && (c2 - c1).norm() < r1 + r2;
  }
  Vec3 a0, a1, b0, b1;
  if (!chord(c1, t11, t12, c2, n2, &a0, &a1)) return false;
  if (!chord(c2, t21, t22, c1, n1, &b0, &b1)) return false;
  double lo1 = a0.dot(w), hi1 = a1.dot(w), lo2 = b0.dot(w), hi2 = b1.dot(w);
  if (lo1 > hi1) std::swap(lo1, hi1);
  if (lo2 > hi2) std::swap(lo2, hi2);
  const double eps = 1e-12 * (r1 + r2 + c1.norm() + c2.norm()) * w.norm();
  return std::max(lo1, lo2) <= std::min(hi1, hi2) + eps;
}

SurfelDiscs SurfelDiscs::fromCloud(const SurfelCloud& cloud) {
  cloud.validate();
  const size_t n = cloud.size();
  if (!cloud.hasRadii() && !cloud.hasAxes()) bad("the cloud has neither radii nor axes");
  if (!cloud.hasNormals() && !cloud.hasAxes()) bad("the cloud has no normals");
  const Attribute* patch = cloud.attributes.find(kPatchIdAttribute);
  if (!patch) bad("the cloud has no attribute \"patch_id\"");
  if (patch->size() != n)
    bad("attribute \"patch_id\" has " + std::to_string(patch->size()) + " values for " + std::to_string(n) +
        " surfels");
  const Attribute* role = cloud.attributes.find(kSurfelRoleAttribute);
  if (role && role->size() != n) bad("attribute \"surfel_role\" has the wrong size");
  SurfelDiscs d;
  d.patches.resize(n);
  d.roles.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const double p = patch->get(i);
    if (!(p >= 0 && p <= 2147483647.0) || p != std::floor(p))
      bad("surfel " + std::to_string(i) + " has patch_id " + std::to_string(p) + " (need an integer >= 0)");
    d.patches[i] = static_cast<int32_t>(p);
    const double r = role ? role->get(i) : 0.0;
    if (r != 0.0 && r != 1.0 && r != 2.0)
      bad("surfel " + std::to_string(i) + " has surfel_role " + std::to_string(r) + " (need 0, 1 or 2)");
    d.roles[i] = static_cast<SurfelRole>(static_cast<int>(r));
  }
  d.updateGeometry(cloud);
  return d;
}

void SurfelDiscs::updateGeometry(const SurfelCloud& cloud) {
  const size_t n = cloud.size();
  if (n != patches.size())
    bad("the cloud changed size from " + std::to_string(patches.size()) + " to " + std::to_string(n) +
        " surfels");
  centers = cloud.positions;
  normals.resize(n);
  axes1.resize(n);
  axes2.resize(n);
  radii.resize(n);
  max_radius = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!centers[i].allFinite()) bad("surfel " + std::to_string(i) + " has a non-finite position");
    if (cloud.hasAxes()) {
      axes1[i] = cloud.axes1[i];
      axes2[i] = cloud.axes2[i];
      const Vec3 normal = cloud.hasNormals() ? cloud.normals[i] : axes1[i].cross(axes2[i]);
      if (!(normal.norm() > 0) || !normal.allFinite())
        bad("surfel " + std::to_string(i) + " has a zero or non-finite normal");
      normals[i] = normal.normalized();
      radii[i] = std::max(axes1[i].norm(), axes2[i].norm());
    } else {
      const Vec3& normal = cloud.normals[i];
      if (!(normal.norm() > 0) || !normal.allFinite())
        bad("surfel " + std::to_string(i) + " has a zero or non-finite normal");
      normals[i] = normal.normalized();
      Vec3 u, v;
      tangentBasis(normals[i], &u, &v);
      radii[i] = cloud.radii[i];
      axes1[i] = radii[i] * u;
      axes2[i] = radii[i] * v;
    }
    if (!(radii[i] > 0) || !std::isfinite(radii[i]))
      bad("surfel " + std::to_string(i) + " has radius " + std::to_string(radii[i]) + " (need > 0)");
    max_radius = std::max(max_radius, radii[i]);
  }
}

bool SurfelDiscs::partners(uint32_t i, uint32_t j) const {
  if (patches[i] == patches[j]) return false;
  const double reach = radii[i] + radii[j];
  if (!((centers[i] - centers[j]).squaredNorm() < reach * reach)) return false;
  return discsIntersect(centers[i], normals[i], axes1[i], axes2[i], centers[j], normals[j], axes1[j],
                        axes2[j]);
}

}  // namespace rc
