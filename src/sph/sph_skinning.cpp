#include "relaxed_connectivity/sph/sph_skinning.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <map>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <Eigen/Eigenvalues>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/sph/sph_kernels.h"

namespace rc {
namespace {

/// Fewer points than this are blended on one thread (a parallel region costs more than it saves).
constexpr std::ptrdiff_t kParallelPoints = 4096;

using Mat3 = Eigen::Matrix3d;

bool finite(const Vec3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

/// Cofactor matrix cof(J) = det(J) J^-T, defined for singular J too (Nanson: n da = cof(J) N dA).
Mat3 cofactor(const Mat3& j) {
  Mat3 c;
  c.col(0) = j.col(1).cross(j.col(2));
  c.col(1) = j.col(2).cross(j.col(0));
  c.col(2) = j.col(0).cross(j.col(1));
  return c;
}

/// Poly6 shape (1 - d^2/h^2)^3 (C.1 without its constant) for the affine fit.
double poly6Shape(double sq_dist, double h2) {
  if (sq_dist >= h2) return 0.0;
  const double t = 1.0 - sq_dist / h2;
  return t * t * t;
}

}  // namespace

void SphSkinConfig::validate() const {
  if (!std::isfinite(support_radius) || support_radius <= 0.0)
    throw std::invalid_argument("SphSkinConfig: support_radius must be finite and > 0, got " +
                                std::to_string(support_radius));
  if (!std::isfinite(fit_radius) || fit_radius < 0.0)
    throw std::invalid_argument("SphSkinConfig: fit_radius must be finite and >= 0, got " +
                                std::to_string(fit_radius));
  if (dimension != 2 && dimension != 3)
    throw std::invalid_argument("SphSkinConfig: dimension must be 2 or 3, got " + std::to_string(dimension));
}

std::vector<uint32_t> solidParticleIndices(const SphParticles& particles, uint8_t phase) {
  std::vector<uint32_t> out;
  for (size_t i = 0; i < particles.size(); ++i)
    if (particles.phases[i] == phase && particles.kinds[i] == SphParticleKind::kFluid)
      out.push_back(static_cast<uint32_t>(i));
  return out;
}

SphSkin::SphSkin(const SphSkinRest& rest, const std::vector<Vec3>& rest_points, const SphSkinConfig& config)
    : config_(config), system_size_(rest.positions.size()), rest_points_(rest_points) {
  config_.validate();
  const size_t n = system_size_;
  if (n > UINT32_MAX) throw std::invalid_argument("SphSkin: more than 2^32 particles");
  if (!rest.volumes.empty() && rest.volumes.size() != n)
    throw std::invalid_argument("SphSkin: rest.volumes has " + std::to_string(rest.volumes.size()) +
                                " entries for " + std::to_string(n) + " particles");
  if (!rest.transforms.empty() && rest.transforms.size() != n)
    throw std::invalid_argument("SphSkin: rest.transforms has " + std::to_string(rest.transforms.size()) +
                                " entries for " + std::to_string(n) + " particles");
  for (size_t p = 0; p < rest_points_.size(); ++p)
    if (!finite(rest_points_[p]))
      throw std::invalid_argument("SphSkin: rest surface point " + std::to_string(p) + " is not finite");

  // The solid's particles (compact index c).
  std::vector<uint32_t> solid = rest.solid;
  if (rest.solid.empty()) {
    solid.resize(n);
    for (size_t i = 0; i < n; ++i) solid[i] = static_cast<uint32_t>(i);
  }
  std::vector<Vec3> solid_positions(solid.size());
  for (size_t c = 0; c < solid.size(); ++c) {
    const uint32_t g = solid[c];
    if (g >= n)
      throw std::invalid_argument("SphSkin: rest.solid[" + std::to_string(c) + "] = " + std::to_string(g) +
                                  " is out of range (" + std::to_string(n) + " particles)");
    if (!finite(rest.positions[g]))
      throw std::invalid_argument("SphSkin: rest position of particle " + std::to_string(g) +
                                  " is not finite");
    if (!rest.volumes.empty() && !(std::isfinite(rest.volumes[g]) && rest.volumes[g] > 0.0))
      throw std::invalid_argument("SphSkin: volume of particle " + std::to_string(g) +
                                  " must be finite and > 0");
    solid_positions[c] = rest.positions[g];
  }
  const size_t point_count = rest_points_.size();
  pair_begin_.assign(point_count + 1, 0);
  weight_sum_.assign(point_count, 0.0);
  points_ = rest_points_;
  jacobians_.assign(point_count, Mat3::Identity());
  if (point_count == 0) return;
  if (solid.empty())
    throw std::invalid_argument("SphSkin: " + std::to_string(point_count) +
                                " surface points but no solid particles to bind them to");

  // Binding (8.38): particles within the support of each rest point.
  const double h = config_.support_radius, h2 = h * h;
  const SphKernels kernels(config_.dimension, h);
  const KdTree tree(solid_positions);
  std::vector<size_t> offsets;
  std::vector<Neighbor> found;
  tree.radiusBatch(rest_points_, h, offsets, found);
  std::vector<int64_t> compact_of_solid(solid.size(), -1);
  std::vector<Neighbor> nearest(1);
  for (size_t p = 0; p < point_count; ++p) {
    const size_t begin = pair_particle_.size();
    double sum = 0.0;
    for (size_t k = offsets[p]; k < offsets[p + 1]; ++k) {
      const Neighbor& nb = found[k];
      if (nb.sq_dist >= h2) continue;  // W_h(h) = 0
      const uint32_t g = solid[nb.index];
      const double w = (rest.volumes.empty() ? 1.0 : rest.volumes[g]) * kernels.poly6(nb.sq_dist);
      if (compact_of_solid[nb.index] < 0) {
        compact_of_solid[nb.index] = static_cast<int64_t>(bound_.size());
        bound_.push_back(g);
      }
      pair_particle_.push_back(static_cast<uint32_t>(compact_of_solid[nb.index]));
      pair_weight_.push_back(w);
      pair_offset_.push_back(rest_points_[p] - rest.positions[g]);
      sum += w;
    }
    if (pair_particle_.size() == begin) {
      tree.knn(rest_points_[p], 1, nearest.data());
      if (config_.orphans == SphSkinOrphanPolicy::kThrow)
        throw std::invalid_argument("SphSkin: surface point " + std::to_string(p) +
                                    " has no solid particle within support_radius " + std::to_string(h) +
                                    " (nearest at distance " + std::to_string(std::sqrt(nearest[0].sq_dist)) +
                                    ")");
      const uint32_t c = nearest[0].index, g = solid[c];
      if (compact_of_solid[c] < 0) {
        compact_of_solid[c] = static_cast<int64_t>(bound_.size());
        bound_.push_back(g);
      }
      pair_particle_.push_back(static_cast<uint32_t>(compact_of_solid[c]));
      pair_weight_.push_back(1.0);
      pair_offset_.push_back(rest_points_[p] - rest.positions[g]);
      ++orphans_;
    } else {
      weight_sum_[p] = sum;
      for (size_t k = begin; k < pair_particle_.size(); ++k) pair_weight_[k] /= sum;
    }
    pair_begin_[p + 1] = pair_particle_.size();
  }

  // Rest transforms of the bound particles.
  const size_t bound_count = bound_.size();
  rest_transform_.resize(bound_count);
  rest_inverse_.resize(bound_count);
  current_.assign(bound_count, Mat3::Identity());
  for (size_t l = 0; l < bound_count; ++l) {
    const Mat3& a = rest.transforms.empty() ? rest.uniform_transform : rest.transforms[bound_[l]];
    const double scale = a.norm();
    if (!a.allFinite() || !(std::abs(a.determinant()) > 1e-12 * scale * scale * scale))
      throw std::invalid_argument("SphSkin: rest transform of particle " + std::to_string(bound_[l]) +
                                  " is singular or not finite");
    rest_transform_[l] = a;
    rest_inverse_[l] = a.inverse();
  }

  // Rest neighbourhoods of the bound particles for the affine fit of fitTransforms().
  const double fit_radius = config_.fit_radius > 0.0 ? config_.fit_radius : h;
  const double fit_r2 = fit_radius * fit_radius;
  std::vector<Vec3> bound_positions(bound_count);
  for (size_t l = 0; l < bound_count; ++l) bound_positions[l] = rest.positions[bound_[l]];
  tree.radiusBatch(bound_positions, fit_radius, offsets, found);
  fit_begin_.assign(bound_count + 1, 0);
  fit_moment_pinv_.resize(bound_count);
  fit_null_.resize(bound_count);
  for (size_t l = 0; l < bound_count; ++l) {
    Mat3 moment = Mat3::Zero();
    for (size_t k = offsets[l]; k < offsets[l + 1]; ++k) {
      const uint32_t g = solid[found[k].index];
      if (g == bound_[l] || found[k].sq_dist >= fit_r2) continue;
      const double w = poly6Shape(found[k].sq_dist, fit_r2);
      const Vec3 r = rest.positions[g] - bound_positions[l];
      fit_neighbor_.push_back(g);
      fit_weight_.push_back(w);
      fit_rest_.push_back(r);
      moment += w * r * r.transpose();
    }
    fit_begin_[l + 1] = fit_neighbor_.size();
    // Pseudo-inverse: directions without rest neighbours keep the identity.
    const Eigen::SelfAdjointEigenSolver<Mat3> eigen(moment);
    const double largest = eigen.eigenvalues().maxCoeff();
    Mat3 pinv = Mat3::Zero(), range = Mat3::Zero();
    for (int e = 0; e < 3; ++e) {
      const double lambda = eigen.eigenvalues()[e];
      if (!(lambda > 1e-10 * largest)) continue;
      const Vec3 v = eigen.eigenvectors().col(e);
      pinv += (v / lambda) * v.transpose();
      range += v * v.transpose();
    }
    fit_moment_pinv_[l] = pinv;
    fit_null_[l] = Mat3::Identity() - range;
  }
}

void SphSkin::checkPositions(const std::vector<Vec3>& positions) const {
  if (positions.size() != system_size_)
    throw std::invalid_argument("SphSkin: " + std::to_string(positions.size()) + " particle positions for " +
                                std::to_string(system_size_) + " bound particles of the rest state");
}

void SphSkin::fitCompact(const std::vector<Vec3>& positions, std::vector<Mat3>& compact) const {
  checkPositions(positions);
  compact.resize(bound_.size());
  const std::ptrdiff_t bound_count = static_cast<std::ptrdiff_t>(bound_.size());
#pragma omp parallel for schedule(static) if (bound_count >= kParallelPoints)
  for (std::ptrdiff_t l = 0; l < bound_count; ++l) {
    const Vec3& xi = positions[bound_[l]];
    Mat3 b = Mat3::Zero();
    for (size_t k = fit_begin_[l]; k < fit_begin_[l + 1]; ++k)
      b.noalias() += (fit_weight_[k] * (positions[fit_neighbor_[k]] - xi)) * fit_rest_[k].transpose();
    compact[l] = b * fit_moment_pinv_[l] + fit_null_[l];
  }
}

void SphSkin::fitTransforms(const std::vector<Vec3>& positions, std::vector<Mat3>& out) const {
  std::vector<Mat3> compact;
  fitCompact(positions, compact);
  if (out.size() != system_size_) out.resize(system_size_, Mat3::Identity());
  for (size_t l = 0; l < bound_.size(); ++l) out[bound_[l]] = compact[l] * rest_transform_[l];
}

void SphSkin::deform(const std::vector<Vec3>& positions, const std::vector<Mat3>& transforms) {
  checkPositions(positions);
  if (transforms.size() != system_size_)
    throw std::invalid_argument("SphSkin: " + std::to_string(transforms.size()) + " transforms for " +
                                std::to_string(system_size_) + " particles");
  const std::ptrdiff_t bound_count = static_cast<std::ptrdiff_t>(bound_.size());
#pragma omp parallel for schedule(static) if (bound_count >= kParallelPoints)
  for (std::ptrdiff_t l = 0; l < bound_count; ++l)
    current_[l] = transforms[bound_[l]] * rest_inverse_[l];  // F_i = A_i (A_i^0)^-1
  blend(positions);
}

void SphSkin::deform(const std::vector<Vec3>& positions) {
  fitCompact(positions, current_);
  blend(positions);
}

void SphSkin::blend(const std::vector<Vec3>& positions) {
  const std::ptrdiff_t point_count = static_cast<std::ptrdiff_t>(rest_points_.size());
#pragma omp parallel for schedule(static) if (point_count >= kParallelPoints)
  for (std::ptrdiff_t p = 0; p < point_count; ++p) {
    Vec3 s = Vec3::Zero();
    Mat3 j = Mat3::Zero();
    for (size_t k = pair_begin_[p]; k < pair_begin_[p + 1]; ++k) {
      const uint32_t l = pair_particle_[k];
      const double w = pair_weight_[k];
      s += w * (positions[bound_[l]] + current_[l] * pair_offset_[k]);  // (8.38)
      j += w * current_[l];
    }
    points_[p] = s;
    jacobians_[p] = j;
  }
}

void SphSkin::transformNormals(const std::vector<Vec3>& rest_normals, std::vector<Vec3>& out) const {
  if (rest_normals.size() != rest_points_.size())
    throw std::invalid_argument("SphSkin: " + std::to_string(rest_normals.size()) + " rest normals for " +
                                std::to_string(rest_points_.size()) + " bound points");
  out.resize(rest_normals.size());
  const std::ptrdiff_t count = static_cast<std::ptrdiff_t>(rest_normals.size());
#pragma omp parallel for schedule(static) if (count >= kParallelPoints)
  for (std::ptrdiff_t p = 0; p < count; ++p) {
    const Vec3 n = cofactor(jacobians_[p]) * rest_normals[p];
    const double length = n.norm();
    out[p] = length > 0.0 && std::isfinite(length) ? Vec3(n / length) : rest_normals[p];
  }
}

void SphSkin::deformSurfels(const SurfelCloud& rest, SurfelCloud& out) const {
  if (rest.size() != rest_points_.size())
    throw std::invalid_argument("SphSkin: surfel cloud has " + std::to_string(rest.size()) + " surfels for " +
                                std::to_string(rest_points_.size()) + " bound points");
  rest.validate();
  out = rest;
  out.positions = points_;
  const std::ptrdiff_t count = static_cast<std::ptrdiff_t>(rest.size());
#pragma omp parallel for schedule(static) if (count >= kParallelPoints)
  for (std::ptrdiff_t p = 0; p < count; ++p) {
    const Mat3& j = jacobians_[p];
    double area_factor = std::cbrt(std::abs(j.determinant()));
    area_factor *= area_factor;
    if (rest.hasNormals()) {
      const Vec3 n = cofactor(j) * rest.normals[p];
      const double length = n.norm();
      area_factor = length / rest.normals[p].norm();
      if (length > 0.0 && std::isfinite(length)) out.normals[p] = n / length;
    }
    if (rest.hasRadii()) out.radii[p] = rest.radii[p] * std::sqrt(area_factor);
    if (rest.hasAxes()) {
      out.axes1[p] = j * rest.axes1[p];
      out.axes2[p] = j * rest.axes2[p];
    }
  }
}

void SphSkin::deformMesh(const TriangleMesh& rest, TriangleMesh& out) const {
  deformSurfels(rest.vertices, out.vertices);
  out.triangles = rest.triangles;
}

namespace {

void checkResolution(int resolution, const char* what) {
  if (resolution < 1 || resolution > 1000)
    throw std::invalid_argument(std::string(what) + ": resolution must be in [1, 1000], got " +
                                std::to_string(resolution));
}

}  // namespace

TriangleMesh sphBoxSkinMesh(const Vec3& half_extent, int resolution) {
  checkResolution(resolution, "sphBoxSkinMesh");
  if (!(half_extent.minCoeff() > 0.0) || !finite(half_extent))
    throw std::invalid_argument("sphBoxSkinMesh: half extents must be finite and > 0");
  const int64_t n = resolution, side = n + 1;
  TriangleMesh mesh;
  std::unordered_map<int64_t, uint32_t> index_of;  // grid point (a, b, c) in [0, n]^3 on the boundary
  auto vertex = [&](std::array<int64_t, 3> g) {
    const int64_t key = (g[0] * side + g[1]) * side + g[2];
    const auto found = index_of.find(key);
    if (found != index_of.end()) return found->second;
    Vec3 x;
    for (int k = 0; k < 3; ++k)  // exact at the faces: -h + 2h = h
      x[k] = g[k] == n ? half_extent[k] : -half_extent[k] + 2.0 * half_extent[k] * double(g[k]) / double(n);
    const uint32_t i = static_cast<uint32_t>(mesh.vertices.positions.size());
    mesh.vertices.positions.push_back(x);
    index_of.emplace(key, i);
    return i;
  };
  for (int k = 0; k < 3; ++k) {
    const int u = (k + 1) % 3, v = (k + 2) % 3;  // e_u x e_v = e_k
    for (const int64_t level : {int64_t(0), n}) {
      for (int64_t a = 0; a < n; ++a)
        for (int64_t b = 0; b < n; ++b) {
          std::array<uint32_t, 4> q;
          const int64_t corner[4][2] = {{a, b}, {a + 1, b}, {a + 1, b + 1}, {a, b + 1}};
          for (int c = 0; c < 4; ++c) {
            std::array<int64_t, 3> g;
            g[k] = level;
            g[u] = corner[c][0];
            g[v] = corner[c][1];
            q[c] = vertex(g);
          }
          if (level == n) {  // counter-clockwise seen from +e_k
            mesh.triangles.push_back({q[0], q[1], q[2]});
            mesh.triangles.push_back({q[0], q[2], q[3]});
          } else {
            mesh.triangles.push_back({q[0], q[2], q[1]});
            mesh.triangles.push_back({q[0], q[3], q[2]});
          }
        }
    }
  }
  return mesh;
}

TriangleMesh sphSphereSkinMesh(double radius, int resolution) {
  checkResolution(resolution, "sphSphereSkinMesh");
  if (!(std::isfinite(radius) && radius > 0.0))
    throw std::invalid_argument("sphSphereSkinMesh: radius must be finite and > 0, got " +
                                std::to_string(radius));
  const double t = 0.5 * (1.0 + std::sqrt(5.0));
  const Vec3 corners[12] = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                            {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  const int faces[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  const int n = resolution;
  TriangleMesh mesh;
  // A grid point is sum_c w_c corner_c / n; keyed by its (corner, weight) pairs in corner order, so points
  // on shared edges and corners are one vertex with bitwise the same position.
  std::map<std::array<int, 6>, uint32_t> index_of;
  auto vertex = [&](const int face[3], int i, int j) {
    std::array<std::pair<int, int>, 3> terms = {{{face[0], n - i - j}, {face[1], i}, {face[2], j}}};
    std::sort(terms.begin(), terms.end());
    std::array<int, 6> key;
    key.fill(-1);
    int used = 0;
    for (const auto& term : terms)
      if (term.second > 0) {
        key[2 * used] = term.first;
        key[2 * used + 1] = term.second;
        ++used;
      }
    const auto found = index_of.find(key);
    if (found != index_of.end()) return found->second;
    Vec3 x = Vec3::Zero();
    for (int c = 0; c < used; ++c) x += double(key[2 * c + 1]) * corners[key[2 * c]];
    const Vec3 normal = x.normalized();
    const uint32_t index = static_cast<uint32_t>(mesh.vertices.positions.size());
    mesh.vertices.positions.push_back(radius * normal);
    mesh.vertices.normals.push_back(normal);
    index_of.emplace(key, index);
    return index;
  };
  for (const auto& face : faces)
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        const uint32_t v00 = vertex(face, i, j), v10 = vertex(face, i + 1, j), v01 = vertex(face, i, j + 1);
        mesh.triangles.push_back({v00, v10, v01});
        if (i + j + 2 <= n) mesh.triangles.push_back({v10, vertex(face, i + 1, j + 1), v01});
      }
  return mesh;
}

}  // namespace rc
