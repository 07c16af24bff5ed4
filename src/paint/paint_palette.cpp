#include "relaxed_connectivity/paint/paint_palette.h"

#include <cmath>

#include "relaxed_connectivity/io/yaml_reader.h"
#include "relaxed_connectivity/paint/paint_attributes.h"

namespace rc {

namespace {

[[noreturn]] void raisePaletteError(const std::string& message) {
  throw PaletteError(message);
}

Vec3 unitColour(const YamlReader& src, const YAML::Node& node, const std::string& what) {
  const Vec3 c = src.vec3(node, what);
  if ((c.array() < 0).any() || (c.array() > 1).any()) src.fail(node, what + " components must lie in [0, 1]");
  return c;
}

/// Unit board axes: x along the frame's x projected onto the board (its y when the normal is along x).
void boardAxes(const Vec3& normal, Vec3* ex, Vec3* ey) {
  const Vec3 ref = std::abs(normal.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  *ex = (ref - normal.dot(ref) * normal).normalized();
  *ey = normal.cross(*ex);
}

}  // namespace

PaletteSpec parsePalette(const std::string& yaml_text, const std::string& source_name) {
  const YamlReader src(source_name, raisePaletteError);
  const YAML::Node root = src.parseMap(yaml_text, "a palette must be a map of settings");
  src.allowKeys(root, {"name", "centre", "normal", "size", "spacing", "colour", "wells"}, "palette");
  PaletteSpec p;
  if (root["name"]) p.name = src.string(root["name"], "name");
  if (root["centre"]) p.centre = src.vec3(root["centre"], "centre");
  if (root["normal"]) {
    p.normal = src.vec3(root["normal"], "normal");
    if (!(p.normal.norm() > 0)) src.fail(root["normal"], "normal must not be zero");
    p.normal.normalize();
  }
  if (const YAML::Node size = root["size"]) {
    if (!size.IsSequence() || size.size() != 2) src.fail(size, "size must be [width, depth] in metres");
    p.width = src.positive(size[0], "size[0]");
    p.depth = src.positive(size[1], "size[1]");
  }
  if (root["spacing"]) p.spacing = src.positive(root["spacing"], "spacing");
  if (p.width / p.spacing > 2000 || p.depth / p.spacing > 2000)
    src.fail(root["spacing"] ? root["spacing"] : root, "more than 2000 surfels along a side: raise spacing");
  if (root["colour"]) p.board_colour = unitColour(src, root["colour"], "colour");
  const YAML::Node wells = src.require(root, "wells", "palette");
  if (!wells.IsSequence() || wells.size() == 0) src.fail(wells, "wells must be a non-empty list");
  for (const YAML::Node& w : wells) {
    src.allowKeys(w,
                  {"position", "radius", "colour", "reflectivity", "shininess", "optical_density", "volume"},
                  "well");
    PaletteWell well;
    const YAML::Node pos = src.require(w, "position", "well");
    if (!pos.IsSequence() || pos.size() != 2) src.fail(pos, "position must be [x, y] on the board in metres");
    well.x = src.number(pos[0], "position[0]");
    well.y = src.number(pos[1], "position[1]");
    if (w["radius"]) well.radius = src.positive(w["radius"], "radius");
    well.colour.rgb = unitColour(src, src.require(w, "colour", "well"), "colour");
    if (w["reflectivity"]) well.colour.reflectivity = src.unitInterval(w["reflectivity"], "reflectivity");
    if (w["shininess"]) well.colour.shininess = src.nonNegative(w["shininess"], "shininess");
    if (w["optical_density"]) well.optical_density = src.positive(w["optical_density"], "optical_density");
    if (w["volume"]) well.volume = src.positive(w["volume"], "volume");
    if (std::abs(well.x) + well.radius > 0.5 * p.width || std::abs(well.y) + well.radius > 0.5 * p.depth)
      src.fail(w, "the well does not lie on the board (size " + std::to_string(p.width) + " x " +
                      std::to_string(p.depth) + " m)");
    for (const PaletteWell& other : p.wells)
      if (std::hypot(well.x - other.x, well.y - other.y) < well.radius + other.radius)
        src.fail(w, "the well overlaps an earlier one");
    p.wells.push_back(well);
  }
  return p;
}

PaletteSpec readPalette(const std::string& path) {
  return parsePalette(YamlReader::readFile(path, raisePaletteError), path);
}

SurfelCloud makePaletteCloud(const PaletteSpec& spec) {
  Vec3 ex, ey;
  boardAxes(spec.normal, &ex, &ey);
  const int nx = std::max(1, int(std::lround(spec.width / spec.spacing))),
            ny = std::max(1, int(std::lround(spec.depth / spec.spacing)));
  SurfelCloud c;
  std::vector<int> well_of;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double x = -0.5 * spec.width + i * spec.spacing, y = -0.5 * spec.depth + j * spec.spacing;
      c.positions.push_back(spec.centre + x * ex + y * ey);
      int well = -1;
      for (size_t k = 0; k < spec.wells.size(); ++k)
        if (std::hypot(x - spec.wells[k].x, y - spec.wells[k].y) <= spec.wells[k].radius) well = int(k);
      well_of.push_back(well);
    }
  c.normals.assign(c.size(), spec.normal);
  c.radii.assign(c.size(), 0.75 * spec.spacing);
  const auto byte = [](double v) { return uint8_t(std::lround(255.0 * v)); };
  c.colors.assign(c.size(),
                  {byte(spec.board_colour[0]), byte(spec.board_colour[1]), byte(spec.board_colour[2]), 255});
  PaintState board;
  board.dry_volume = 1.0;
  addPaintAttributes(c, board, true);  // the board's colour as the dry layer
  PaintColumns columns(c);
  for (size_t i = 0; i < c.size(); ++i) {
    if (well_of[i] < 0) continue;
    const PaletteWell& w = spec.wells[size_t(well_of[i])];
    PaintState s = columns.read(i);
    s.wet = w.colour;
    s.wet_volume = w.volume;
    s.optical_density = w.optical_density;
    columns.write(i, s);
  }
  return c;
}

size_t appendPalette(SurfelCloud& object, const PaletteSpec& spec) {
  if (!hasPaintAttributes(object)) {
    PaintState base;  // as PaintSurface starts an object without paint columns
    base.dry.rgb = Vec3::Ones();
    base.dry_volume = 1.0;
    addPaintAttributes(object, base, true);
  }
  const size_t first = object.size();
  SurfelCloud palette = makePaletteCloud(spec);
  if (!object.hasRadii()) palette.radii.clear();
  // The palette's columns in the object's order; columns only the object has are zeros on the board.
  AttributeSet ordered;
  for (const Attribute& a : object.attributes.columns()) {
    Attribute& column = ordered.add(a.name, a.type, a.count, palette.size());
    if (const Attribute* mine = palette.attributes.find(a.name);
        mine && mine->bytes.size() == column.bytes.size())
      column.bytes = mine->bytes;
  }
  palette.attributes = std::move(ordered);
  object.append(palette);
  return first;
}

}  // namespace rc
