// Analytic reference surfaces (sphere, torus) with exact closest point, normal and signed distance, and
// samplers that turn them into surfel clouds with exact normals. Used as ground truth by the tests and
// benchmarks.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

enum class SamplingPattern {
  kUniformRandom,  ///< i.i.d. points, uniform with respect to area
  kFibonacci,      ///< quasi-uniform golden-ratio lattice (area-uniform)
};

struct SamplingOptions {
  SamplingPattern pattern = SamplingPattern::kFibonacci;
  double noise_sigma = 0.0;  ///< isotropic Gaussian position noise (normals stay exact)
  uint64_t seed = 1;
};

class AnalyticSurface {
 public:
  virtual ~AnalyticSurface() = default;
  /// Signed distance, positive outside.
  virtual double signedDistance(const Vec3& x) const = 0;
  /// Closest surface point (a valid choice on the medial axis).
  virtual Vec3 closestPoint(const Vec3& x) const = 0;
  /// Outward unit normal at the closest point of x.
  virtual Vec3 normal(const Vec3& x) const = 0;
  virtual double area() const = 0;
  /// Smallest local feature size (distance from the surface to its medial axis).
  virtual double minFeatureSize() const = 0;
  /// n surfels with exact outward normals.
  virtual SurfelCloud sample(size_t n, const SamplingOptions& options = {}) const = 0;
  /// Mean sample spacing sqrt(area / n).
  double spacing(size_t n) const;
  /// First intersection t >= t_min of the ray origin + t*dir (dir need not be unit); false if none.
  virtual bool intersectRay(const Vec3& origin, const Vec3& dir, double t_min, double* t) const = 0;
};

class AnalyticSphere : public AnalyticSurface {
 public:
  AnalyticSphere(const Vec3& center, double radius);
  double signedDistance(const Vec3& x) const override;
  Vec3 closestPoint(const Vec3& x) const override;
  Vec3 normal(const Vec3& x) const override;
  double area() const override;
  double minFeatureSize() const override { return radius_; }
  SurfelCloud sample(size_t n, const SamplingOptions& options = {}) const override;
  bool intersectRay(const Vec3& origin, const Vec3& dir, double t_min, double* t) const override;
  const Vec3& center() const { return center_; }
  double radius() const { return radius_; }

 private:
  Vec3 center_;
  double radius_;
};

/// Torus around the z axis through `center`: major radius R (tube centre circle), minor radius r < R.
class AnalyticTorus : public AnalyticSurface {
 public:
  AnalyticTorus(const Vec3& center, double major_radius, double minor_radius);
  double signedDistance(const Vec3& x) const override;
  Vec3 closestPoint(const Vec3& x) const override;
  Vec3 normal(const Vec3& x) const override;
  double area() const override;
  double minFeatureSize() const override { return minor_radius_; }
  SurfelCloud sample(size_t n, const SamplingOptions& options = {}) const override;
  bool intersectRay(const Vec3& origin, const Vec3& dir, double t_min, double* t) const override;
  double majorRadius() const { return major_radius_; }
  double minorRadius() const { return minor_radius_; }

 private:
  /// Nearest point on the tube centre circle.
  Vec3 tubeCenter(const Vec3& x) const;
  Vec3 center_;
  double major_radius_, minor_radius_;
};

}  // namespace rc
