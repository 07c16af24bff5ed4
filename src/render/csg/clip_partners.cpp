#include "relaxed_connectivity/render/csg/clip_partners.h"

#include <omp.h>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "relaxed_connectivity/core/kd_tree.h"

namespace rc {

namespace {

struct Span {
  int32_t row, i0, i1;
};

struct Footprint {
  Eigen::Vector2d quad[4];  // cell coordinates
  double dilate = 0;
  bool full = false;  // crosses the near plane: covers the whole buffer
};

}  // namespace

struct ClipPartnerFinder::Work {
  // candidate bookkeeping
  std::vector<uint32_t> all_ids;
  std::vector<Vec3> points;
  // clip buffer
  std::vector<Footprint> footprints;
  std::vector<uint32_t> span_offsets;
  std::vector<Span> spans;
  std::vector<uint32_t> cell_offsets;
  std::vector<uint32_t> cell_items;  // local candidate indices, ascending per cell
  std::vector<uint32_t> overflow;    // local indices of footprints crossing the near plane
  // per-thread results
  std::vector<std::vector<uint32_t>> thread_stamps;
  std::vector<std::vector<uint32_t>> thread_lists;
  std::vector<std::vector<Neighbor>> thread_neighbors;
  std::vector<uint32_t> list_thread, list_start, list_count;  // per candidate
};

ClipPartnerFinder::ClipPartnerFinder(const ClipBufferOptions& options) : options_(options), work_(new Work) {
  if (!(options.cell_size_px > 0) || !std::isfinite(options.cell_size_px))
    throw std::invalid_argument("ClipBufferOptions::cell_size_px must be > 0");
}
ClipPartnerFinder::~ClipPartnerFinder() = default;

namespace {

const std::vector<uint32_t>& candidateIds(const SurfelDiscs& discs, const std::vector<uint32_t>* candidates,
                                          std::vector<uint32_t>& all) {
  if (candidates) {
    for (uint32_t id : *candidates)
      if (id >= discs.size())
        throw std::invalid_argument("clip partners: candidate surfel " + std::to_string(id) +
                                    " >= " + std::to_string(discs.size()) + " surfels");
    return *candidates;
  }
  all.resize(discs.size());
  std::iota(all.begin(), all.end(), 0u);
  return all;
}

// Assembles the per-candidate lists (written by threads) into sorted CSR over all surfels.
void assemble(size_t n, const std::vector<uint32_t>& cand, const std::vector<std::vector<uint32_t>>& lists,
              const std::vector<uint32_t>& list_thread, const std::vector<uint32_t>& list_start,
              const std::vector<uint32_t>& list_count, ClipPartners* out) {
  out->offsets.assign(n + 1, 0);
  for (size_t k = 0; k < cand.size(); ++k) out->offsets[cand[k] + 1] = list_count[k];
  for (size_t i = 0; i < n; ++i) out->offsets[i + 1] += out->offsets[i];
  out->ids.resize(out->offsets[n]);
  const int64_t m = static_cast<int64_t>(cand.size());
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < m; ++k) {
    const uint32_t* src = lists[list_thread[k]].data() + list_start[k];
    uint32_t* dst = out->ids.data() + out->offsets[cand[k]];
    std::copy(src, src + list_count[k], dst);
    std::sort(dst, dst + list_count[k]);
  }
}

void prepareThreads(std::vector<std::vector<uint32_t>>& lists, size_t threads) {
  lists.resize(threads);
  for (auto& l : lists) l.clear();
}

}  // namespace

