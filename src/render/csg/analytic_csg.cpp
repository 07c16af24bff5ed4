#include "relaxed_connectivity/render/csg/analytic_csg.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

RayBoundary boundary(double t, int patch, const Vec3& normal) {
  return RayBoundary{t, patch, normal};
}

RayBoundary infiniteBoundary(double t) {
  return RayBoundary{t, -1, Vec3::Zero()};
}

/// Sweeps the boundaries of a and b in ray order and emits the intervals where op(in_a, in_b) holds. A result
/// boundary caused by an operand boundary keeps its patch; its normal flips when the result enters where the
/// operand leaves (or vice versa), so it always points out of the result.
template <class Op>
IntervalList combine(const IntervalList& a, const IntervalList& b, Op op) {
  struct Event {
    RayBoundary where;
    int operand;
    bool entering;
  };
  std::vector<Event> events;
  events.reserve(2 * (a.size() + b.size()));
  for (const RayInterval& i : a) {
    events.push_back({i.enter, 0, true});
    events.push_back({i.leave, 0, false});
  }
  for (const RayInterval& i : b) {
    events.push_back({i.enter, 1, true});
    events.push_back({i.leave, 1, false});
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const Event& x, const Event& y) { return x.where.t < y.where.t; });
  IntervalList out;
  bool in[2] = {false, false};
  bool result = op(false, false);
  RayInterval open;
  if (result) open.enter = infiniteBoundary(-kInf);
  auto close = [&](const RayBoundary& leave) {
    open.leave = leave;
    if (open.leave.t > open.enter.t) out.push_back(open);
  };
  for (const Event& e : events) {
    in[e.operand] = e.entering;
    const bool now = op(in[0], in[1]);
    if (now == result) continue;
    RayBoundary where = e.where;
    if (now != e.entering) where.normal = -where.normal;
    if (now) {
      open.enter = where;
    } else {
      close(where);
    }
    result = now;
  }
  if (result) close(infiniteBoundary(kInf));
  return out;
}

}  // namespace

AnalyticSolid AnalyticSolid::sphere(const Vec3& center, double radius) {
  if (!(radius > 0)) throw std::invalid_argument("AnalyticSolid::sphere: radius must be positive");
  AnalyticSolid s;
  s.kind = Kind::kSphere;
  s.center = center;
  s.radius = radius;
  return s;
}

AnalyticSolid AnalyticSolid::ellipsoid(const Vec3& center, const Vec3& semi_axes,
                                       const Eigen::Matrix3d& rotation) {
  if (!(semi_axes.minCoeff() > 0))
    throw std::invalid_argument("AnalyticSolid::ellipsoid: semi-axes must be positive");
  AnalyticSolid s;
  s.kind = Kind::kEllipsoid;
  s.center = center;
  s.semi_axes = semi_axes;
  s.rotation = rotation;
  return s;
}

AnalyticSolid AnalyticSolid::halfSpace(const Vec3& point_on_plane, const Vec3& outward_normal) {
  if (!(outward_normal.norm() > 0))
    throw std::invalid_argument("AnalyticSolid::halfSpace: normal must be non-zero");
  AnalyticSolid s;
  s.kind = Kind::kHalfSpace;
  s.center = point_on_plane;
  s.normal = outward_normal.normalized();
  return s;
}

AnalyticSolid AnalyticSolid::box(const Vec3& center, const Vec3& half_extents,
                                 const Eigen::Matrix3d& rotation) {
  if (!(half_extents.minCoeff() > 0))
    throw std::invalid_argument("AnalyticSolid::box: half extents must be positive");
  AnalyticSolid s;
  s.kind = Kind::kBox;
  s.center = center;
  s.semi_axes = half_extents;
  s.rotation = rotation;
  return s;
}

AnalyticSolid AnalyticSolid::transformed(const Eigen::Isometry3d& motion) const {
  AnalyticSolid s = *this;
  s.center = motion * center;
  s.rotation = motion.linear() * rotation;
  s.normal = motion.linear() * normal;
  return s;
}

double AnalyticSolid::implicit(const Vec3& x) const {
  switch (kind) {
    case Kind::kSphere:
      return (x - center).norm() - radius;
    case Kind::kEllipsoid:
      return (rotation.transpose() * (x - center)).cwiseQuotient(semi_axes).norm() - 1.0;
    case Kind::kHalfSpace:
      return (x - center).dot(normal);
    case Kind::kBox:
      return ((rotation.transpose() * (x - center)).cwiseAbs() - semi_axes).maxCoeff();
  }
  return kInf;
}

