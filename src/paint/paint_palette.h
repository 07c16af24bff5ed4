// The palette (thesis Fig. 5.1): a small surfel board beside the object with wells of wet paint. It becomes
// part of the painted object (appendPalette), so the brush dips into it with the same collision and paint
// exchange (5.9)-(5.11) as on the object: it loads paint where tau surface->brush > 0, and it leaves paint on
// the palette where colours then mix (5.11), as on a real palette. Read from config/paint/palettes/*.yaml.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/paint/paint_state.h"

namespace rc {

struct PaletteWell {
  double x = 0, y = 0;   ///< centre on the board [m] (board axes)
  double radius = 0.01;  ///< [m]
  PaintColour colour;    ///< of the wet paint
  double optical_density = 4.0;
  double volume = 20.0;  ///< wet volume per surfel (a deep well: many loads)
};

struct PaletteSpec {
  std::string name = "palette";
  Vec3 centre = Vec3(0.12, 0, 0);    ///< [m], in the object's frame
  Vec3 normal = Vec3::UnitZ();       ///< up, towards the brush
  double width = 0.1, depth = 0.06;  ///< board size [m] along its x and y axes
  double spacing = 1e-3;             ///< surfel spacing [m]
  Vec3 board_colour = Vec3(0.85, 0.75, 0.55);
  std::vector<PaletteWell> wells;
};

class PaletteError : public std::runtime_error {
 public:
  explicit PaletteError(const std::string& message) : std::runtime_error(message) {}
};

/// Throws PaletteError "<file>:<line>:<column>: <problem>" for a bad key or value (a well off the board,
/// overlapping wells, a colour outside [0, 1], ...).
PaletteSpec parsePalette(const std::string& yaml_text, const std::string& source_name);
PaletteSpec readPalette(const std::string& path);

/// The board as surfels (square grid, normals, radii, colours) with paint columns: the board's colour dry,
/// each well's paint wet on the surfels inside it. The board's x axis is the object frame's x projected
/// onto the board (y when the normal is along x).
SurfelCloud makePaletteCloud(const PaletteSpec& spec);

/// Appends the palette to the object: the object gets paint columns first (its colours as the dry layer,
/// white without colours, as PaintSurface would start it); channels only one side has are dropped (e.g.
/// colours when the object has none: the board then starts white under its wells). Returns the index of the
/// first palette surfel.
size_t appendPalette(SurfelCloud& object, const PaletteSpec& spec);

}  // namespace rc
