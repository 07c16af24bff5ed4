// MLS weight functions of thesis 3.1.5: Gaussian (3.10), clipped Gaussian (3.11), Wendland C2 (3.12), and the
// elliptical distance (3.13) that turns any of them into an anisotropic kernel.
#pragma once

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

enum class WeightKind { kGaussian, kClippedGaussian, kWendlandC2 };

/// Parses "gaussian", "clipped_gaussian", "wendland" (throws std::invalid_argument naming the value).
WeightKind parseWeightKind(const std::string& name);
const char* weightKindName(WeightKind kind);

/// A radially symmetric weight w(d) of the distance d.
struct WeightFunction {
  WeightKind kind = WeightKind::kWendlandC2;
  /// Gaussian width sigma (3.10) for the Gaussians; support radius r (3.12) for Wendland.
  double scale = 1.0;
  /// Clipped Gaussian cut-off (3.11) in units of sigma: w = 0 for d >= clip * sigma.
  double clip = 3.0;

  static WeightFunction gaussian(double sigma) { return {WeightKind::kGaussian, sigma, 0.0}; }
  static WeightFunction clippedGaussian(double sigma, double clip = 3.0) {
    return {WeightKind::kClippedGaussian, sigma, clip};
  }
  static WeightFunction wendland(double support) { return {WeightKind::kWendlandC2, support, 0.0}; }

  /// Distance beyond which w is zero (infinity for the plain Gaussian).
  double support() const {
    switch (kind) {
      case WeightKind::kGaussian:
        return std::numeric_limits<double>::infinity();
      case WeightKind::kClippedGaussian:
        return clip * scale;
      case WeightKind::kWendlandC2:
        return scale;
    }
    return scale;
  }

  /// w(d) from the squared distance (avoids a sqrt for the Gaussians).
  double fromSquared(double d2) const {
    switch (kind) {
      case WeightKind::kGaussian:
        return std::exp(-d2 / (scale * scale));  // (3.10)
      case WeightKind::kClippedGaussian:         // (3.11)
        return d2 < clip * clip * scale * scale ? std::exp(-d2 / (scale * scale)) : 0.0;
      case WeightKind::kWendlandC2: {  // (3.12) with Wendland's (1 + 4q): the printed (1 + q) is not C2 at 0
        if (d2 >= scale * scale) return 0.0;
        const double q = std::sqrt(d2) / scale, a = 1.0 - q, a2 = a * a;
        return a2 * a2 * (1.0 + 4.0 * q);
      }
    }
    return 0.0;
  }
  double operator()(double d) const { return fromSquared(d * d); }
};

/// Elliptical distance of (3.13): sqrt((t1.d)^2/|t1|^4 + (t2.d)^2/|t2|^4), i.e. d measured in units of the
/// tangent axis lengths. Feed it to a WeightFunction of unit scale.
inline double ellipticalDistance(const Vec3& t1, const Vec3& t2, const Vec3& d) {
  const double a = t1.dot(d) / t1.squaredNorm(), b = t2.dot(d) / t2.squaredNorm();
  return std::sqrt(a * a + b * b);
}

}  // namespace rc