void ClipPartnerFinder::findSpatial(const SurfelDiscs& discs, ClipPartners* out,
                                    const std::vector<uint32_t>* candidates, ClipPartnerStats* stats) {
  Work& w = *work_;
  const std::vector<uint32_t>& cand = candidateIds(discs, candidates, w.all_ids);
  const size_t m = cand.size();
  w.points.resize(m);
  double rmax = 0;
  for (size_t k = 0; k < m; ++k) {
    w.points[k] = discs.centers[cand[k]];
    rmax = std::max(rmax, discs.radii[cand[k]]);
  }
  w.list_thread.resize(m);
  w.list_start.resize(m);
  w.list_count.resize(m);
  const int threads = omp_get_max_threads();
  prepareThreads(w.thread_lists, threads);
  w.thread_neighbors.resize(threads);
  size_t tested = 0;
  if (m > 0) {
    KdTree tree(w.points);
#pragma omp parallel num_threads(threads) reduction(+ : tested)
    {
      const int t = omp_get_thread_num();
      std::vector<uint32_t>& list = w.thread_lists[t];
      std::vector<Neighbor>& neighbors = w.thread_neighbors[t];
#pragma omp for schedule(dynamic, 64)
      for (int64_t k = 0; k < static_cast<int64_t>(m); ++k) {
        const uint32_t s = cand[k];
        w.list_thread[k] = t;
        w.list_start[k] = static_cast<uint32_t>(list.size());
        tree.radius(discs.centers[s], discs.radii[s] + rmax, neighbors);
        for (const Neighbor& nb : neighbors) {
          const uint32_t g = cand[nb.index];
          if (discs.patches[g] == discs.patches[s]) continue;
          ++tested;
          if (discs.partners(s, g)) list.push_back(g);
        }
        w.list_count[k] = static_cast<uint32_t>(list.size()) - w.list_start[k];
      }
    }
  }
  assemble(discs.size(), cand, w.thread_lists, w.list_thread, w.list_start, w.list_count, out);
  if (stats) {
    *stats = ClipPartnerStats();
    stats->candidates = m;
    stats->tested_pairs = tested;
    stats->pairs = out->pairCount();
  }
}

namespace {

// Conservative horizontal extent (in cells) of the convex quad inside the band [y0, y1].
bool bandExtent(const Eigen::Vector2d* q, double y0, double y1, double* xmin, double* xmax) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int e = 0; e < 4; ++e) {
    const Eigen::Vector2d& a = q[e];
    const Eigen::Vector2d& b = q[(e + 1) & 3];
    const double dy = b.y() - a.y();
    double t0, t1;
    if (dy == 0.0) {
      if (a.y() < y0 || a.y() > y1) continue;
      t0 = 0;
      t1 = 1;
    } else {
      t0 = (y0 - a.y()) / dy;
      t1 = (y1 - a.y()) / dy;
      if (t0 > t1) std::swap(t0, t1);
      t0 = std::max(t0, 0.0);
      t1 = std::min(t1, 1.0);
      if (t0 > t1) continue;
    }
    const double xa = a.x() + t0 * (b.x() - a.x()), xb = a.x() + t1 * (b.x() - a.x());
    lo = std::min(lo, std::min(xa, xb));
    hi = std::max(hi, std::max(xa, xb));
  }
  *xmin = lo;
  *xmax = hi;
  return lo <= hi;
}

int clampCell(double x, int n) {
  if (!(x >= 0)) return 0;  // also NaN
  if (x >= n - 1) return n - 1;
  return static_cast<int>(x);
}

}  // namespace

