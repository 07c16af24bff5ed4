#include "relaxed_connectivity/core/sorted_cell_grid.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace rc {

namespace {
constexpr size_t kMaxCells = size_t(1) << 31;
}  // namespace

void SortedCellGrid::build(const std::vector<Vec3>& points, double cell_size, int num_threads,
                           const std::string& caller) {
  if (!(cell_size >= 0.0) || !std::isfinite(cell_size))
    throw std::invalid_argument(caller + ": cell size must be finite and >= 0, got " +
                                std::to_string(cell_size));
  const size_t n = points.size();
  if (n >= std::numeric_limits<uint32_t>::max())
    throw std::length_error(caller + ": too many points (" + std::to_string(n) + ")");
  order_.resize(n);
  sorted_cell_.resize(n);
  if (n == 0) return;

  Vec3 lo = points[0], hi = points[0];
  for (size_t i = 0; i < n; ++i) {
    const Vec3& p = points[i];
    if (!p.allFinite())
      throw std::invalid_argument(caller + ": point " + std::to_string(i) + " is not finite");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 extent = hi - lo;
  const double max_abs = std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
  // Slack so that rounding never puts a neighbour at distance <= cell_size two cells away.
  double cell = cell_size * (1.0 + 1e-12) + 16.0 * std::numeric_limits<double>::epsilon() * max_abs;
  if (!(cell > 0.0)) cell = std::max(extent.maxCoeff(), 1.0);  // a zero radius at the origin
  const double max_cells = double(std::min(kMaxCells, std::max<size_t>(8 * n, 4096)));
  for (;;) {
    double total = 1.0;
    for (int a = 0; a < 3; ++a) total *= std::floor(extent[a] / cell) + 1.0;
    if (total <= max_cells) break;
    cell *= 1.25;
  }
  inv_cell_ = 1.0 / cell;
  size_t num_cells = 1;
  for (int a = 0; a < 3; ++a) {
    origin_[a] = lo[a];
    dims_[a] = static_cast<size_t>(std::floor(extent[a] * inv_cell_)) + 1;
    num_cells *= dims_[a];
  }

  cell_of_point_.resize(n);
  auto clampCell = [](double s, size_t dim) {
    return static_cast<size_t>(std::min(std::max(s, 0.0), double(dim - 1)));
  };
#pragma omp parallel for num_threads(num_threads) schedule(static)
  for (long i = 0; i < static_cast<long>(n); ++i) {
    const Vec3& p = points[i];
    const size_t cx = clampCell((p.x() - origin_[0]) * inv_cell_, dims_[0]);
    const size_t cy = clampCell((p.y() - origin_[1]) * inv_cell_, dims_[1]);
    const size_t cz = clampCell((p.z() - origin_[2]) * inv_cell_, dims_[2]);
    cell_of_point_[i] = static_cast<uint32_t>(cx + dims_[0] * (cy + dims_[1] * cz));
  }
  cell_start_.assign(num_cells + 1, 0);
  for (size_t i = 0; i < n; ++i) ++cell_start_[cell_of_point_[i] + 1];
  for (size_t c = 0; c < num_cells; ++c) cell_start_[c + 1] += cell_start_[c];
  for (size_t i = 0; i < n; ++i) {
    const uint32_t c = cell_of_point_[i];
    const uint32_t s = cell_start_[c]++;
    order_[s] = static_cast<uint32_t>(i);
    sorted_cell_[s] = c;
  }
  std::memmove(cell_start_.data() + 1, cell_start_.data(), num_cells * sizeof(uint32_t));
  cell_start_[0] = 0;
}

int SortedCellGrid::neighborRuns(uint32_t c, Run runs[9]) const {
  const size_t nx = dims_[0], ny = dims_[1], nz = dims_[2];
  const size_t cx = c % nx, cy = (c / nx) % ny, cz = c / (nx * ny);
  const size_t x0 = cx > 0 ? cx - 1 : 0, x1 = std::min(cx + 1, nx - 1);
  int num_runs = 0;
  for (size_t z = (cz > 0 ? cz - 1 : 0); z <= std::min(cz + 1, nz - 1); ++z)
    for (size_t y = (cy > 0 ? cy - 1 : 0); y <= std::min(cy + 1, ny - 1); ++y) {
      const size_t row = nx * (y + ny * z);
      const uint32_t b = cell_start_[row + x0], e = cell_start_[row + x1 + 1];
      if (b != e) runs[num_runs++] = {b, e};
    }
  return num_runs;
}

void SortedCellGrid::cellCoordinates(const Vec3& q, double coordinates[3], double* outside_distance) const {
  const double width = cellWidth();
  double sq = 0;
  for (int a = 0; a < 3; ++a) {
    coordinates[a] = std::floor((q[a] - origin_[a]) * inv_cell_);
    const double below = origin_[a] - q[a], above = q[a] - (origin_[a] + double(dims_[a]) * width);
    const double out = std::max({below, above, 0.0});
    sq += out * out;
  }
  *outside_distance = std::sqrt(sq);
}

int SortedCellGrid::runsAround(const Vec3& q, Run runs[9]) const {
  if (order_.empty()) return 0;
  long lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    // The cell index unclamped (in double, so that a far query cannot overflow), then the block clipped.
    const double c = std::floor((q[a] - origin_[a]) * inv_cell_);
    const double last = double(dims_[a] - 1);
    lo[a] = long(std::max(c - 1.0, 0.0));
    hi[a] = long(std::min(c + 1.0, last));
    if (c + 1.0 < 0.0 || c - 1.0 > last) return 0;
  }
  const size_t nx = dims_[0], ny = dims_[1];
  int num_runs = 0;
  for (long z = lo[2]; z <= hi[2]; ++z)
    for (long y = lo[1]; y <= hi[1]; ++y) {
      const size_t row = nx * (size_t(y) + ny * size_t(z));
      const uint32_t b = cell_start_[row + size_t(lo[0])], e = cell_start_[row + size_t(hi[0]) + 1];
      if (b != e) runs[num_runs++] = {b, e};
    }
  return num_runs;
}

}  // namespace rc
