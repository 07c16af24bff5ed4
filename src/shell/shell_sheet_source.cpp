#include "relaxed_connectivity/shell/shell_sheet_source.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace rc {

void sheetCells(const SheetSource& sheet, long* nx, long* ny) {
  if (!(sheet.width > 0.0) || !(sheet.height > 0.0) || !(sheet.spacing > 0.0))
    throw std::invalid_argument("sheet: size and spacing must be positive");
  *nx = long(std::round(sheet.width / sheet.spacing));
  *ny = long(std::round(sheet.height / sheet.spacing));
  if (*nx < 2 || *ny < 2) throw std::invalid_argument("sheet: the spacing is larger than the sheet");
  if (double(*nx) * double(*ny) > 5e7)
    throw std::invalid_argument("sheet: the spacing makes too many surfels");
}

SurfelCloud sheetSurfels(const SheetSource& sheet) {
  long nx = 0, ny = 0;
  sheetCells(sheet, &nx, &ny);
  const double w = sheet.width, h = sheet.height;
  const double tile = sheet.tile > 0.0 ? sheet.tile : 0.1 * std::min(w, h);
  SurfelCloud cloud;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.5 * sheet.jitter, 0.5 * sheet.jitter);
  const double sx = w / nx, sy = h / ny;
  for (long a = 0; a < nx; ++a) {
    for (long b = 0; b < ny; ++b) {
      const Vec3 p(-0.5 * w + (a + 0.5 + u(rng)) * sx, -0.5 * h + (b + 0.5 + u(rng)) * sy, 0.0);
      cloud.positions.push_back(p);
      cloud.normals.push_back(Vec3::UnitZ());
      if (sheet.colors == SheetColors::kChecker) {
        const bool dark = (long(std::floor(p.x() / tile)) + long(std::floor(p.y() / tile))) % 2 != 0;
        cloud.colors.push_back(dark ? Rgba{40, 60, 160, 255} : Rgba{240, 220, 90, 255});
      } else if (sheet.colors == SheetColors::kRings) {
        const double r = p.head<2>().norm() / tile;
        const double t = 0.5 + 0.5 * std::cos(2.0 * M_PI * r);
        cloud.colors.push_back(
            Rgba{uint8_t(200 * t + 40), uint8_t(60 + 100 * (1 - t)), uint8_t(220 * (1 - t)), 255});
      }
    }
  }
  cloud.radii.assign(cloud.size(), 0.75 * std::max(sx, sy));
  return cloud;
}

}  // namespace rc