IntervalList solidIntervals(const AnalyticSolid& solid, int patch, const Vec3& origin, const Vec3& dir) {
  using Kind = AnalyticSolid::Kind;
  switch (solid.kind) {
    case Kind::kSphere: {
      const Vec3 oc = origin - solid.center;
      const double b = oc.dot(dir), c = oc.squaredNorm() - solid.radius * solid.radius;
      const double disc = b * b - c * dir.squaredNorm();
      if (!(disc > 0)) return {};
      const double s = std::sqrt(disc), a = dir.squaredNorm();
      const double t0 = (-b - s) / a, t1 = (-b + s) / a;
      const Vec3 p0 = origin + t0 * dir, p1 = origin + t1 * dir;
      return {{boundary(t0, patch, (p0 - solid.center) / solid.radius),
               boundary(t1, patch, (p1 - solid.center) / solid.radius)}};
    }
    case Kind::kEllipsoid: {
      const Vec3 o = (solid.rotation.transpose() * (origin - solid.center)).cwiseQuotient(solid.semi_axes);
      const Vec3 d = (solid.rotation.transpose() * dir).cwiseQuotient(solid.semi_axes);
      const double a = d.squaredNorm(), b = o.dot(d), c = o.squaredNorm() - 1.0;
      const double disc = b * b - a * c;
      if (!(disc > 0)) return {};
      const double s = std::sqrt(disc);
      const double t0 = (-b - s) / a, t1 = (-b + s) / a;
      auto normalAt = [&](double t) {
        return (solid.rotation * (o + t * d).cwiseQuotient(solid.semi_axes)).normalized().eval();
      };
      return {{boundary(t0, patch, normalAt(t0)), boundary(t1, patch, normalAt(t1))}};
    }
    case Kind::kHalfSpace: {
      const double s0 = (origin - solid.center).dot(solid.normal), dn = dir.dot(solid.normal);
      if (std::abs(dn) < 1e-300) {
        if (s0 <= 0) return {{infiniteBoundary(-kInf), infiniteBoundary(kInf)}};
        return {};
      }
      const double t = -s0 / dn;
      if (dn > 0) return {{infiniteBoundary(-kInf), boundary(t, patch, solid.normal)}};
      return {{boundary(t, patch, solid.normal), infiniteBoundary(kInf)}};
    }
    case Kind::kBox: {
      const Vec3 o = solid.rotation.transpose() * (origin - solid.center);
      const Vec3 d = solid.rotation.transpose() * dir;
      double t_near = -kInf, t_far = kInf;
      Vec3 n_near = Vec3::Zero(), n_far = Vec3::Zero();
      for (int k = 0; k < 3; ++k) {
        const double h = solid.semi_axes[k];
        if (std::abs(d[k]) < 1e-300) {
          if (std::abs(o[k]) > h) return {};
          continue;
        }
        const double sign = d[k] > 0 ? 1.0 : -1.0;
        const double t0 = (-sign * h - o[k]) / d[k], t1 = (sign * h - o[k]) / d[k];
        if (t0 > t_near) {
          t_near = t0;
          n_near = -sign * solid.rotation.col(k);
        }
        if (t1 < t_far) {
          t_far = t1;
          n_far = sign * solid.rotation.col(k);
        }
      }
      if (!(t_near < t_far)) return {};
      return {{boundary(t_near, patch, n_near), boundary(t_far, patch, n_far)}};
    }
  }
  return {};
}

IntervalList intervalUnion(const IntervalList& a, const IntervalList& b) {
  return combine(a, b, [](bool x, bool y) { return x || y; });
}

IntervalList intervalIntersection(const IntervalList& a, const IntervalList& b) {
  return combine(a, b, [](bool x, bool y) { return x && y; });
}

IntervalList intervalDifference(const IntervalList& a, const IntervalList& b) {
  return combine(a, b, [](bool x, bool y) { return x && !y; });
}

IntervalList intervalComplement(const IntervalList& a) {
  return combine(a, {}, [](bool x, bool) { return !x; });
}

