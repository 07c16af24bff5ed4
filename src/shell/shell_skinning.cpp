#include "shell/shell_skinning.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/kd_tree.h"

namespace rc {
namespace {

constexpr int32_t kDiscontinuityRole = 1;  // kRoleDiscontinuity in src/render/scene.h
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

Vec3 toWorld(const Frame& f, const Vec3& y) {
  return y.x() * f.e1 + y.y() * f.e2 + y.z() * f.e3;
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
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Vec3 n = eig.eigenvectors().col(0);
  return n.dot(reference) < 0.0 ? Vec3(-n) : n;
}

double skinWeight(double t) {  // (7.30): w(0) = inf, w(1) = 0, smooth
  t = std::max(t, 1e-9);
  const double a = (1.0 - t * t) / t;
  return t >= 1.0 ? 0.0 : a * a;
}

}  // namespace

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
  const Attribute* roles = rest.attributes.find("surfel_role");
  const std::vector<Vec3>& xr = nodes.rest_positions;
  KdTree tree(xr);
  const size_t candidates = std::min(nodes.size(), 4 * node_count_);
  const double offset = 1e-6 * std::max(nodes.spacing, 1e-12);
  std::vector<char> isolated(surfel_count_, 0);
#pragma omp parallel for schedule(static) if (surfel_count_ >= kParallelSurfels)
  for (size_t s = 0; s < surfel_count_; ++s) {
    const Vec3& p = rest.positions[s];
    const Vec3 normal = rest.normals[s].normalized();
    const bool discontinuity = roles && std::lround(roles->get(s)) == kDiscontinuityRole;
    const Vec3 bind = discontinuity ? Vec3(p - offset * normal) : p;  // material side: behind the normal
    std::vector<Neighbor> found(candidates);
    const size_t got = tree.knn(bind, candidates, found.data());
    uint32_t* ids = node_ids_.data() + s * node_count_;
    size_t m = 0;
    for (size_t c = 0; c < got && m < node_count_; ++c) {
      if (cracks.empty() || crackVisible(cracks, bind, xr[found[c].index])) ids[m++] = found[c].index;
    }
    if (m == 0) {
      isolated[s] = 1;
      continue;
    }
    set_size_[s] = static_cast<uint8_t>(m);
    Vec3 reference = Vec3::Zero();
    for (size_t j = 0; j < m; ++j) reference += nodes.rest_normals[ids[j]];
    const Vec3 plane = planeNormal(xr, ids, m, reference.norm() > 0.0 ? reference : normal);
    const double far = (xr[ids[m - 1]] - p).norm();
    const Vec3 local = p - xr[ids[0]];
    size_t f = 0;
    double sum = 0.0;
    for (size_t j = 1; j < m; ++j) {
      const double w = far > 0.0 ? skinWeight((xr[ids[j]] - p).norm() / far) : 0.0;
      const Frame frame = makeFrame(xr[ids[0]], xr[ids[j]], plane);
      if (!(w > 0.0) || frame.e2.squaredNorm() < 1e-4) continue;  // e_1 nearly along N: no frame
      const size_t slot = s * frames + f;
      frame_slots_[slot] = static_cast<uint8_t>(j);
      weights_[slot] = w;
      Vec3* c = coords_.data() + slot * per_frame;
      c[0] = toLocal(frame, local);
      c[1] = toLocal(frame, normal);
      if (has_axes_) c[2] = toLocal(frame, rest.axes1[s]), c[3] = toLocal(frame, rest.axes2[s]);
      sum += w;
      ++f;
    }
    for (size_t q = 0; q < f; ++q) weights_[s * frames + q] /= sum;  // (7.29)
    if (f == 0) {  // no usable frame (a single visible node): move rigidly with x_0, no rotation
      Vec3* c = coords_.data() + s * frames * per_frame;
      c[0] = local, c[1] = normal;
      if (has_axes_) c[2] = rest.axes1[s], c[3] = rest.axes2[s];
    }
    frame_count_[s] = static_cast<uint8_t>(f);
  }
  for (size_t s = 0; s < surfel_count_; ++s) {
    if (isolated[s]) {
      throw std::invalid_argument("ShellSkinning: surfel " + std::to_string(s) +
                                  " sees no node (all candidates are behind cracks)");
    }
  }
}

void ShellSkinning::deform(const ShellNodes& nodes, const std::vector<Vec3>& x, SurfelCloud* out) const {
  if (x.size() != nodes.size())
    throw std::invalid_argument("ShellSkinning::deform: position count differs from node count");
  if (out->size() != surfel_count_) out->positions.resize(surfel_count_);
  out->normals.resize(surfel_count_);
  if (has_axes_) out->axes1.resize(surfel_count_), out->axes2.resize(surfel_count_);
  std::vector<Vec3> fan(nodes.size());
#pragma omp parallel for schedule(static) if (nodes.size() >= kParallelSurfels)
  for (size_t i = 0; i < nodes.size(); ++i) fan[i] = fanNormal(nodes, i, x);
  const size_t frames = node_count_ - 1, per_frame = has_axes_ ? 4 : 2;
#pragma omp parallel for schedule(static) if (surfel_count_ >= kParallelSurfels)
  for (size_t s = 0; s < surfel_count_; ++s) {
    const uint32_t* ids = node_ids_.data() + s * node_count_;
    const size_t m = set_size_[s], nf = frame_count_[s];
    const Vec3& x0 = x[ids[0]];
    if (nf == 0) {  // no frame: translate with x_0
      const Vec3* c = coords_.data() + s * frames * per_frame;
      out->positions[s] = x0 + c[0];
      out->normals[s] = c[1];
      if (has_axes_) out->axes1[s] = c[2], out->axes2[s] = c[3];
      continue;
    }
    Vec3 reference = Vec3::Zero();
    for (size_t j = 0; j < m; ++j) reference += fan[ids[j]];
    const Vec3 plane = planeNormal(x, ids, m, reference);
    Vec3 p = Vec3::Zero(), n = Vec3::Zero(), a1 = Vec3::Zero(), a2 = Vec3::Zero();
    for (size_t q = 0; q < nf; ++q) {  // (7.28), (7.29)
      const size_t slot = s * frames + q;
      const Frame frame = makeFrame(x0, x[ids[frame_slots_[slot]]], plane);
      const double w = weights_[slot];
      const Vec3* c = coords_.data() + slot * per_frame;
      p += w * toWorld(frame, c[0]);
      n += w * toWorld(frame, c[1]);
      if (has_axes_) a1 += w * toWorld(frame, c[2]), a2 += w * toWorld(frame, c[3]);
    }
    out->positions[s] = x0 + p;
    out->normals[s] = n.normalized();
    if (has_axes_) out->axes1[s] = a1, out->axes2[s] = a2;
  }
}

SurfelCloud crackDiscontinuitySurfels(const std::vector<ShellCrack>& cracks) {
  SurfelCloud cloud;
  const size_t n = 2 * cracks.size();
  cloud.attributes.add("surfel_role", ScalarType::kInt32, 1, n);  // add all first: add() may reallocate
  cloud.attributes.add("patch_id", ScalarType::kInt32, 1, n);
  cloud.attributes.add("crack_side", ScalarType::kInt32, 1, n);
  Attribute& role = *cloud.attributes.find("surfel_role");
  Attribute& patch = *cloud.attributes.find("patch_id");
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
      role.set(s, kDiscontinuityRole);
      patch.set(s, 1.0 + c);
      side.set(s, sign);
    }
  }
  return cloud;
}

}  // namespace rc
