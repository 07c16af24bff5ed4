#include "relaxed_connectivity/shell/shell_skinning.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/core/surfel_attributes.h"

namespace rc {
namespace {

constexpr size_t kParallelSurfels = 1024;

struct Frame {
  Vec3 e1, e2, e3;
};

// (7.26)
Frame makeFrame(const Vec3& x0, const Vec3& xi, const Vec3& normal) {
  Frame f;
  f.e1 = xi - x0;
  const double l = f.e1.norm();
  f.e2 = normal.cross(f.e1) / l;
  f.e3 = f.e2.cross(f.e1) / l;
  return f;
}

// (7.27) for a vector v (p - x_0 for positions).
Vec3 toLocal(const Frame& f, const Vec3& v) {
  return Vec3(v.dot(f.e1) / f.e1.squaredNorm(), v.dot(f.e2) / f.e2.squaredNorm(),
              v.dot(f.e3) / f.e3.squaredNorm());
}

// Least-squares plane normal of the points, oriented along `reference` (unchanged if fewer than 3 points).
Vec3 planeNormal(const std::vector<Vec3>& x, const uint32_t* ids, size_t count, const Vec3& reference) {
  if (count < 3) return reference.normalized();
  Vec3 c = Vec3::Zero();
  for (size_t m = 0; m < count; ++m) c += x[ids[m]];
  c /= double(count);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t m = 0; m < count; ++m) {
    const Vec3 d = x[ids[m]] - c;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(cov);  // closed form: the smallest eigenvalue is well separated for a plane fit
  Vec3 n = eig.eigenvectors().col(0);
  return n.dot(reference) < 0.0 ? Vec3(-n) : n;
}

double skinWeight(double t) {  // (7.30): w(0) = inf, w(1) = 0, smooth
  t = std::max(t, 1e-9);
  const double a = (1.0 - t * t) / t;
  return t >= 1.0 ? 0.0 : a * a;
}

}  // namespace

struct ShellSkinning::Binder {
  const SurfelCloud& rest;
  const ShellNodes& nodes;
  const std::vector<ShellCrack>& cracks;
  const KdTree& tree;
  const Attribute* roles;
  size_t candidates;
  double offset;
  Binder(const SurfelCloud& rest_, const ShellNodes& nodes_, const std::vector<ShellCrack>& cracks_,
         const KdTree& tree_, size_t node_count)
      : rest(rest_),
        nodes(nodes_),
        cracks(cracks_),
        tree(tree_),
        roles(rest_.attributes.find(kSurfelRoleAttribute)),
        candidates(std::min(nodes_.size(), 4 * node_count)),
        offset(1e-6 * std::max(nodes_.spacing, 1e-12)) {}
  /// Point a surfel is bound from: discontinuity surfels on their material side, behind the normal.
  Vec3 bindPoint(size_t s) const {
    const Vec3& p = rest.positions[s];
    const bool discontinuity =
        roles && std::lround(roles->get(s)) == surfelRoleValue(SurfelRole::kDiscontinuity);
    return discontinuity ? Vec3(p - offset * rest.normals[s].normalized()) : p;
  }
};

bool ShellSkinning::bindSurfel(const Binder& b, size_t s, uint32_t* ids, uint8_t* set_size,
                               uint8_t* frame_count, uint8_t* frame_slots, double* weights,
                               Vec3* coords) const {
  const SurfelCloud& rest = b.rest;
  const std::vector<Vec3>& xr = b.nodes.rest_positions;
  const size_t per_frame = has_axes_ ? 4 : 2;
  const Vec3& p = rest.positions[s];
  const Vec3 normal = rest.normals[s].normalized();
  const Vec3 bind = b.bindPoint(s);
  thread_local std::vector<Neighbor> found;
  found.resize(b.candidates);
  const size_t got = b.tree.knn(bind, b.candidates, found.data());
  // Only cracks within radius + (farthest candidate) of the bind point can cut a segment to a candidate.
  thread_local std::vector<const ShellCrack*> near;
  near.clear();
  if (!b.cracks.empty() && got > 0) {
    const double far_candidate = std::sqrt(found[got - 1].sq_dist);
    for (const ShellCrack& k : b.cracks) {
      const double reach = (k.radius + far_candidate) * (1.0 + 1e-9);
      if ((k.center - bind).squaredNorm() <= reach * reach) near.push_back(&k);
    }
  }
  size_t m = 0;
  for (size_t c = 0; c < got && m < node_count_; ++c) {
    const Vec3& node = xr[found[c].index];
    bool visible = true;
    for (size_t k = 0; k < near.size() && visible; ++k) visible = !crackSeparates(*near[k], bind, node);
    if (visible) ids[m++] = found[c].index;
  }
  *set_size = 0;
  *frame_count = 0;
  if (m == 0) return false;
  *set_size = static_cast<uint8_t>(m);
  Vec3 reference = Vec3::Zero();
  for (size_t j = 0; j < m; ++j) reference += b.nodes.rest_normals[ids[j]];
  const Vec3 plane = planeNormal(xr, ids, m, reference.norm() > 0.0 ? reference : normal);
  const double far = (xr[ids[m - 1]] - p).norm();
  const Vec3 local = p - xr[ids[0]];
  size_t f = 0;
  double sum = 0.0;
  for (size_t j = 1; j < m; ++j) {
    const double w = far > 0.0 ? skinWeight((xr[ids[j]] - p).norm() / far) : 0.0;
    const Frame frame = makeFrame(xr[ids[0]], xr[ids[j]], plane);
    if (!(w > 0.0) || frame.e2.squaredNorm() < 1e-4) continue;  // e_1 nearly along N: no frame
    frame_slots[f] = static_cast<uint8_t>(j);
    weights[f] = w;
    Vec3* c = coords + f * per_frame;
    c[0] = toLocal(frame, local);
    c[1] = toLocal(frame, normal);
    if (has_axes_) c[2] = toLocal(frame, rest.axes1[s]), c[3] = toLocal(frame, rest.axes2[s]);
    sum += w;
    ++f;
  }
  for (size_t q = 0; q < f; ++q) weights[q] /= sum;  // (7.29)
  if (f == 0) {  // no usable frame (a single visible node): move rigidly with x_0, no rotation
    coords[0] = local, coords[1] = normal;
    if (has_axes_) coords[2] = rest.axes1[s], coords[3] = rest.axes2[s];
  }
  *frame_count = static_cast<uint8_t>(f);
  return true;
}

ShellSkinning::ShellSkinning(const SurfelCloud& rest, const ShellNodes& nodes,
                             const std::vector<ShellCrack>& cracks, const ShellSkinningOptions& options) {
  if (options.node_count < 2 || options.node_count > 255) {
    throw std::invalid_argument("ShellSkinningOptions::node_count must be in [2, 255]");
  }
  if (!rest.hasNormals()) throw std::invalid_argument("ShellSkinning: the rest cloud needs normals");
  rest.validate();
  if (nodes.size() < 1) throw std::invalid_argument("ShellSkinning: no nodes");
  surfel_count_ = rest.size();
  node_count_ = std::min(options.node_count, nodes.size());
  has_axes_ = rest.hasAxes();
  const size_t frames = node_count_ - 1, per_frame = has_axes_ ? 4 : 2;
  node_ids_.assign(surfel_count_ * node_count_, 0);
  frame_count_.assign(surfel_count_, 0);
  weights_.assign(surfel_count_ * frames, 0.0);
  coords_.assign(surfel_count_ * frames * per_frame, Vec3::Zero());
  frame_slots_.assign(surfel_count_ * frames, 0);
  set_size_.assign(surfel_count_, 0);
  const KdTree tree(nodes.rest_positions);
  const Binder binder(rest, nodes, cracks, tree, node_count_);
  std::vector<char> isolated(surfel_count_, 0);
#pragma omp parallel for schedule(static) if (surfel_count_ >= kParallelSurfels)
  for (size_t s = 0; s < surfel_count_; ++s) {
    isolated[s] = !bindSurfel(binder, s, node_ids_.data() + s * node_count_, &set_size_[s], &frame_count_[s],
                              frame_slots_.data() + s * frames, weights_.data() + s * frames,
                              coords_.data() + s * frames * per_frame);
  }
  for (size_t s = 0; s < surfel_count_; ++s) {
    if (isolated[s]) {
      throw std::invalid_argument("ShellSkinning: surfel " + std::to_string(s) +
                                  " sees no node (all candidates are behind cracks)");
    }
  }
  plane_set_.assign(surfel_count_, 0);
  for (size_t s = 0; s < surfel_count_; ++s) assignPlaneSet(s);
  bound_cracks_ = cracks.size();
  last_rebound_ = surfel_count_;
}

void ShellSkinning::assignPlaneSet(size_t s) {
  const size_t m = set_size_[s];
  uint32_t sorted[256];
  std::copy_n(node_ids_.data() + s * node_count_, m, sorted);
  std::sort(sorted, sorted + m);
  std::string key(reinterpret_cast<const char*>(sorted), m * sizeof(uint32_t));
  const auto [it, inserted] = set_index_.emplace(std::move(key), static_cast<uint32_t>(set_sizes_.size()));
  if (inserted) {
    set_ids_.insert(set_ids_.end(), sorted, sorted + m);
    set_ids_.resize(set_ids_.size() + node_count_ - m, 0);
    set_sizes_.push_back(static_cast<uint8_t>(m));
  }
  plane_set_[s] = it->second;
}

size_t ShellSkinning::rebind(const SurfelCloud& rest, const ShellNodes& nodes,
                             const std::vector<ShellCrack>& cracks) {
  if (rest.size() < surfel_count_ || cracks.size() < bound_cracks_ || rest.hasAxes() != has_axes_ ||
      !rest.hasNormals()) {
    throw std::invalid_argument(
        "ShellSkinning::rebind: the cloud and cracks must extend those bound (same channels)");
  }
  rest.validate();
  const size_t old_count = surfel_count_, count = rest.size();
  const size_t frames = node_count_ - 1, per_frame = has_axes_ ? 4 : 2;
  const KdTree tree(nodes.rest_positions);
  const Binder binder(rest, nodes, cracks, tree, node_count_);
  // Surfels cut from one of their nodes by a new crack (the rest keep P_p exactly), then appended ones.
  const std::vector<Vec3>& xr = nodes.rest_positions;
  std::vector<char> affected(old_count, 0);
  if (cracks.size() > bound_cracks_) {
#pragma omp parallel for schedule(static) if (old_count >= kParallelSurfels)
    for (size_t s = 0; s < old_count; ++s) {
      const Vec3 bind = binder.bindPoint(s);
      const uint32_t* ids = node_ids_.data() + s * node_count_;
      const size_t m = set_size_[s];
      const double far_node = m > 0 ? (xr[ids[m - 1]] - bind).norm() : 0.0;  // P_p is nearest first
      bool cut = false;
      for (size_t c = bound_cracks_; c < cracks.size() && !cut; ++c) {
        const ShellCrack& k = cracks[c];
        const double reach = (k.radius + far_node) * (1.0 + 1e-9);
        if ((k.center - bind).squaredNorm() > reach * reach) continue;  // cannot reach a segment to P_p
        for (size_t j = 0; j < m && !cut; ++j) cut = crackSeparates(k, bind, xr[ids[j]]);
      }
      affected[s] = cut;
    }
  }
  std::vector<size_t> todo;
  for (size_t s = 0; s < old_count; ++s)
    if (affected[s]) todo.push_back(s);
  for (size_t s = old_count; s < count; ++s) todo.push_back(s);
  const size_t t = todo.size();
  std::vector<uint32_t> ids(t * node_count_, 0);
  std::vector<uint8_t> sizes(t, 0), nframes(t, 0), slots(t * frames, 0);
  std::vector<double> weights(t * frames, 0.0);
  std::vector<Vec3> coords(t * frames * per_frame, Vec3::Zero());
  std::vector<char> seen(t, 0);
#pragma omp parallel for schedule(dynamic, 64) if (t >= 256)
  for (size_t r = 0; r < t; ++r) {
    seen[r] = bindSurfel(binder, todo[r], ids.data() + r * node_count_, &sizes[r], &nframes[r],
                         slots.data() + r * frames, weights.data() + r * frames,
                         coords.data() + r * frames * per_frame);
  }
  for (size_t r = 0; r < t; ++r) {
    if (!seen[r] && todo[r] >= old_count) {
      throw std::invalid_argument("ShellSkinning::rebind: surfel " + std::to_string(todo[r]) +
                                  " sees no node (all candidates are behind cracks)");
    }
  }
  surfel_count_ = count;
  node_ids_.resize(count * node_count_, 0);
  set_size_.resize(count, 0);
  frame_count_.resize(count, 0);
  frame_slots_.resize(count * frames, 0);
  weights_.resize(count * frames, 0.0);
  coords_.resize(count * frames * per_frame, Vec3::Zero());
  plane_set_.resize(count, 0);
  size_t kept = 0;
  for (size_t r = 0; r < t; ++r) {
    if (!seen[r]) {  // an old surfel now behind cracks on all sides: keep its binding
      ++kept;
      continue;
    }
    const size_t s = todo[r];
    std::copy_n(ids.data() + r * node_count_, node_count_, node_ids_.data() + s * node_count_);
    set_size_[s] = sizes[r];
    frame_count_[s] = nframes[r];
    std::copy_n(slots.data() + r * frames, frames, frame_slots_.data() + s * frames);
    std::copy_n(weights.data() + r * frames, frames, weights_.data() + s * frames);
    std::copy_n(coords.data() + r * frames * per_frame, frames * per_frame,
                coords_.data() + s * frames * per_frame);
    assignPlaneSet(s);
  }
  bound_cracks_ = cracks.size();
  last_rebound_ = t - kept;
  return kept;
}

void ShellSkinning::deform(const ShellNodes& nodes, const std::vector<Vec3>& x, SurfelCloud* out) const {
  if (x.size() != nodes.size())
    throw std::invalid_argument("ShellSkinning::deform: position count differs from node count");
  if (out->size() != surfel_count_) out->positions.resize(surfel_count_);
  out->normals.resize(surfel_count_);
  if (has_axes_) out->axes1.resize(surfel_count_), out->axes2.resize(surfel_count_);
  const size_t sets = set_sizes_.size();
  fan_.resize(nodes.size());
  set_normals_.resize(sets);
  Vec3* fan = fan_.data();
  Vec3* planes = set_normals_.data();
  const size_t frames = node_count_ - 1, per_frame = has_axes_ ? 4 : 2;
#pragma omp parallel if (surfel_count_ >= kParallelSurfels)
  {
#pragma omp for schedule(static)
    for (size_t i = 0; i < nodes.size(); ++i) fan[i] = fanNormal(nodes, i, x);
#pragma omp for schedule(static)
    for (size_t c = 0; c < sets; ++c) {  // plane normal of each distinct P_p, once
      const uint32_t* ids = set_ids_.data() + c * node_count_;
      const size_t m = set_sizes_[c];
      Vec3 reference = Vec3::Zero();
      for (size_t j = 0; j < m; ++j) reference += fan[ids[j]];
      planes[c] = planeNormal(x, ids, m, reference);
    }
#pragma omp for schedule(static)
    for (size_t s = 0; s < surfel_count_; ++s) {
      const uint32_t* ids = node_ids_.data() + s * node_count_;
      const size_t nf = frame_count_[s];
      const Vec3& x0 = x[ids[0]];
      const Vec3* c = coords_.data() + s * frames * per_frame;
      if (nf == 0) {  // no frame: translate with x_0
        out->positions[s] = x0 + c[0];
        out->normals[s] = c[1];
        if (has_axes_) out->axes1[s] = c[2], out->axes2[s] = c[3];
        continue;
      }
      const Vec3 plane = planes[plane_set_[s]];
      const uint8_t* slots = frame_slots_.data() + s * frames;
      const double* weights = weights_.data() + s * frames;
      Vec3 p = Vec3::Zero(), n = Vec3::Zero(), a1 = Vec3::Zero(), a2 = Vec3::Zero();
      for (size_t q = 0; q < nf; ++q, c += per_frame) {  // (7.26), (7.28), (7.29)
        const Vec3 e1 = x[ids[slots[q]]] - x0;
        const double inv_l = 1.0 / e1.norm();
        const Vec3 e2 = plane.cross(e1) * inv_l;
        const Vec3 e3 = e2.cross(e1) * inv_l;
        const double w = weights[q];
        p += w * (c[0].x() * e1 + c[0].y() * e2 + c[0].z() * e3);
        n += w * (c[1].x() * e1 + c[1].y() * e2 + c[1].z() * e3);
        if (has_axes_) {
          a1 += w * (c[2].x() * e1 + c[2].y() * e2 + c[2].z() * e3);
          a2 += w * (c[3].x() * e1 + c[3].y() * e2 + c[3].z() * e3);
        }
      }
      out->positions[s] = x0 + p;
      out->normals[s] = n.normalized();
      if (has_axes_) out->axes1[s] = a1, out->axes2[s] = a2;
    }
  }
}

SurfelCloud crackDiscontinuitySurfels(const std::vector<ShellCrack>& cracks) {
  SurfelCloud cloud;
  const size_t n = 2 * cracks.size();
  cloud.attributes.add(kSurfelRoleAttribute, ScalarType::kInt32, 1,
                       n);  // add all first: add() may reallocate
  cloud.attributes.add(kPatchIdAttribute, ScalarType::kInt32, 1, n);
  cloud.attributes.add("crack_side", ScalarType::kInt32, 1, n);
  Attribute& role = *cloud.attributes.find(kSurfelRoleAttribute);
  Attribute& patch = *cloud.attributes.find(kPatchIdAttribute);
  Attribute& side = *cloud.attributes.find("crack_side");
  for (size_t c = 0; c < cracks.size(); ++c) {
    const ShellCrack& k = cracks[c];
    const Vec3 nrm = k.normal.normalized();
    const Vec3 u = nrm.cross(std::abs(nrm.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).normalized();
    const Vec3 v = nrm.cross(u);
    for (int sign : {1, -1}) {
      const size_t s = cloud.positions.size();
      cloud.positions.push_back(k.center);
      cloud.normals.push_back(sign * nrm);
      cloud.radii.push_back(k.radius);
      cloud.axes1.push_back(k.radius * u);
      cloud.axes2.push_back(sign * k.radius * v);  // t1 x t2 = normal
      role.set(s, surfelRoleValue(SurfelRole::kDiscontinuity));
      patch.set(s, 1.0 + c);
      side.set(s, sign);
    }
  }
  return cloud;
}

}  // namespace rc
