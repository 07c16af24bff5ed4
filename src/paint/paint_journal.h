// Undo and redo per stroke: a journal of surfel deltas. While a stroke records, the first change to an
// original (its enabled flag, paint or children, PaintSurfaceObserver) snapshots that original's state; at
// the end of the stroke the same originals are snapshotted again. Undo restores the "before" snapshots,
// redo the "after" ones, so both are exact (bitwise) for everything the stroke touched. The journal keeps
// at most `max_bytes` of snapshots; the oldest strokes are forgotten first.
//
// Changes made while nothing records (drying, diffusion, downsampling in the background) are not undone;
// undoing a stroke restores the originals it touched as they were when it began, background work on them
// included.
#pragma once

#include <cstddef>
#include <deque>
#include <vector>

#include "relaxed_connectivity/paint/paint_surface.h"

namespace rc {

class PaintJournal : private PaintSurfaceObserver {
 public:
  /// Observes `surface` (which must outlive the journal, and have no other observer) while recording.
  explicit PaintJournal(PaintSurface& surface, size_t max_bytes = size_t(256) << 20);
  ~PaintJournal() override;
  PaintJournal(const PaintJournal&) = delete;
  PaintJournal& operator=(const PaintJournal&) = delete;

  /// Opens a stroke (no-op while one is open); a new stroke forgets what could be redone.
  void beginStroke();
  /// Closes the open stroke: snapshots the touched originals' new state. A stroke that changed nothing is
  /// dropped. Returns whether a stroke was kept.
  bool endStroke();
  bool strokeOpen() const { return open_; }

  /// Changes to the surface are journalled only while a Recording lives (and a stroke is open), so that
  /// background work between paint events stays out of the journal.
  class Recording {
   public:
    explicit Recording(PaintJournal& journal);
    ~Recording();
    Recording(const Recording&) = delete;
    Recording& operator=(const Recording&) = delete;

   private:
    PaintJournal& journal_;
  };

  /// Undoes the last kept stroke (closing an open one first); false when there is nothing to undo.
  bool undo();
  /// Redoes the last undone stroke; false when there is nothing to redo.
  bool redo();
  /// Forgets everything (e.g. after loading another state).
  void clear();

  size_t undoCount() const { return done_.size(); }
  size_t redoCount() const { return undone_.size(); }
  /// Memory held by the snapshots (the journal size in the paint model's stats).
  size_t bytes() const { return bytes_; }
  size_t maxBytes() const { return max_bytes_; }

 private:
  struct Snapshot {
    uint32_t original;
    bool enabled;
    PaintState paint;
    std::vector<ChildSurfel> children;
  };
  struct Stroke {
    std::vector<Snapshot> before, after;
    size_t bytes = 0;
  };

  void beforeChange(size_t original) override;
  Snapshot snapshot(size_t original) const;
  static size_t bytesOf(const Snapshot& s);
  void apply(const std::vector<Snapshot>& snapshots);
  void trim();

  PaintSurface& surface_;
  size_t max_bytes_;
  std::deque<Stroke> done_;
  std::vector<Stroke> undone_;
  Stroke current_;
  bool open_ = false;
  int recording_ = 0;
  std::vector<uint32_t> touched_in_;  // per original: the stroke serial that snapshotted it
  uint32_t serial_ = 0;
  size_t bytes_ = 0;
};

}  // namespace rc
