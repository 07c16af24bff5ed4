#include "relaxed_connectivity/sph/sph_kernels.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

SphKernels::SphKernels(int dimension_, double h_) : dimension(dimension_), h(h_) {
  if (dimension != 2 && dimension != 3)
    throw std::invalid_argument("SphKernels: dimension must be 2 or 3, got " + std::to_string(dimension));
  if (!(h > 0.0) || !std::isfinite(h))
    throw std::invalid_argument("SphKernels: smoothing length h must be finite and > 0, got " +
                                std::to_string(h));
  h2 = h * h;
  inv_h = 1.0 / h;
  if (dimension == 3) {
    poly6_coeff = 315.0 / (64.0 * M_PI * h * h * h);  // (C.1)
    spiky_coeff = 15.0 / (M_PI * h * h * h);          // (C.7)
    viscosity_coeff = 45.0 / (M_PI * h2 * h2 * h);    // [146]
  } else {
    poly6_coeff = 4.0 / (M_PI * h2);   // (C.4)
    spiky_coeff = 10.0 / (M_PI * h2);  // (C.10), corrected (see header)
    viscosity_coeff = 40.0 / (M_PI * h2 * h2);
  }
}

}  // namespace rc
