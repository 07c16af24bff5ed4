// The object being painted (thesis 5.3, Fig. 5.2): the original surfels in a static kd-tree, each with a list
// of child surfels that replace it after resampling. Originals are never deleted (collision uses only them);
// a replaced original is disabled for rendering and paint transfer, children are removed and added freely.
#pragma once

#include <memory>
#include <vector>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/core/neighbor.h"
#include "relaxed_connectivity/core/sorted_cell_grid.h"
#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/paint/paint_state.h"

namespace rc {

/// A surfel that replaced (part of) an original after resampling (5.5): its geometry and paint.
struct ChildSurfel {
  Vec3 position;
  Vec3 normal;
  double radius = 0;
  PaintState paint;

  bool operator==(const ChildSurfel& o) const {
    return position == o.position && normal == o.normal && radius == o.radius && paint == o.paint;
  }
};

/// Told before the state of an original (its enabled flag, paint or children) changes: the undo journal
/// (paint_journal.h) snapshots what a stroke is about to change.
class PaintSurfaceObserver {
 public:
  virtual ~PaintSurfaceObserver() = default;
  virtual void beforeChange(size_t original) = 0;
};

class PaintSurface {
 public:
  /// Takes the original surfels (positions and unit normals required, radii optional) and builds the kd-tree
  /// once. Throws std::invalid_argument for an empty cloud, missing normals or non-finite positions/normals.
  explicit PaintSurface(SurfelCloud originals);

  const SurfelCloud& originals() const { return originals_; }
  /// Unique per constructed surface in this process: what a cache of queries against it (Brush) checks.
  uint64_t id() const { return id_; }
  size_t originalCount() const { return originals_.size(); }
  /// The median surfel radius (without radii: the median distance to the nearest other original, over a
  /// sample): the sampling scale collision margins use.
  double typicalRadius() const { return typical_radius_; }

  /// The k original surfels nearest to x, sorted by distance (squared distances); returns how many. Exact:
  /// answered from a uniform grid of the originals where the cells around x certify the result (near the
  /// surface, 3-5x faster than the kd-tree, bench_paint_brush), else by the kd-tree.
  size_t nearestOriginals(const Vec3& x, size_t k, Neighbor* out) const;
  /// A lower bound on the distance from x to every original surfel, in O(1) from a distance transform of the
  /// collision grid's occupied cells (0 within a cell of an occupied one; capped at a few cells).
  double clearanceLowerBound(const Vec3& x) const;
  /// The original surfel closest to x (exact), given an original `hint` near x (e.g. the closest one at a
  /// previous position): its distance bounds the search.
  Neighbor closestOriginal(const Vec3& x, uint32_t hint) const;
  /// The original surfel closest to x: the father a new child surfel is assigned to (5.5).
  uint32_t closestOriginal(const Vec3& x) const;

  /// Whether original i is rendered and painted (false once children replace it).
  bool enabled(size_t original) const { return enabled_[original] != 0; }
  void setEnabled(size_t original, bool enabled);
  const std::vector<ChildSurfel>& children(size_t original) const { return children_[original]; }
  /// Mutable access tells the observer first (read through a const surface to avoid that).
  std::vector<ChildSurfel>& children(size_t original) {
    notify(original);
    return children_[original];
  }
  /// Mutable access for a change no viewer sees (lookAlike before and after: drying under opaque paint): the
  /// observer is told (undo stays exact), takeChangedOriginals does not list it (no delta for nothing).
  PaintState& originalPaintUnseen(size_t original) {
    if (observer_) observer_->beforeChange(original);
    return original_paint_[original];
  }
  std::vector<ChildSurfel>& childrenUnseen(size_t original) {
    if (observer_) observer_->beforeChange(original);
    return children_[original];
  }
  /// The paint of an original surfel: from the cloud's paint columns when it has them (paint_attributes.h),
  /// else no wet paint over a dry base layer (volume 1) of the surfel's own colour (white without colours).
  const PaintState& originalPaint(size_t original) const { return original_paint_[original]; }
  PaintState& originalPaint(size_t original) {
    notify(original);
    return original_paint_[original];
  }
  /// The object's own colour at an original (its input colour; white without colours): what the eraser
  /// restores.
  PaintColour baseColour(size_t original) const;
  /// The indices of the originals within `radius` of x (enabled or not), into `out` (cleared first).
  void originalsWithin(const Vec3& x, double radius, std::vector<uint32_t>& out) const;
  /// Removes child `k` of `original` (a child deleted by resampling, 5.5); the original stays disabled. The
  /// list's room is trimmed when it exceeds twice its children (plus 4).
  void removeChild(size_t original, size_t k);
  /// Appends a child to its father (the closest original, or `father` when given) and disables the father.
  /// Returns the father.
  uint32_t addChild(const ChildSurfel& child);
  void addChild(uint32_t father, const ChildSurfel& child);
  /// An enabled original becomes its own first child (with its paint) and is disabled, so that a child
  /// added to it next hides nothing it showed or held (resampling next to a surfel it keeps, 5.5).
  void keepAsChild(uint32_t original);
  /// Removes every child of `original` (deleted children are dropped, 5.5) and re-enables it (downsampling,
  /// 5.5.2).
  void clearChildren(size_t original);

