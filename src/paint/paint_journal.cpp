#include "relaxed_connectivity/paint/paint_journal.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace rc {

PaintJournal::PaintJournal(PaintSurface& surface, size_t max_bytes)
    : surface_(surface), max_bytes_(max_bytes), touched_in_(surface.originalCount(), 0) {
  if (surface_.observer())
    throw std::logic_error("PaintJournal: the surface is already observed by another journal");
  surface_.setObserver(this);
}

PaintJournal::~PaintJournal() {
  surface_.setObserver(nullptr);
}

PaintJournal::Recording::Recording(PaintJournal& journal) : journal_(journal) {
  ++journal_.recording_;
}
PaintJournal::Recording::~Recording() {
  --journal_.recording_;
}

void PaintJournal::beginStroke() {
  if (open_) return;
  open_ = true;
  current_ = Stroke();
  if (++serial_ == 0) {  // wrapped: forget the serials of old strokes
    std::fill(touched_in_.begin(), touched_in_.end(), 0);
    serial_ = 1;
  }
}

void PaintJournal::beforeChange(size_t original) {
  if (!open_ || recording_ == 0 || touched_in_[original] == serial_) return;
  touched_in_[original] = serial_;
  current_.before.push_back(snapshot(original));
  current_.bytes += bytesOf(current_.before.back());
  bytes_ += bytesOf(current_.before.back());
}

PaintJournal::Snapshot PaintJournal::snapshot(size_t original) const {
  const PaintSurface& s = surface_;
  return {uint32_t(original), s.enabled(original), s.originalPaint(original), s.children(original)};
}

size_t PaintJournal::bytesOf(const Snapshot& s) {
  return sizeof(Snapshot) + s.children.capacity() * sizeof(ChildSurfel);
}

bool PaintJournal::endStroke() {
  if (!open_) return false;
  open_ = false;
  // Originals whose state ended where it began (e.g. paint set back unchanged) need no delta.
  Stroke stroke;
  stroke.before.reserve(current_.before.size());
  stroke.after.reserve(current_.before.size());
  for (Snapshot& before : current_.before) {
    Snapshot after = snapshot(before.original);
    if (after.enabled == before.enabled && after.paint == before.paint && after.children == before.children)
      continue;
    stroke.bytes += bytesOf(before) + bytesOf(after);
    stroke.before.push_back(std::move(before));
    stroke.after.push_back(std::move(after));
  }
  bytes_ -= current_.bytes;
  current_ = Stroke();
  if (stroke.before.empty()) return false;
  // The arrays hold what bytesOf() counts: without this, the room reserved for every touched original (or
  // push_back's doubling) stayed allocated, up to twice the counted bytes, uncounted by ~journal_bytes.
  stroke.before.shrink_to_fit();
  stroke.after.shrink_to_fit();
  for (const Stroke& s : undone_) bytes_ -= s.bytes;
  undone_.clear();
  bytes_ += stroke.bytes;
  done_.push_back(std::move(stroke));
  trim();
  return true;
}

void PaintJournal::apply(const std::vector<Snapshot>& snapshots) {
  for (const Snapshot& s : snapshots) surface_.restoreOriginal(s.original, s.enabled, s.paint, s.children);
}

bool PaintJournal::undo() {
  endStroke();
  if (done_.empty()) return false;
  Stroke stroke = std::move(done_.back());
  done_.pop_back();
  apply(stroke.before);
  undone_.push_back(std::move(stroke));
  return true;
}

bool PaintJournal::redo() {
  endStroke();  // a stroke that changed something forgets what could be redone
  if (undone_.empty()) return false;
  Stroke stroke = std::move(undone_.back());
  undone_.pop_back();
  apply(stroke.after);
  done_.push_back(std::move(stroke));
  return true;
}

void PaintJournal::clear() {
  done_.clear();
  undone_.clear();
  current_ = Stroke();
  open_ = false;
  bytes_ = 0;
}

void PaintJournal::trim() {
  while (bytes_ > max_bytes_ && done_.size() > 1) {  // the newest stroke stays undoable
    bytes_ -= done_.front().bytes;
    done_.pop_front();
  }
}

}  // namespace rc
