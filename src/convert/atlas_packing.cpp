#include "relaxed_connectivity/convert/atlas_packing.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

namespace rc {
namespace {

/// Whether the closed axis-aligned square of half-size `half` around p meets the closed triangle abc
/// (separating axes: the square's two and the triangle's three edge normals).
bool squareMeetsTriangle(const Eigen::Vector2d& p, double half, const Eigen::Vector2d& a,
                         const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  if (std::max({a.x(), b.x(), c.x()}) < p.x() - half || std::min({a.x(), b.x(), c.x()}) > p.x() + half ||
      std::max({a.y(), b.y(), c.y()}) < p.y() - half || std::min({a.y(), b.y(), c.y()}) > p.y() + half)
    return false;
  const std::array<Eigen::Vector2d, 3> v = {a, b, c};
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector2d edge = v[(e + 1) % 3] - v[e];
    const Eigen::Vector2d n(-edge.y(), edge.x());
    const double apex = n.dot(v[(e + 2) % 3] - v[e]);  // the third vertex's side
    const double centre = n.dot(p - v[e]), radius = half * (std::abs(n.x()) + std::abs(n.y()));
    // The square lies wholly on the side away from the triangle: separated.
    if (apex >= 0 ? centre + radius < 0 : centre - radius > 0) return false;
  }
  return true;
}

/// A patch's mask reduced to what packing needs: per texel row, the first and last claimed column.
struct RowProfile {
  int width = 0, height = 0;
  double origin = 0;
  std::vector<int> left, right;  // -1: the row claims nothing
  size_t claimed = 0;
  double alpha_left = 0, alpha_right = 0;  // base angles [rad]
};

RowProfile profileOf(const PatchShape& p, int border) {
  const PatchMask mask = patchMask(p, border);
  RowProfile r;
  r.width = mask.width;
  r.height = mask.height;
  r.origin = mask.origin;
  r.left.assign(size_t(mask.height), -1);
  r.right.assign(size_t(mask.height), -1);
  for (int y = 0; y < mask.height; ++y)
    for (int x = 0; x < mask.width; ++x)
      if (mask.texels[size_t(y) * mask.width + x]) {
        if (r.left[y] < 0) r.left[y] = x;
        r.right[y] = x;
        ++r.claimed;
      }
  r.alpha_left = std::atan2(p.height, p.apex_x);
  r.alpha_right = std::atan2(p.height, p.base - p.apex_x);
  return r;
}

bool isPowerOfTwo(int v) {
  return v > 0 && (v & (v - 1)) == 0;
}

using AngleMap = std::multimap<double, uint32_t>;

void eraseCandidate(AngleMap& map, double angle, uint32_t index) {
  for (auto [it, end] = map.equal_range(angle); it != end; ++it)
    if (it->second == index) {
      map.erase(it);
      return;
    }
}

int nextPowerOfTwo(double v) {
  int p = 1;
  while (p < v) p *= 2;
  return p;
}

}  // namespace

int longestEdge(const std::array<Eigen::Vector3d, 3>& v) {
  int k = 0;
  double longest = -1;
  for (int e = 0; e < 3; ++e) {
    const double length = (v[(e + 1) % 3] - v[e]).squaredNorm();
    if (length > longest) longest = length, k = e;
  }
  return k;
}

PatchShape PatchShape::ofTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c, double texels_per_unit) {
  // The longest edge is the base; the apex is the vertex opposite it.
  const std::array<Eigen::Vector3d, 3> v = {a, b, c};
  const int k = longestEdge(v);
  const double longest = (v[(k + 1) % 3] - v[k]).norm();
  const Eigen::Vector3d& p0 = v[k];
  const Eigen::Vector3d& p1 = v[(k + 1) % 3];
  const Eigen::Vector3d& apex = v[(k + 2) % 3];
  const Eigen::Vector3d axis = (p1 - p0) / std::max(longest, 1e-300);
  PatchShape s;
  s.base = longest * texels_per_unit;
  s.apex_x = std::clamp((apex - p0).dot(axis), 0.0, longest) * texels_per_unit;
  s.height = ((apex - p0) - (apex - p0).dot(axis) * axis).norm() * texels_per_unit;
  return s;
}