AnalyticCsgCaster::AnalyticCsgCaster(std::vector<AnalyticSolid> solids, CsgTree tree)
    : solids_(std::move(solids)), tree_(std::move(tree)) {
  if (tree_.empty()) throw std::invalid_argument("AnalyticCsgCaster: empty CSG tree");
  for (int patch : tree_.patches()) {
    if (patch < 0 || size_t(patch) >= solids_.size())
      throw std::invalid_argument("AnalyticCsgCaster: CSG leaf patch " + std::to_string(patch) +
                                  " has no analytic solid (" + std::to_string(solids_.size()) + " solids)");
  }
}

IntervalList AnalyticCsgCaster::evaluate(int node, const Vec3& origin, const Vec3& dir) const {
  const CsgTree::Node& n = tree_.node(node);
  switch (n.op) {
    case CsgTree::Op::kLeaf: {
      IntervalList leaf = solidIntervals(solids_[n.patch], n.patch, origin, dir);
      return n.inverted ? intervalComplement(leaf) : leaf;
    }
    case CsgTree::Op::kUnion:
      return intervalUnion(evaluate(n.left, origin, dir), evaluate(n.right, origin, dir));
    case CsgTree::Op::kIntersection:
      return intervalIntersection(evaluate(n.left, origin, dir), evaluate(n.right, origin, dir));
    case CsgTree::Op::kDifference:
      return intervalDifference(evaluate(n.left, origin, dir), evaluate(n.right, origin, dir));
    case CsgTree::Op::kComplement:
      return intervalComplement(evaluate(n.left, origin, dir));
  }
  return {};
}

IntervalList AnalyticCsgCaster::intervals(const Vec3& origin, const Vec3& dir) const {
  return evaluate(tree_.root(), origin, dir);
}

AnalyticHit AnalyticCsgCaster::cast(const Vec3& origin, const Vec3& dir, double t_min) const {
  AnalyticHit hit;
  for (const RayInterval& interval : intervals(origin, dir)) {
    for (const RayBoundary* b : {&interval.enter, &interval.leave}) {
      if (b->t > t_min && std::isfinite(b->t)) {
        hit.hit = true;
        hit.t = b->t;
        hit.patch = b->patch;
        hit.normal = b->normal;
        return hit;
      }
    }
  }
  return hit;
}

bool AnalyticCsgCaster::containsNode(int node, const Vec3& x) const {
  const CsgTree::Node& n = tree_.node(node);
  switch (n.op) {
    case CsgTree::Op::kLeaf:
      return solids_[n.patch].contains(x) != n.inverted;
    case CsgTree::Op::kUnion:
      return containsNode(n.left, x) || containsNode(n.right, x);
    case CsgTree::Op::kIntersection:
      return containsNode(n.left, x) && containsNode(n.right, x);
    case CsgTree::Op::kDifference:
      return containsNode(n.left, x) && !containsNode(n.right, x);
    case CsgTree::Op::kComplement:
      return !containsNode(n.left, x);
  }
  return false;
}

bool AnalyticCsgCaster::contains(const Vec3& x) const {
  return containsNode(tree_.root(), x);
}

AnalyticImages castImage(const AnalyticCsgCaster& caster, const Camera& camera) {
  camera.validate();
  AnalyticImages out;
  out.width = camera.width;
  out.height = camera.height;
  const size_t n = size_t(camera.width) * camera.height;
  out.depth.assign(n, std::numeric_limits<float>::infinity());
  out.patch_id.assign(n, -1);
  out.normal.assign(n, Eigen::Vector3f::Zero());
  const Vec3 eye = camera.world_T_camera.translation();
  const Vec3 forward = camera.world_T_camera.linear().col(2);
#pragma omp parallel for schedule(dynamic, 4)
  for (int64_t v = 0; v < int64_t(camera.height); ++v) {
    for (uint32_t u = 0; u < camera.width; ++u) {
      Vec3 origin, dir;
      camera.pixelRay(u, double(v), &origin, &dir);
      // Camera z grows along the ray at rate dir . forward; skip surfaces in front of the near plane.
      const double z0 = (origin - eye).dot(forward), rate = dir.dot(forward);
      const double t_min = (camera.near_clip - z0) / rate;
      const AnalyticHit hit = caster.cast(origin, dir, t_min);
      if (!hit.hit) continue;
      const size_t i = size_t(v) * camera.width + u;
      out.depth[i] = float(z0 + hit.t * rate);
      out.patch_id[i] = hit.patch;
      out.normal[i] = hit.normal.cast<float>();
    }
  }
  return out;
}

}  // namespace rc
