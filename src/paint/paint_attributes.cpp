#include "relaxed_connectivity/paint/paint_attributes.h"

#include <cstring>
#include <iterator>
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
  if (cloud.attributes.has(kPaintTransferRate)) cloud.attributes.remove(kPaintTransferRate);
  cloud.attributes.add(kPaintTransferRate, ScalarType::kFloat64, 1, cloud.size());
  PaintColumns columns(cloud);
  for (size_t i = 0; i < cloud.size(); ++i) {
    PaintState p = initial;
    if (dry_from_colours && cloud.hasColors())
      p.dry.rgb = Vec3(cloud.colors[i][0], cloud.colors[i][1], cloud.colors[i][2]) / 255.0;
    columns.write(i, p);
  }
}

PaintColumns::PaintColumns(SurfelCloud& cloud) {
  Attribute** targets[] = {&wet_rgb_,    &wet_reflectivity_, &wet_shininess_,
                           &dry_rgb_,    &dry_reflectivity_, &dry_shininess_,
                           &wet_volume_, &dry_volume_,       &optical_density_};
  for (size_t c = 0; c < std::size(kColumns); ++c) {
    Attribute* a = cloud.attributes.find(kColumns[c].name);
    if (!a || a->type != ScalarType::kFloat64 || a->count != kColumns[c].count)
      throw std::invalid_argument(std::string("paint attributes: the cloud has no float64 '") +
                                  kColumns[c].name + "' column of " + std::to_string(kColumns[c].count));
    *targets[c] = a;
  }
  transfer_rate_ = cloud.attributes.find(kPaintTransferRate);
  if (transfer_rate_ && (transfer_rate_->type != ScalarType::kFloat64 || transfer_rate_->count != 1))
    throw std::invalid_argument(std::string("paint attributes: '") + kPaintTransferRate +
                                "' must be one float64 per surfel");
  size_ = wet_volume_->size();
}

PaintState PaintColumns::read(size_t i) const {
  if (i >= size_)
    throw std::invalid_argument("paint attributes: surfel " + std::to_string(i) + " of " +
                                std::to_string(size_));
  const auto get = [i](const Attribute* a, uint32_t k) {
    double v;
    std::memcpy(&v, a->bytes.data() + (i * a->count + k) * sizeof(double), sizeof(double));
    return v;
  };
  PaintState p;
  for (uint32_t k = 0; k < 3; ++k) p.wet.rgb[k] = get(wet_rgb_, k), p.dry.rgb[k] = get(dry_rgb_, k);
  p.wet.reflectivity = get(wet_reflectivity_, 0);
  p.wet.shininess = get(wet_shininess_, 0);
  p.dry.reflectivity = get(dry_reflectivity_, 0);
  p.dry.shininess = get(dry_shininess_, 0);
  p.wet_volume = get(wet_volume_, 0);
  p.dry_volume = get(dry_volume_, 0);
  p.optical_density = get(optical_density_, 0);
  if (transfer_rate_) p.transfer_rate = get(transfer_rate_, 0);
  return p;
}

void PaintColumns::write(size_t i, const PaintState& p) {
  if (i >= size_)
    throw std::invalid_argument("paint attributes: surfel " + std::to_string(i) + " of " +
                                std::to_string(size_));
  const auto set = [i](Attribute* a, uint32_t k, double v) {
    std::memcpy(a->bytes.data() + (i * a->count + k) * sizeof(double), &v, sizeof(double));
  };
  for (uint32_t k = 0; k < 3; ++k) set(wet_rgb_, k, p.wet.rgb[k]), set(dry_rgb_, k, p.dry.rgb[k]);
  set(wet_reflectivity_, 0, p.wet.reflectivity);
  set(wet_shininess_, 0, p.wet.shininess);
  set(dry_reflectivity_, 0, p.dry.reflectivity);
  set(dry_shininess_, 0, p.dry.shininess);
  set(wet_volume_, 0, p.wet_volume);
  set(dry_volume_, 0, p.dry_volume);
  set(optical_density_, 0, p.optical_density);
  if (transfer_rate_) set(transfer_rate_, 0, p.transfer_rate);
}

PaintState readPaint(const SurfelCloud& cloud, size_t i) {
  return PaintColumns(const_cast<SurfelCloud&>(cloud)).read(i);  // read() does not write
}

void writePaint(SurfelCloud& cloud, size_t i, const PaintState& p) {
  PaintColumns(cloud).write(i, p);
}

}  // namespace rc
