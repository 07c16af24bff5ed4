#include "relaxed_connectivity/sph/polar_decomposition.h"

#include <cmath>

namespace rc {

bool extractRotation(const Eigen::Matrix3d& a, Eigen::Quaterniond& q, int max_iterations, double tolerance) {
  q.normalize();
  for (int iter = 0; iter < max_iterations; ++iter) {
    const Eigen::Matrix3d m = a * q.toRotationMatrix().transpose();
    const Eigen::Vector3d t(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1));
    const double trace = m.trace();
    // H = tr(M) I - sym(M), symmetric.
    const double h00 = trace - m(0, 0), h11 = trace - m(1, 1), h22 = trace - m(2, 2);
    const double h01 = -0.5 * (m(0, 1) + m(1, 0)), h02 = -0.5 * (m(0, 2) + m(2, 0)),
                 h12 = -0.5 * (m(1, 2) + m(2, 1));
    const double c00 = h11 * h22 - h12 * h12, c01 = h02 * h12 - h01 * h22, c02 = h01 * h12 - h02 * h11;
    const double det = h00 * c00 + h01 * c01 + h02 * c02;
    Eigen::Vector3d omega;
    bool newton = false;
    if (h00 > 0.0 && h00 * h11 - h01 * h01 > 0.0 && det > 1e-12 * trace * trace * trace) {
      const double c11 = h00 * h22 - h02 * h02, c12 = h01 * h02 - h00 * h12, c22 = h00 * h11 - h01 * h01;
      omega =
          Eigen::Vector3d(c00 * t.x() + c01 * t.y() + c02 * t.z(), c01 * t.x() + c11 * t.y() + c12 * t.z(),
                          c02 * t.x() + c12 * t.y() + c22 * t.z()) /
          det;
      newton = true;
    } else {
      omega = t * (1.0 / (std::abs(trace) + 1.0e-9));
    }
    const double w = omega.norm();
    if (!(w > tolerance)) return std::isfinite(w);
    q = Eigen::Quaterniond(Eigen::AngleAxisd(w, omega / w)) * q;
    q.normalize();
    // Quadratic convergence: after a Newton step this small the error is below ~1e-14.
    if (newton && w < 1e-7) return true;
  }
  return false;
}

}  // namespace rc
