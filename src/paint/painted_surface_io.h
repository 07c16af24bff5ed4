// Save and load of the painted state (thesis 5.3 object representation): one binary PLY (float64 geometry)
// holding every original surfel, in order and with its own channels and current paint, followed by every
// child surfel grouped by father. Per vertex, `surfel_kind` (uint8: 0 enabled original, 1 disabled original,
// 2 child) and `father` (uint32: the original a child belongs to; an original's own index) restore the
// father/child structure; the paint columns are those of paint_attributes.h. Children carry the visible
// colour (5.8) when the originals have colours, so viewers show the painted object. Save -> load -> save
// is byte-identical.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "relaxed_connectivity/paint/paint_surface.h"

namespace rc {

constexpr const char* kSurfelKind = "surfel_kind";
constexpr const char* kSurfelFather = "father";

/// Writes the state to `path` (throws IoError naming the file on failure). With `atomic`, writes
/// `path`.tmp and renames it over `path`, so that an interrupted autosave never leaves half a file.
void savePaintedSurface(const std::string& path, const PaintSurface& surface, bool atomic = false);

/// Told the fraction done (0..1) and the stage of a long load.
using LoadProgress = std::function<void(double fraction, const std::string& stage)>;

/// Reads a state written by savePaintedSurface; throws IoError naming the file, the vertex and the problem
/// (missing columns, a child before the originals, a father out of range, a bad kind).
std::unique_ptr<PaintSurface> loadPaintedSurface(const std::string& path, const LoadProgress& progress = {});

}  // namespace rc
