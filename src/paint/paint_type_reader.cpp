#include "relaxed_connectivity/paint/paint_type_reader.h"

#include "relaxed_connectivity/io/yaml_reader.h"

namespace rc {

namespace {

[[noreturn]] void raisePaintTypeError(const std::string& message) {
  throw PaintTypeError(message);
}

}  // namespace

PaintType parsePaintType(const std::string& yaml_text, const std::string& source_name) {
  const YamlReader src(source_name, raisePaintTypeError);
  const YAML::Node root = src.parseMap(yaml_text, "a paint type must be a map of settings");
  src.allowKeys(
      root,
      {"name", "colour", "reflectivity", "shininess", "optical_density", "load_volume", "transfer_to_surface",
       "transfer_to_brush", "drying_rate", "drying", "diffusion", "imprint", "eraser"},
      "paint type");
  PaintType p;
  if (root["name"]) p.name = src.string(root["name"], "name");
  if (root["colour"]) {
    p.colour.rgb = src.vec3(root["colour"], "colour");
    if ((p.colour.rgb.array() < 0).any() || (p.colour.rgb.array() > 1).any())
      src.fail(root["colour"], "colour components must lie in [0, 1]");
  }
  if (root["reflectivity"]) p.colour.reflectivity = src.unitInterval(root["reflectivity"], "reflectivity");
  if (root["shininess"]) p.colour.shininess = src.nonNegative(root["shininess"], "shininess");
  const auto non_negative = [&](const YAML::Node& map, const char* key, double* value) {
    if (map[key]) *value = src.nonNegative(map[key], key);
  };
  if (root["optical_density"]) p.optical_density = src.positive(root["optical_density"], "optical_density");
  if (root["load_volume"]) p.load_volume = src.positive(root["load_volume"], "load_volume");
  non_negative(root, "transfer_to_surface", &p.transfer_to_surface);
  non_negative(root, "transfer_to_brush", &p.transfer_to_brush);
  non_negative(root, "drying_rate", &p.drying_rate);
  non_negative(root, "diffusion", &p.diffusion);
  if (const YAML::Node d = root["drying"]) {
    src.allowKeys(d, {"brighten", "reflectivity_factor", "shininess_factor"}, "drying");
    if (d["brighten"]) p.drying.brighten = src.unitInterval(d["brighten"], "brighten");
    if (d["reflectivity_factor"])
      p.drying.reflectivity_factor = src.unitInterval(d["reflectivity_factor"], "reflectivity_factor");
    if (d["shininess_factor"])
      p.drying.shininess_factor = src.unitInterval(d["shininess_factor"], "shininess_factor");
  }
  if (const YAML::Node m = root["imprint"]) {
    src.allowKeys(m, {"depth", "spacing"}, "imprint");
    non_negative(m, "depth", &p.imprint_depth);
    non_negative(m, "spacing", &p.imprint_spacing);
    if ((p.imprint_depth > 0) != (p.imprint_spacing > 0))
      src.fail(m, "imprint needs both depth and spacing (or neither)");
  }
  if (root["eraser"]) p.eraser = src.boolean(root["eraser"], "eraser");
  return p;
}

PaintType readPaintType(const std::string& path) {
  return parsePaintType(YamlReader::readFile(path, raisePaintTypeError), path);
}

}  // namespace rc
