// The paint stroke shared by the paint benches (bench_paint_model, bench_paint_rendering): a great circle
// over a 10 cm sphere at 0.1 m/s, one main-loop event every 1/30 s (thesis 5.8), the stylus leaning 30
// degrees back.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

namespace rc::bench {

constexpr double kRadius = 0.1, kEvent = 1.0 / 30, kSpeed = 0.1, kLean = 0.5235987755982988;

/// The stylus pose of event e for a brush with `bristle_length`, pressed `press` into the sphere.
inline Eigen::Isometry3d strokePose(int e, double bristle_length, double press) {
  using Vec3 = Eigen::Vector3d;
  const double angle = kSpeed * kEvent * e / kRadius - 0.5;
  const Vec3 up(std::sin(angle), 0, std::cos(angle)), ahead(std::cos(angle), 0, -std::sin(angle));
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() =
      Eigen::Quaterniond::FromTwoVectors(Vec3(0, 0, -1), -std::cos(kLean) * up - std::sin(kLean) * ahead)
          .toRotationMatrix();
  t.translation() = (kRadius + bristle_length - press) * up;
  return t;
}

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

}  // namespace rc::bench