double patchMaskOrigin(int border) {
  // Claimed texels lie within `border` texels of the triangle, so a margin of `border` holds them all and
  // leaves no empty mask row that would still take row height in the atlas.
  return std::max(border, 1);
}

PatchMask patchMask(const PatchShape& p, int border) {
  if (!std::isfinite(p.base) || !std::isfinite(p.apex_x) || !std::isfinite(p.height) || !(p.base > 0) ||
      !(p.height > 0) || p.apex_x < 0 || p.apex_x > p.base)
    throw std::invalid_argument("patchMask: a patch needs base > 0, height > 0 and 0 <= apex_x <= base");
  if (border < 0) throw std::invalid_argument("patchMask: border must be >= 0");
  PatchMask m;
  m.origin = patchMaskOrigin(border);
  m.width = int(std::ceil(p.base + 2 * m.origin));
  m.height = int(std::ceil(p.height + 2 * m.origin));
  m.texels.assign(size_t(m.width) * size_t(m.height), 0);
  const Eigen::Vector2d a(m.origin, m.origin), b(m.origin + p.base, m.origin),
      c(m.origin + p.apex_x, m.origin + p.height);
  // A texel is claimed when a point of the triangle lies within `border` texels of its centre in x and in y
  // (Chebyshev distance < border): with border 1, exactly the texels bilinear filtering reads for points of
  // the triangle. (Border 0: the texels whose square overlaps the triangle.)
  const double half = std::max(border, 0) > 0 ? border - 1e-9 : 0.5;
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x)
      m.texels[size_t(y) * m.width + x] =
          squareMeetsTriangle(Eigen::Vector2d(x + 0.5, y + 0.5), half, a, b, c);
  return m;
}