void ClipPartnerFinder::findClipBuffer(const SurfelDiscs& discs, const Camera& camera, ClipPartners* out,
                                       const std::vector<uint32_t>* candidates, ClipPartnerStats* stats) {
  Work& w = *work_;
  const std::vector<uint32_t>& cand = candidateIds(discs, candidates, w.all_ids);
  const int64_t m = static_cast<int64_t>(cand.size());
  const double cs = options_.cell_size_px;
  const int W = std::max(1, static_cast<int>(std::ceil(camera.width / cs)));
  const int H = std::max(1, static_cast<int>(std::ceil(camera.height / cs)));
  const double inf = std::numeric_limits<double>::infinity();

  // 1. Footprints: projected bounding squares c +- r u +- r v of the discs.
  w.footprints.resize(m);
  w.span_offsets.resize(m + 1);
  size_t edge_on = 0;
#pragma omp parallel for schedule(static) reduction(+ : edge_on)
  for (int64_t k = 0; k < m; ++k) {
    const uint32_t s = cand[k];
    Footprint& f = w.footprints[k];
    const Vec3& c = discs.centers[s];
    const Vec3 u = discs.axes1[s].normalized() * discs.radii[s];
    const Vec3 v = discs.normals[s].cross(u);
    const double su[4] = {1, -1, -1, 1}, sv[4] = {1, 1, -1, -1};
    f.full = false;
    for (int q = 0; q < 4 && !f.full; ++q) {
      double px, py;
      if (!camera.project(camera.toCamera(c + su[q] * u + sv[q] * v), &px, &py) || !std::isfinite(px) ||
          !std::isfinite(py)) {
        f.full = true;
      } else {
        f.quad[q] = Eigen::Vector2d((px + 0.5) / cs, (py + 0.5) / cs);
      }
    }
    int rows = 0;
    if (!f.full) {
      // Edge-on splats (thin quads) become thick lines: dilate by half a cell (4.2.3).
      const Eigen::Vector2d d0 = f.quad[2] - f.quad[0], d1 = f.quad[3] - f.quad[1];
      const double area = 0.5 * std::abs(d0.x() * d1.y() - d0.y() * d1.x());
      const double diag2 = std::max(d0.squaredNorm(), d1.squaredNorm());
      const bool thin = area < options_.edge_on_cosine * 0.5 * diag2;
      edge_on += thin;
      f.dilate = thin ? 0.5 : 1e-6;
      double ymin = inf, ymax = -inf;
      for (int q = 0; q < 4; ++q) {
        ymin = std::min(ymin, f.quad[q].y());
        ymax = std::max(ymax, f.quad[q].y());
      }
      rows = clampCell(std::floor(ymax + f.dilate), H) - clampCell(std::floor(ymin - f.dilate), H) + 1;
    }
    w.span_offsets[k + 1] = rows;
  }
  w.span_offsets[0] = 0;
  for (int64_t k = 0; k < m; ++k) w.span_offsets[k + 1] += w.span_offsets[k];

  // 2. Spans (row, first cell, last cell) per footprint; border rows/columns absorb everything beyond.
  w.spans.resize(w.span_offsets[m]);
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < m; ++k) {
    const Footprint& f = w.footprints[k];
    Span* span = w.spans.data() + w.span_offsets[k];
    const int rows = static_cast<int>(w.span_offsets[k + 1] - w.span_offsets[k]);
    if (f.full) continue;
    double ymin = inf;
    for (int q = 0; q < 4; ++q) ymin = std::min(ymin, f.quad[q].y());
    const int j0 = clampCell(std::floor(ymin - f.dilate), H);
    for (int r = 0; r < rows; ++r) {
      const int j = j0 + r;
      const double y0 = j == 0 ? -inf : j - f.dilate, y1 = j == H - 1 ? inf : j + 1 + f.dilate;
      double xmin, xmax;
      if (!bandExtent(f.quad, y0, y1, &xmin, &xmax)) {
        span[r] = {j, 0, -1};  // empty row (numerically touching only)
        continue;
      }
      span[r] = {j, clampCell(std::floor(xmin - f.dilate), W), clampCell(std::floor(xmax + f.dilate), W)};
    }
  }

  w.overflow.clear();
  for (int64_t k = 0; k < m; ++k)
    if (w.footprints[k].full) w.overflow.push_back(static_cast<uint32_t>(k));

  // 3. Cell lists (CSR), each in ascending candidate order.
  const size_t cells = static_cast<size_t>(W) * H;
  w.cell_offsets.assign(cells + 1, 0);
  for (const Span& sp : w.spans)
    for (int i = sp.i0; i <= sp.i1; ++i) ++w.cell_offsets[static_cast<size_t>(sp.row) * W + i + 1];
  for (size_t c = 0; c < cells; ++c) w.cell_offsets[c + 1] += w.cell_offsets[c];
  w.cell_items.resize(w.cell_offsets[cells]);
  {
    std::vector<uint32_t>& fill = w.list_start;  // reuse as per-cell write cursor
    fill.assign(w.cell_offsets.begin(), w.cell_offsets.end() - 1);
    for (int64_t k = 0; k < m; ++k)
      for (uint32_t sidx = w.span_offsets[k]; sidx < w.span_offsets[k + 1]; ++sidx) {
        const Span& sp = w.spans[sidx];
        for (int i = sp.i0; i <= sp.i1; ++i) w.cell_items[fill[static_cast<size_t>(sp.row) * W + i]++] = k;
      }
  }

  // 4. Algorithm 4.1, order-independent: each surfel reads every cell of its footprint; surfels of other
  //    patches found there are tested once (stamp) with ||c1 - c2|| < r1 + r2 and the disc-disc test.
  w.list_thread.resize(m);
  w.list_start.resize(m);
  w.list_count.resize(m);
  const int threads = omp_get_max_threads();
  prepareThreads(w.thread_lists, threads);
  w.thread_stamps.resize(threads);
  size_t tested = 0;
