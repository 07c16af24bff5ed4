#include "relaxed_connectivity/paint/brush_skin.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace rc {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Half-extents (along x, along y) of the brush cross-section at s = depth / bristle_length in [0, 1]: the
/// bristles bulge a little below the ferrule and taper to a point (round) or a thin edge (flat).
Eigen::Vector2d crossSection(const BrushPreset& p, double s) {
  const double profile =
      (1.0 + 0.3 * std::sin(kPi * std::min(s, 0.5))) * std::pow(std::max(0.0, 1.0 - s), 0.6);
  if (p.shape == BrushShape::kRound) return Eigen::Vector2d(p.radius, p.radius) * profile;
  const double width = p.radius * (1.0 + 0.1 * std::sin(kPi * s));  // flat: keeps its width to the edge
  return Eigen::Vector2d(width, 0.5 * p.thickness * std::max(profile, 0.15));
}

}  // namespace

BrushSkin::BrushSkin(const BrushPreset& p, const BrushSkeleton& skeleton) {
  // Rings of surfels every surfel_spacing from the ferrule to the tip on an elliptic cross-section; normals
  // from the surface of the sweep (finite differences along s and around the ring).
  const double h = p.surfel_spacing;
  const int rings = std::max(2, int(std::ceil(p.bristle_length / h)));
  for (int r = 0; r <= rings; ++r) {
    const double s = std::min(double(r) / rings, 0.999);
    const Eigen::Vector2d e = crossSection(p, s);
    const double perimeter = kPi * (3 * (e[0] + e[1]) - std::sqrt((3 * e[0] + e[1]) * (e[0] + 3 * e[1])));
    const int count = std::max(3, int(std::ceil(perimeter / h)));
    const double ds = 1e-4, z = -p.bristle_length * s;
    const Eigen::Vector2d e2 = crossSection(p, std::min(s + ds, 1.0));
    for (int k = 0; k < count; ++k) {
      const double a = 2 * kPi * (k + 0.5 * (r % 2)) / count;
      const Vec3 x(e[0] * std::cos(a), e[1] * std::sin(a), z);
      const Vec3 along =
          Vec3(e2[0] * std::cos(a), e2[1] * std::sin(a), -p.bristle_length * std::min(s + ds, 1.0)) - x;
      const Vec3 around(-e[0] * std::sin(a), e[1] * std::cos(a), 0);
      Vec3 n = around.cross(along);
      if (n.dot(Vec3(x.x(), x.y(), 0)) < 0) n = -n;
      rest_positions_.push_back(x);
      rest_normals_.push_back(n.norm() > 0 ? Vec3(n.normalized()) : Vec3(0, 0, -1));
    }
  }
  rest_positions_.push_back(Vec3(0, 0, -p.bristle_length));  // the tip
  rest_normals_.push_back(Vec3(0, 0, -1));
  radius_ = 0.75 * h;
  // Skinning weights: the kInfluences nearest skeleton nodes at rest, inverse squared distance.
  const std::vector<Vec3>& nodes = skeleton.restPositions();
  nodes_.resize(size());
  weights_.resize(size());
  for (size_t i = 0; i < size(); ++i) {
    std::vector<std::pair<double, int>> by_distance;
    for (int j = 0; j < int(nodes.size()); ++j)
      by_distance.push_back({(nodes[j] - rest_positions_[i]).norm(), j});
    std::partial_sort(by_distance.begin(), by_distance.begin() + kInfluences, by_distance.end());
    double sum = 0;
    for (int k = 0; k < kInfluences; ++k) {
      const double w = 1.0 / std::pow(by_distance[k].first + 0.1 * h, 2);
      nodes_[i][k] = by_distance[k].second;
      weights_[i][k] = w;
      sum += w;
    }
    for (double& w : weights_[i]) w /= sum;
  }
  node_neighbours_.resize(nodes.size());
  for (const BrushSpring& s : skeleton.springs()) {
    node_neighbours_[s.a].push_back(s.b);
    node_neighbours_[s.b].push_back(s.a);
  }
  rotations_.assign(nodes.size(), Eigen::Matrix3d::Identity());
  PaintState loaded;
  loaded.wet.rgb = p.paint_colour;
  loaded.wet_volume = p.paint_volume;
  paint.assign(size(), loaded);
  update(skeleton);
}

void BrushSkin::update(const BrushSkeleton& skeleton) {
  const std::vector<Vec3>& rest = skeleton.restPositions();
  const std::vector<Vec3>& x = skeleton.positions();
  const Eigen::Matrix3d handle_rotation = skeleton.handlePose().linear();
  for (int j = 0; j < skeleton.nodeCount(); ++j) {
    if (skeleton.isHandle(j)) {
      rotations_[j] = handle_rotation;
      continue;
    }
    // Best-fit rotation of the node's springs: R = argmin sum |R (r_k - r_j) - (x_k - x_j)|^2 (Kabsch).
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (int k : node_neighbours_[j]) covariance += (x[k] - x[j]) * (rest[k] - rest[j]).transpose();
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
    d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
    rotations_[j] = svd.matrixU() * d * svd.matrixV().transpose();
  }
  positions_.resize(size());
  normals_.resize(size());
  for (size_t i = 0; i < size(); ++i) {
    Vec3 p = Vec3::Zero(), n = Vec3::Zero();
    for (int k = 0; k < kInfluences; ++k) {
      const int j = nodes_[i][k];
      const double w = weights_[i][k];
      p += w * (rotations_[j] * (rest_positions_[i] - rest[j]) + x[j]);
      n += w * (rotations_[j] * rest_normals_[i]);
    }
    positions_[i] = p;
    normals_[i] = n.norm() > 0 ? Vec3(n.normalized()) : n;
  }
}

SurfelCloud BrushSkin::cloud() const {
  SurfelCloud c;
  c.positions = positions_;
  c.normals = normals_;
  c.radii.assign(size(), radius_);
  c.colors.resize(size());
  for (size_t i = 0; i < size(); ++i)
    for (int k = 0; k < 3; ++k)
      c.colors[i][k] = uint8_t(std::lround(255.0 * std::clamp(paint[i].wet.rgb[k], 0.0, 1.0)));
  for (auto& col : c.colors) col[3] = 255;
  return c;
}

}  // namespace rc