AtlasLayout packPatches(const std::vector<PatchShape>& patches, const AtlasOptions& options) {
  if (!(options.height_tolerance >= 0) || !(options.height_tolerance < 1))
    throw std::invalid_argument("packPatches: height_tolerance must be in [0, 1)");
  if (options.page_size != 0 && !isPowerOfTwo(options.page_size))
    throw std::invalid_argument("packPatches: page_size " + std::to_string(options.page_size) +
                                " is not a power of two");
  if (!isPowerOfTwo(options.max_page_size))
    throw std::invalid_argument("packPatches: max_page_size must be a power of two");
  std::vector<RowProfile> profiles;
  profiles.reserve(patches.size());
  double box_area = 0, triangle_area = 0;
  int largest = 1;
  size_t claimed = 0;
  for (size_t i = 0; i < patches.size(); ++i) {
    try {
      profiles.push_back(profileOf(patches[i], options.border));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("packPatches: patch " + std::to_string(i) + ": " + e.what());
    }
    box_area += double(profiles.back().width) * profiles.back().height;
    triangle_area += 0.5 * patches[i].base * patches[i].height;
    largest = std::max({largest, profiles.back().width, profiles.back().height});
    claimed += profiles.back().claimed;
  }
  AtlasLayout layout;
  layout.page_size =
      options.page_size > 0
          ? options.page_size
          : std::min(options.max_page_size,
                     std::max(nextPowerOfTwo(largest), nextPowerOfTwo(std::sqrt(box_area / 0.8))));
  const int P = layout.page_size;
  if (largest > P)
    throw std::invalid_argument("packPatches: a patch of " + std::to_string(largest) +
                                " texels does not fit a page of " + std::to_string(P));
  layout.placements.assign(patches.size(), PatchPlacement());
  if (patches.empty()) return layout;

  // Patches by height, tallest first. The pool holds the unplaced patches tall enough for the current row
  // (T_h of line 4), keyed by their left and by their right base angle: the best fit (line 8) is the
  // nearest key to beta in either map, O(log n). Row heights only fall, so the pool only grows by the
  // patches that the lower threshold admits; patches that did not fit a row wait in `skipped` for the next.
  std::vector<uint32_t> order(patches.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return profiles[a].height > profiles[b].height; });
  size_t next = 0;  // order[next..] are not in the pool yet
  AngleMap by_left, by_right;
  std::multiset<int> pool_heights;
  std::vector<uint32_t> skipped;
  auto addToPool = [&](uint32_t i) {
    by_left.emplace(profiles[i].alpha_left, i);
    by_right.emplace(profiles[i].alpha_right, i);
    pool_heights.insert(profiles[i].height);
  };
  int page = 0, y_row = 0, row_height = 0;
  std::vector<int> row_right;  // per texel row of the current row: first free column
  std::vector<int> row_left;   // per texel row of the current row: its first claimed column (P: none)
  std::vector<bool> placed(patches.size(), false);
  // Mask row of strip row `s` for a patch at vertical offset `shift` in the row, flipped or not.
  auto maskRow = [](const RowProfile& r, bool flip_v, int shift, int s) {
    return flip_v ? r.height - 1 - (s - shift) : s - shift;
  };
  // insert(): the leftmost column where the patch's texels clear those placed in the row.
  auto leftmostX = [&](const RowProfile& r, bool flip_h, bool flip_v, int shift) {
    int x = 0;
    for (int s = shift; s < shift + r.height; ++s) {
      const int m = maskRow(r, flip_v, shift, s);
      if (r.left[m] < 0) continue;
      x = std::max(x, row_right[s] - (flip_h ? r.width - 1 - r.right[m] : r.left[m]));
    }
    return x;
  };
  // The rightmost column left of every texel the row holds (its first patch leaves a wedge at the page's
  // left edge); -1 if the patch does not fit there.
  auto rightmostXBeforeRowStart = [&](const RowProfile& r, bool flip_h, bool flip_v, int shift) {
    int x = P;
    for (int s = shift; s < shift + r.height; ++s) {
      const int m = maskRow(r, flip_v, shift, s);
      if (r.left[m] < 0) continue;
      x = std::min(x, row_left[s] - 1 - (flip_h ? r.width - 1 - r.left[m] : r.right[m]));
    }
    return x >= P ? -1 : x;
  };
  auto place = [&](uint32_t t, bool flip_h, bool flip_v, int shift, int x) {
    const RowProfile& r = profiles[t];
    for (int s = shift; s < shift + r.height; ++s) {
      const int m = maskRow(r, flip_v, shift, s);
      if (r.left[m] < 0) continue;
      row_right[s] = std::max(row_right[s], x + (flip_h ? r.width - 1 - r.left[m] : r.right[m]) + 1);
      row_left[s] = std::min(row_left[s], x + (flip_h ? r.width - 1 - r.right[m] : r.left[m]));
    }
    // The triangle's corners on the page.
    const PatchShape& p = patches[t];
    std::array<Eigen::Vector2d, 3> c = {Eigen::Vector2d(r.origin, r.origin),
                                        Eigen::Vector2d(r.origin + p.base, r.origin),
                                        Eigen::Vector2d(r.origin + p.apex_x, r.origin + p.height)};
    for (Eigen::Vector2d& q : c) {
      if (flip_h) q.x() = r.width - q.x();
      if (flip_v) q.y() = r.height - q.y();
      q += Eigen::Vector2d(x, y_row + shift);
    }
    PatchPlacement& out = layout.placements[t];
    out.page = page;
    out.corners = c;
    out.flipped_horizontally = flip_h;
    out.flipped_vertically = flip_v;
    placed[t] = true;
  };
  constexpr int kFailuresToCloseARow = 16;  // candidates tried in vain before a row counts as full
  while (!pool_heights.empty() || next < order.size()) {
    // (line 3) the tallest patch left
    while (next < order.size() && placed[order[next]]) ++next;  // (taken by an earlier row-end fill)
    if (pool_heights.empty() && next == order.size()) break;
    row_height = pool_heights.empty() ? 0 : *pool_heights.rbegin();
    if (next < order.size()) row_height = std::max(row_height, profiles[order[next]].height);
    if (y_row + row_height > P) ++page, y_row = 0;
    const double lowest = row_height - options.height_tolerance * row_height;
    for (; next < order.size() && profiles[order[next]].height >= lowest; ++next)  // (line 4)
      if (!placed[order[next]]) addToPool(order[next]);
    row_right.assign(size_t(row_height), 0);
    row_left.assign(size_t(row_height), P);
    double beta = M_PI / 2;  // (line 5)
    bool mirror = false;
    int failures = 0;
    while (!by_left.empty() && failures < kFailuresToCloseARow) {
      // (line 8) the candidate whose base angle fits the free angle best; ties: the smaller index.
      uint32_t t = UINT32_MAX;
      double best_fit = std::numeric_limits<double>::infinity();
      for (const AngleMap* map : {&by_left, &by_right}) {
        auto it = map->lower_bound(beta);
        for (auto near : {it, it == map->begin() ? map->end() : std::prev(it)}) {
          if (near == map->end()) continue;
          const double fit = std::abs(near->first - beta);
          if (fit < best_fit || (fit == best_fit && near->second < t)) best_fit = fit, t = near->second;
        }
      }
      eraseCandidate(by_left, profiles[t].alpha_left, t);
      eraseCandidate(by_right, profiles[t].alpha_right, t);
      pool_heights.erase(pool_heights.find(profiles[t].height));
      const RowProfile& r = profiles[t];
      const bool flip_h = std::abs(r.alpha_left - beta) > std::abs(r.alpha_right - beta);  // (line 9)
      const bool flip_v = mirror;                                                          // (line 14)
      // insert(y_min, t): pushed from the right as far left as its texels allow.
      const int shift = flip_v ? row_height - r.height : 0;  // flipped: aligned with the row's top
      const int x = leftmostX(r, flip_h, flip_v, shift);
      if (x + r.width > P) {
        ++failures;
        skipped.push_back(t);
        continue;
      }
      failures = 0;
      place(t, flip_h, flip_v, shift, x);
      beta = flip_h ? r.alpha_left : r.alpha_right;  // (lines 10, 12) the free angle on the right
      mirror = !mirror;                              // (line 15)
    }
    // Row-end fill (beyond Algorithm 6.1): the space a row leaves when its height class runs out takes the
    // next shorter patches, each at the height within the row where it lands leftmost. Without it, the rows
    // of the few tallest patches stay mostly empty.
    failures = 0;
    for (size_t k = next; k < order.size() && failures < kFailuresToCloseARow; ++k) {
      const uint32_t t = order[k];
      if (placed[t]) continue;
      const RowProfile& r = profiles[t];
      int best_x = P, best_shift = 0;
      bool best_flip_h = false, best_flip_v = false;
      // First the gap a row's first patch leaves on its left (pushed right against it), then the row's end.
      for (bool flip_h : {false, true})
        for (bool flip_v : {false, true})
          for (int shift = 0; shift + r.height <= row_height; ++shift) {
            const int x = rightmostXBeforeRowStart(r, flip_h, flip_v, shift);
            if (x >= 0 && (best_x == P || x < best_x))
              best_x = x, best_shift = shift, best_flip_h = flip_h, best_flip_v = flip_v;
          }
      if (best_x == P)
        for (bool flip_h : {false, true})
          for (bool flip_v : {false, true})
            for (int shift = 0; shift + r.height <= row_height; ++shift) {
              const int x = leftmostX(r, flip_h, flip_v, shift);
              if (x < best_x) best_x = x, best_shift = shift, best_flip_h = flip_h, best_flip_v = flip_v;
            }
      if (best_x + r.width > P) {
        ++failures;
        continue;
      }
      failures = 0;
      place(t, best_flip_h, best_flip_v, best_shift, best_x);
    }
    for (uint32_t i : skipped) addToPool(i);
    skipped.clear();
    y_row += row_height;  // (line 20)
  }
  layout.pages = page + 1;
  layout.last_page_height = y_row;
  const double atlas_area = double(P) * P * page + double(P) * layout.last_page_height;
  layout.usage = triangle_area / atlas_area;
  layout.usage_with_borders = double(claimed) / atlas_area;
  return layout;
}

}  // namespace rc
