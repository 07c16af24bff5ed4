// SPH kernel functions of thesis appendix C (poly6, spiky) and the viscosity Laplacian of [146], in 2D and
// 3D.
#pragma once

#include <cmath>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// The kernels for one smoothing length h and dimension (2 or 3), normalised for that dimension (8.1).
/// Distances come squared where the kernel needs no square root. 2D simulations run in the x-y plane (z = 0);
/// only the normalisation constants differ from 3D.
///
///  poly6  W(d)  = a (1 - d^2/h^2)^3                  (C.1)/(C.4), a = 315/(64 pi h^3) | 4/(pi h^2)
///  spiky  W^(d) = b (1 - d/h)^3                      (C.7)/(C.10), b = 15/(pi h^3) | 10/(pi h^2)
///  viscosity Laplacian  L(d) = c (1 - d/h)           c = 45/(pi h^5) | 40/(pi h^4)
///
/// Note on (C.10): the thesis prints 15/(pi h^2) for the 2D spiky kernel, but its derivative (C.11) uses
/// 30 = 3 * 10 and only 10/(pi h^2) integrates to 1 in 2D; 10 is used here. The thesis' w'' (C.3, C.6, C.9,
/// C.12) is the radial second derivative, not the Laplacian; both are provided. viscosityLaplacian() is the
/// Laplacian kernel normalised so that the SPH Laplacian (8.12) of |x|^2 is exact (= 2 * dimension), which
/// makes mu in (8.18) the shear viscosity.
struct SphKernels {
  /// Throws std::invalid_argument unless dimension is 2 or 3 and h is finite and > 0.
  SphKernels(int dimension, double h);

  int dimension;
  double h, h2, inv_h;
  double poly6_coeff, spiky_coeff, viscosity_coeff;

  // --- poly6 (density, XSPH) ---
  /// W(d) from d^2 (C.1)/(C.4).
  double poly6(double sq_dist) const {
    if (sq_dist >= h2) return 0.0;
    const double t = 1.0 - sq_dist / h2;
    return poly6_coeff * t * t * t;
  }
  /// w'(d) (C.2)/(C.5).
  double poly6Derivative(double dist) const {
    if (dist >= h || dist <= 0.0) return 0.0;
    const double t = 1.0 - dist * dist / h2;
    return -6.0 * poly6_coeff * dist / h2 * t * t;
  }
  /// grad W(r) = r w'(|r|)/|r| (8.8).
  Vec3 poly6Gradient(const Vec3& r) const {
    const double d2 = r.squaredNorm();
    if (d2 >= h2) return Vec3::Zero();
    const double t = 1.0 - d2 / h2;
    return (-6.0 * poly6_coeff / h2 * t * t) * r;
  }
  /// w''(d) (C.3)/(C.6).
  double poly6SecondDerivative(double dist) const {
    if (dist >= h) return 0.0;
    const double q2 = dist * dist / h2;
    return 6.0 * poly6_coeff / h2 * (1.0 - q2) * (5.0 * q2 - 1.0);
  }
  /// The Laplacian w'' + (dim - 1) w'/d = 6 a/h^2 (1 - q^2)((4 + dim) q^2 - dim).
  double poly6Laplacian(double sq_dist) const {
    if (sq_dist >= h2) return 0.0;
    const double q2 = sq_dist / h2;
    return 6.0 * poly6_coeff / h2 * (1.0 - q2) * ((4.0 + dimension) * q2 - dimension);
  }

  // --- spiky (pressure gradient) ---
  /// W^(d) (C.7)/(C.10).
  double spiky(double dist) const {
    if (dist >= h) return 0.0;
    const double t = 1.0 - dist * inv_h;
    return spiky_coeff * t * t * t;
  }
  /// w^'(d) (C.8)/(C.11).
  double spikyDerivative(double dist) const {
    if (dist >= h || dist <= 0.0) return 0.0;
    const double t = 1.0 - dist * inv_h;
    return -3.0 * spiky_coeff * inv_h * t * t;
  }
  /// grad W^(r) = r w^'(|r|)/|r|; zero for r = 0 (no direction).
  Vec3 spikyGradient(const Vec3& r) const {
    const double d2 = r.squaredNorm();
    if (d2 >= h2 || d2 <= 0.0) return Vec3::Zero();
    const double d = std::sqrt(d2);
    const double t = 1.0 - d * inv_h;
    return (-3.0 * spiky_coeff * inv_h * t * t / d) * r;
  }
  /// w^''(d) (C.9)/(C.12).
  double spikySecondDerivative(double dist) const {
    if (dist >= h) return 0.0;
    return 6.0 * spiky_coeff * inv_h * inv_h * (1.0 - dist * inv_h);
  }

  // --- viscosity (8.18) ---
  /// Laplacian kernel L(d) = c (1 - d/h) >= 0 ([146]), normalised as described above.
  double viscosityLaplacian(double dist) const {
    if (dist >= h) return 0.0;
    return viscosity_coeff * (1.0 - dist * inv_h);
  }
};

}  // namespace rc
