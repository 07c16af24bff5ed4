#include "relaxed_connectivity/convert/procedural_paint.h"

#include <cmath>
#include <stdexcept>

namespace rc {

void paintCells(SurfelCloud& cloud, double cells_per_diagonal) {
  if (!(cells_per_diagonal > 0)) throw std::invalid_argument("paintCells: cells_per_diagonal must be > 0");
  Vec3 lo, hi;
  if (!cloud.bounds(&lo, &hi)) return;
  const double cell = std::max((hi - lo).norm(), 1e-12) / cells_per_diagonal;
  cloud.colors.resize(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Vec3 q = (cloud.positions[i] - lo) / cell;
    const bool odd = (int(std::floor(q.x())) + int(std::floor(q.y())) + int(std::floor(q.z()))) & 1;
    const double g = q.z() / cells_per_diagonal;
    double r = odd ? 0.9 : 0.2 + 0.5 * g, green = odd ? 0.7 - 0.4 * g : 0.4, b = odd ? 0.2 : 0.8;
    if (std::abs(std::sin(M_PI * 3 * q.x())) < 0.12) r *= 0.3, green *= 0.3, b *= 0.3;  // stripes
    cloud.colors[i] = {uint8_t(std::lround(255 * std::clamp(r, 0.0, 1.0))),
                       uint8_t(std::lround(255 * std::clamp(green, 0.0, 1.0))),
                       uint8_t(std::lround(255 * std::clamp(b, 0.0, 1.0))), 255};
  }
}

}  // namespace rc