#pragma omp parallel num_threads(threads) reduction(+ : tested)
  {
    const int t = omp_get_thread_num();
    std::vector<uint32_t>& list = w.thread_lists[t];
    std::vector<uint32_t>& stamp = w.thread_stamps[t];
    stamp.assign(m, UINT32_MAX);
#pragma omp for schedule(dynamic, 64)
    for (int64_t k = 0; k < m; ++k) {
      const uint32_t s = cand[k];
      const int32_t patch = discs.patches[s];
      w.list_thread[k] = t;
      w.list_start[k] = static_cast<uint32_t>(list.size());
      for (uint32_t sidx = w.span_offsets[k]; sidx < w.span_offsets[k + 1]; ++sidx) {
        const Span& sp = w.spans[sidx];
        const size_t row = static_cast<size_t>(sp.row) * W;
        for (int i = sp.i0; i <= sp.i1; ++i) {
          const uint32_t* item = w.cell_items.data() + w.cell_offsets[row + i];
          const uint32_t* last = w.cell_items.data() + w.cell_offsets[row + i + 1];
          for (; item != last; ++item) {
            const uint32_t l = *item;
            const uint32_t g = cand[l];
            if (discs.patches[g] == patch || stamp[l] == static_cast<uint32_t>(k)) continue;
            stamp[l] = static_cast<uint32_t>(k);
            ++tested;
            if (discs.partners(s, g)) list.push_back(g);
          }
        }
      }
      // Footprints crossing the near plane cannot be projected: they are tested against every candidate.
      auto test = [&](uint32_t l) {
        const uint32_t g = cand[l];
        if (discs.patches[g] == patch || stamp[l] == static_cast<uint32_t>(k)) return;
        stamp[l] = static_cast<uint32_t>(k);
        ++tested;
        if (discs.partners(s, g)) list.push_back(g);
      };
      if (w.footprints[k].full) {
        for (int64_t l = 0; l < m; ++l) test(static_cast<uint32_t>(l));
      } else {
        for (uint32_t l : w.overflow) test(l);
      }
      w.list_count[k] = static_cast<uint32_t>(list.size()) - w.list_start[k];
    }
  }
  assemble(discs.size(), cand, w.thread_lists, w.list_thread, w.list_start, w.list_count, out);
  if (stats) {
    *stats = ClipPartnerStats();
    stats->candidates = m;
    stats->cell_entries = w.cell_items.size();
    stats->edge_on = edge_on;
    stats->tested_pairs = tested;
    stats->pairs = out->pairCount();
  }
}

void ClipPartnerFinder::find(PartnerMethod method, const SurfelDiscs& discs, const Camera* camera,
                             ClipPartners* out, const std::vector<uint32_t>* candidates,
                             ClipPartnerStats* stats) {
  if (method == PartnerMethod::kClipBuffer) {
    if (!camera) throw std::invalid_argument("clip partners: the clip-buffer method needs a camera");
    findClipBuffer(discs, *camera, out, candidates, stats);
  } else {
    findSpatial(discs, out, candidates, stats);
  }
}

}  // namespace rc
