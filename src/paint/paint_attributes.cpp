#include "relaxed_connectivity/paint/paint_attributes.h"

#include <stdexcept>
#include <string>

namespace rc {

namespace {

struct Column {
  const char* name;
  uint32_t count;
};
constexpr Column kColumns[] = {{kPaintWetRgb, 3},    {kPaintWetReflectivity, 1}, {kPaintWetShininess, 1},
                               {kPaintDryRgb, 3},    {kPaintDryReflectivity, 1}, {kPaintDryShininess, 1},
                               {kPaintWetVolume, 1}, {kPaintDryVolume, 1},       {kPaintOpticalDensity, 1}};

const Attribute& column(const SurfelCloud& cloud, const char* name, size_t i) {
  const Attribute* a = cloud.attributes.find(name);
  if (!a)
    throw std::invalid_argument(std::string("paint attributes: the cloud has no '") + name + "' column");
  if (i >= a->size())
    throw std::invalid_argument(std::string("paint attributes: surfel ") + std::to_string(i) + " beyond '" +
                                name + "' (" + std::to_string(a->size()) + " surfels)");
  return *a;
}

Attribute& column(SurfelCloud& cloud, const char* name, size_t i) {
  return const_cast<Attribute&>(column(static_cast<const SurfelCloud&>(cloud), name, i));
}

}  // namespace

bool hasPaintAttributes(const SurfelCloud& cloud) {
  for (const Column& c : kColumns) {
    const Attribute* a = cloud.attributes.find(c.name);
    if (!a || a->type != ScalarType::kFloat64 || a->count != c.count || a->size() != cloud.size())
      return false;
  }
  return true;
}

void addPaintAttributes(SurfelCloud& cloud, const PaintState& initial, bool dry_from_colours) {
  for (const Column& c : kColumns) {
    if (cloud.attributes.has(c.name)) cloud.attributes.remove(c.name);
    cloud.attributes.add(c.name, ScalarType::kFloat64, c.count, cloud.size());
  }
  for (size_t i = 0; i < cloud.size(); ++i) {
    PaintState p = initial;
    if (dry_from_colours && cloud.hasColors())
      p.dry.rgb = Vec3(cloud.colors[i][0], cloud.colors[i][1], cloud.colors[i][2]) / 255.0;
    writePaint(cloud, i, p);
  }
}

PaintState readPaint(const SurfelCloud& cloud, size_t i) {
  PaintState p;
  const Attribute& wet = column(cloud, kPaintWetRgb, i);
  const Attribute& dry = column(cloud, kPaintDryRgb, i);
  for (uint32_t k = 0; k < 3; ++k) p.wet.rgb[k] = wet.get(i, k), p.dry.rgb[k] = dry.get(i, k);
  p.wet.reflectivity = column(cloud, kPaintWetReflectivity, i).get(i);
  p.wet.shininess = column(cloud, kPaintWetShininess, i).get(i);
  p.dry.reflectivity = column(cloud, kPaintDryReflectivity, i).get(i);
  p.dry.shininess = column(cloud, kPaintDryShininess, i).get(i);
  p.wet_volume = column(cloud, kPaintWetVolume, i).get(i);
  p.dry_volume = column(cloud, kPaintDryVolume, i).get(i);
  p.optical_density = column(cloud, kPaintOpticalDensity, i).get(i);
  return p;
}

void writePaint(SurfelCloud& cloud, size_t i, const PaintState& p) {
  Attribute& wet = column(cloud, kPaintWetRgb, i);
  Attribute& dry = column(cloud, kPaintDryRgb, i);
  for (uint32_t k = 0; k < 3; ++k) wet.set(i, p.wet.rgb[k], k), dry.set(i, p.dry.rgb[k], k);
  column(cloud, kPaintWetReflectivity, i).set(i, p.wet.reflectivity);
  column(cloud, kPaintWetShininess, i).set(i, p.wet.shininess);
  column(cloud, kPaintDryReflectivity, i).set(i, p.dry.reflectivity);
  column(cloud, kPaintDryShininess, i).set(i, p.dry.shininess);
  column(cloud, kPaintWetVolume, i).set(i, p.wet_volume);
  column(cloud, kPaintDryVolume, i).set(i, p.dry_volume);
  column(cloud, kPaintOpticalDensity, i).set(i, p.optical_density);
}

}  // namespace rc