  /// Back to the object as constructed: every original enabled with its initial paint, no children (the
  /// paint model's clear). Every original is reported changed.
  void reset();
  /// Sets everything about one original at once (undo, redo, loading a saved state); the observer is not
  /// told.
  void restoreOriginal(size_t original, bool enabled, const PaintState& paint,
                       std::vector<ChildSurfel> children);
  /// The originals whose state (enabled flag, paint or children) changed since the last call, each once, in
  /// the order of their first change; clears the list. What a delta message sends.
  std::vector<uint32_t> takeChangedOriginals();
  /// The active surfels of the listed originals (the enabled original or its children), as activeCloud()
  /// writes them.
  /// Without `paint_columns` only what a viewer needs: positions, normals, radii, visible colours, `father`,
  /// `reflectivity` (a quarter of the bytes).
  SurfelCloud activeCloudOf(const std::vector<uint32_t>& originals, bool paint_columns = true) const;
  /// The observer told before each change (nullptr: none); not owned.
  void setObserver(PaintSurfaceObserver* observer) { observer_ = observer; }
  PaintSurfaceObserver* observer() const { return observer_; }

  size_t childCount() const { return child_count_; }
  /// Surfels shown and painted: enabled originals plus all children.
  size_t activeCount() const { return enabled_count_ + child_count_; }
  /// The active surfels as one cloud (positions, normals, radii, visible colours (5.8)) with their paint
  /// columns (paint_attributes.h) for rendering and export; the uint32 attribute `father` names each
  /// surfel's original, the float attribute `reflectivity` is the visible paint's (for environment
  /// maps, 5.7).
  SurfelCloud activeCloud() const;

 private:
  static constexpr double kGridCellSpacings = 3.0;
  static constexpr uint8_t kMaxCellDistance = 16;
  void buildCollisionGrid(double spacing);
  void buildCellDistances();
  /// The active surfels of originals list[0..count) (all when list is null); n: the expected size.
  SurfelCloud cloudOf(const uint32_t* list, size_t count, size_t n, bool paint_columns) const;
  void notify(size_t original) {
    if (!changed_flag_[original]) changed_flag_[original] = 1, changed_.push_back(uint32_t(original));
    if (observer_) observer_->beforeChange(original);
  }

  SurfelCloud originals_;
  uint64_t id_;
  std::unique_ptr<KdTree> tree_;
  SortedCellGrid grid_;                 // the originals sorted by cell, for nearestOriginals
  std::vector<Vec3> sorted_positions_;  // positions in grid order
  std::vector<uint8_t> cell_distance_;  // Chebyshev distance in cells to the nearest occupied cell (capped)
  std::vector<uint8_t> enabled_;
  std::vector<std::vector<ChildSurfel>> children_;
  std::vector<PaintState> original_paint_;
  size_t enabled_count_ = 0;
  size_t child_count_ = 0;
  double typical_radius_ = 0;
  PaintSurfaceObserver* observer_ = nullptr;
  std::vector<uint8_t> changed_flag_;
  std::vector<uint32_t> changed_;
};

}  // namespace rc
