#include "relaxed_connectivity/paint/paint_surface.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "relaxed_connectivity/paint/paint_attributes.h"

namespace rc {

PaintSurface::PaintSurface(SurfelCloud originals) : originals_(std::move(originals)) {
  static std::atomic<uint64_t> next_id{1};
  id_ = next_id++;
  originals_.validate();
  if (originals_.empty()) throw std::invalid_argument("PaintSurface: the object has no surfels");
  if (!originals_.hasNormals())
    throw std::invalid_argument("PaintSurface: the object's surfels need normals");
  for (size_t i = 0; i < originals_.size(); ++i)
    if (!originals_.positions[i].allFinite() || !originals_.normals[i].allFinite() ||
        originals_.normals[i].norm() == 0)
      throw std::invalid_argument("PaintSurface: surfel " + std::to_string(i) +
                                  " has a non-finite position or normal, or a zero normal");
  for (Vec3& n : originals_.normals)  // unit normals stay bitwise as given (a saved state reloads exactly)
    if (std::abs(n.squaredNorm() - 1.0) > 1e-12) n.normalize();
  tree_ = std::make_unique<KdTree>(originals_.positions);
  changed_flag_.assign(originals_.size(), 0);
  reset();
  takeChangedOriginals();  // nothing has changed yet
  // The median nearest-neighbour spacing over a sample of ~1000 originals; the median radius when the cloud
  // has radii, else that spacing, is the typical radius.
  std::vector<double> spacing, radii;
  const size_t stride = std::max<size_t>(1, originals_.size() / 1000);
  for (size_t i = 0; i < originals_.size(); i += stride) {
    Neighbor n[2];
    if (tree_->knn(originals_.positions[i], 2, n) == 2 && n[1].sq_dist > 0)
      spacing.push_back(std::sqrt(n[1].sq_dist));
    if (originals_.hasRadii()) radii.push_back(originals_.radii[i]);
  }
  const auto median = [](std::vector<double>& v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double median_spacing = median(spacing);
  typical_radius_ = originals_.hasRadii() ? median(radii) : median_spacing;
  buildCollisionGrid(median_spacing);
}

void PaintSurface::buildCollisionGrid(double spacing) {
  // Cells of kGridCellSpacings median nearest-neighbour spacings: the 27 cells around a query near the
  // surface hold about a hundred surfels, enough to certify the 10 nearest.
  const double cell = kGridCellSpacings * spacing;
  grid_.build(originals_.positions, cell, 1, "PaintSurface");
  buildCellDistances();
  sorted_positions_.resize(originals_.size());
  for (size_t s = 0; s < sorted_positions_.size(); ++s)
    sorted_positions_[s] = originals_.positions[grid_.order()[s]];
}

void PaintSurface::buildCellDistances() {
  // Breadth-first over the 26 neighbours from every occupied cell: the Chebyshev distance in cells, up to
  // kMaxCellDistance (farther cells keep that value, still a valid bound).
  const size_t nx = grid_.dim(0), ny = grid_.dim(1), nz = grid_.dim(2), cells = nx * ny * nz;
  cell_distance_.assign(cells, kMaxCellDistance);
  std::vector<uint32_t> front, next;
  for (size_t c = 0; c < cells; ++c)
    if (grid_.occupied(c)) cell_distance_[c] = 0, front.push_back(uint32_t(c));
  for (uint8_t d = 1; d < kMaxCellDistance && !front.empty(); ++d) {
    next.clear();
    for (const uint32_t c : front) {
      const long x = long(c % nx), y = long((c / nx) % ny), z = long(c / (nx * ny));
      for (long dz = -1; dz <= 1; ++dz)
        for (long dy = -1; dy <= 1; ++dy)
          for (long dx = -1; dx <= 1; ++dx) {
            const long X = x + dx, Y = y + dy, Z = z + dz;
            if (X < 0 || Y < 0 || Z < 0 || X >= long(nx) || Y >= long(ny) || Z >= long(nz)) continue;
            const size_t n = size_t(X) + nx * (size_t(Y) + ny * size_t(Z));
            if (cell_distance_[n] > d) cell_distance_[n] = d, next.push_back(uint32_t(n));
          }
    }
    front.swap(next);
  }
}

double PaintSurface::clearanceLowerBound(const Vec3& x) const {
  if (!x.allFinite()) return 0;
  double c[3], outside = 0;
  grid_.cellCoordinates(x, c, &outside);
  if (outside > 0) return outside;  // no surfel lies outside the grid's box
  size_t i[3];
  for (int a = 0; a < 3; ++a) i[a] = size_t(std::min(std::max(c[a], 0.0), double(grid_.dim(a) - 1)));
  const size_t cell = i[0] + grid_.dim(0) * (i[1] + grid_.dim(1) * i[2]);
  // k cells apart along some axis: at least k - 1 whole cells lie between x and any surfel.
  return std::max(0.0, double(cell_distance_[cell]) - 1.0) * grid_.cellWidth();
}

size_t PaintSurface::nearestOriginals(const Vec3& x, size_t k, Neighbor* out) const {
  // The cells around x hold every surfel closer than one cell width: if the k-th nearest among them is that
  // close, they are the k nearest of all (the kd-tree answers otherwise).
  k = std::min(k, originals_.size());
  if (k == 0) return 0;
  SortedCellGrid::Run runs[9];
  const int num_runs = x.allFinite() ? grid_.runsAround(x, runs) : 0;
  size_t count = 0;
  for (int r = 0; r < num_runs; ++r)
    for (uint32_t s = runs[r].begin; s < runs[r].end; ++s) {
      const double d = (sorted_positions_[s] - x).squaredNorm();
      if (count == k && d >= out[k - 1].sq_dist) continue;
      size_t i = count < k ? count++ : k - 1;
      for (; i > 0 && out[i - 1].sq_dist > d; --i) out[i] = out[i - 1];
      out[i] = {s, d};
    }
  const double width = grid_.cellWidth();
  if (count < k || out[k - 1].sq_dist > width * width) return tree_->knn(x, k, out);
  for (size_t i = 0; i < k; ++i) out[i].index = grid_.order()[out[i].index];
  return k;
}

uint32_t PaintSurface::closestOriginal(const Vec3& x) const {
  Neighbor n;
  tree_->knn(x, 1, &n);
  return n.index;
}

Neighbor PaintSurface::closestOriginal(const Vec3& x, uint32_t hint) const {
  Neighbor found;
  const double bound = (originals_.positions.at(hint) - x).squaredNorm();
  const double width = grid_.cellWidth();
  if (bound <= width * width) {  // the grid certifies it
    nearestOriginals(x, 1, &found);
    return found;
  }
  if (!tree_->nearestWithin(x, bound, &found)) found = {hint, bound};  // rounding: the hint itself
  return found;
}

PaintColour PaintSurface::baseColour(size_t original) const {
  PaintColour c;
  c.rgb = Vec3::Ones();
  if (originals_.hasColors()) {
    const Rgba& rgba = originals_.colors.at(original);
    c.rgb = Vec3(rgba[0], rgba[1], rgba[2]) / 255.0;
  }
  return c;
}

void PaintSurface::reset() {
  if (hasPaintAttributes(originals_)) {
    original_paint_.resize(originals_.size());
    const PaintColumns columns(originals_);
    for (size_t i = 0; i < originals_.size(); ++i) original_paint_[i] = columns.read(i);
  } else {
    PaintState base;  // the object's own colour as a dry base layer
    base.dry = baseColour(0);
    base.dry_volume = 1.0;
    original_paint_.assign(originals_.size(), base);
    for (size_t i = 0; i < originals_.size(); ++i) original_paint_[i].dry = baseColour(i);
  }
  children_.assign(originals_.size(), {});
  enabled_.assign(originals_.size(), 1);
  enabled_count_ = originals_.size();
  child_count_ = 0;
  for (size_t i = 0; i < originals_.size(); ++i)
    if (!changed_flag_[i]) changed_flag_[i] = 1, changed_.push_back(uint32_t(i));
}

void PaintSurface::setEnabled(size_t original, bool enabled) {
  if (enabled_[original] == uint8_t(enabled)) return;
  notify(original);
  enabled_[original] = enabled;
  enabled ? ++enabled_count_ : --enabled_count_;
}

uint32_t PaintSurface::addChild(const ChildSurfel& child) {
  const uint32_t father = closestOriginal(child.position);
  addChild(father, child);
  return father;
}

void PaintSurface::addChild(uint32_t father, const ChildSurfel& child) {
  notify(father);
  children_.at(father).push_back(child);
  ++child_count_;
  setEnabled(father, false);
}

void PaintSurface::keepAsChild(uint32_t original) {
  if (!enabled_.at(original)) return;
  addChild(original,
           {originals_.positions[original], originals_.normals[original],
            originals_.hasRadii() ? originals_.radii[original] : typical_radius_, original_paint_[original]});
}

void PaintSurface::originalsWithin(const Vec3& x, double radius, std::vector<uint32_t>& out) const {
  std::vector<Neighbor> found;
  tree_->radius(x, radius, found, true);
  out.clear();
  for (const Neighbor& n : found) out.push_back(n.index);
}

void PaintSurface::removeChild(size_t original, size_t k) {
  std::vector<ChildSurfel>& list = children_.at(original);
  if (k >= list.size())
    throw std::out_of_range("PaintSurface::removeChild: child " + std::to_string(k) + " of " +
                            std::to_string(list.size()));
  notify(original);
  list.erase(list.begin() + long(k));
  --child_count_;
  // Resampling removes and adds children all session long: a list keeps at most twice its children's room
  // (plus a few), not the most it ever held.
  if (list.capacity() > 2 * list.size() + 4) list.shrink_to_fit();
}

void PaintSurface::clearChildren(size_t original) {
  notify(original);
  child_count_ -= children_.at(original).size();
  children_[original].clear();
  children_[original].shrink_to_fit();
  setEnabled(original, true);
}

std::vector<uint32_t> PaintSurface::takeChangedOriginals() {
  for (uint32_t i : changed_) changed_flag_[i] = 0;
  return std::exchange(changed_, {});
}

void PaintSurface::restoreOriginal(size_t original, bool enabled, const PaintState& paint,
                                   std::vector<ChildSurfel> children) {
  std::vector<ChildSurfel>& list = children_.at(original);
  if (!changed_flag_[original]) changed_flag_[original] = 1, changed_.push_back(uint32_t(original));
  child_count_ = child_count_ - list.size() + children.size();
  list = std::move(children);
  original_paint_[original] = paint;
  if (enabled_[original] != uint8_t(enabled)) {
    enabled_[original] = enabled;
    enabled ? ++enabled_count_ : --enabled_count_;
  }
}

SurfelCloud PaintSurface::activeCloud() const {
  return cloudOf(nullptr, originals_.size(), activeCount(), true);
}

SurfelCloud PaintSurface::activeCloudOf(const std::vector<uint32_t>& originals, bool paint_columns) const {
  for (uint32_t i : originals)
    if (i >= originals_.size())
      throw std::out_of_range("PaintSurface::activeCloudOf: original " + std::to_string(i) + " of " +
                              std::to_string(originals_.size()));
  return cloudOf(originals.data(), originals.size(), originals.size(), paint_columns);
}

SurfelCloud PaintSurface::cloudOf(const uint32_t* list, size_t count, size_t n, bool paint_columns) const {
  SurfelCloud out;
  out.positions.reserve(n);
  out.normals.reserve(n);
  out.radii.reserve(n);
  out.colors.reserve(n);
  std::vector<const PaintState*> paint;
  paint.reserve(n);
  std::vector<uint32_t> fathers;
  fathers.reserve(n);
  const auto push = [&](const Vec3& p, const Vec3& normal, double radius, const PaintState& state,
                        uint32_t father) {
    out.positions.push_back(p);
    out.normals.push_back(normal);
    out.radii.push_back(radius);
    const Vec3 c = visibleColour(state).rgb;  // (5.8)
    out.colors.push_back({colourByte(c[0]), colourByte(c[1]), colourByte(c[2]), 255});
    paint.push_back(&state);
    fathers.push_back(father);
  };
  for (size_t k = 0; k < count; ++k) {
    const size_t i = list ? list[k] : k;
    if (enabled_[i])
      push(originals_.positions[i], originals_.normals[i], originals_.hasRadii() ? originals_.radii[i] : 0.0,
           original_paint_[i], uint32_t(i));
    for (const ChildSurfel& c : children_[i]) push(c.position, c.normal, c.radius, c.paint, uint32_t(i));
  }
  if (!originals_.hasRadii() && child_count_ == 0) out.radii.clear();
  if (paint_columns) {
    addPaintAttributes(out, PaintState(), false);
    PaintColumns columns(out);
    for (size_t k = 0; k < out.size(); ++k) columns.write(k, *paint[k]);
  }
  Attribute& father = out.attributes.add("father", ScalarType::kUInt32, 1, out.size());
  for (size_t k = 0; k < out.size(); ++k) father.set(k, fathers[k]);
  // The visible reflectivity (5.8 applied to all paint attributes) for renderers with an environment map
  // (5.7).
  Attribute& reflectivity = out.attributes.add("reflectivity", ScalarType::kFloat32, 1, out.size());
  for (size_t k = 0; k < out.size(); ++k) reflectivity.set(k, visibleColour(*paint[k]).reflectivity);
  return out;
}

}  // namespace rc
