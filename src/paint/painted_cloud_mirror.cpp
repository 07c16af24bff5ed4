#include "relaxed_connectivity/paint/painted_cloud_mirror.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <unordered_set>

#include "relaxed_connectivity/paint/painted_surface_io.h"
#include "relaxed_connectivity/render/splat/environment_map.h"

namespace rc {

namespace {

float floatAt(const Attribute& a, size_t i) {
  float v;
  std::memcpy(&v, a.bytes.data() + sizeof(float) * i, sizeof(float));
  return v;
}

void pushFloat(Attribute& a, float v) {
  const size_t at = a.bytes.size();
  a.bytes.resize(at + sizeof(float));
  std::memcpy(a.bytes.data() + at, &v, sizeof(float));
}

/// The render channels of surfel i appended to `to` (the reflectivity column made when first needed).
void copyChannels(const SurfelCloud& from, size_t i, SurfelCloud* to) {
  to->positions.push_back(from.positions[i]);
  to->normals.push_back(from.normals[i]);
  to->radii.push_back(from.radii[i]);
  if (from.hasColors()) to->colors.push_back(from.colors[i]);
  if (const Attribute* r = from.attributes.find(kReflectivityAttribute)) {
    Attribute* column = to->attributes.find(kReflectivityAttribute);
    if (!column)
      column = &to->attributes.add(kReflectivityAttribute, ScalarType::kFloat32, 1, to->size() - 1);
    pushFloat(*column, floatAt(*r, i));
  }
}

}  // namespace

SurfelCloud PaintedCloudMirror::renderChannels(const SurfelCloud& from, const char* what,
                                               std::vector<uint32_t>* fathers) {
  from.validate();
  auto fail = [&](const std::string& problem) {
    throw std::invalid_argument(std::string("PaintedCloudMirror: ") + what + ": " + problem);
  };
  if (from.empty()) return SurfelCloud();
  if (!from.hasNormals()) fail("no normals");
  if (!from.hasRadii()) fail("no radii");
  const Attribute* father = from.attributes.find(kSurfelFather);
  if (!father || father->type != ScalarType::kUInt32 || father->count != 1)
    fail(std::string("no uint32 column '") + kSurfelFather + "'");
  fathers->resize(from.size());
  std::memcpy(fathers->data(), father->bytes.data(), sizeof(uint32_t) * from.size());
  SurfelCloud out;
  out.positions = from.positions;
  out.normals = from.normals;
  out.radii = from.radii;
  out.colors = from.colors;
  if (const Attribute* r = from.attributes.find(kReflectivityAttribute)) {
    if (r->count != 1)
      fail(std::string("'") + kReflectivityAttribute + "' has " + std::to_string(r->count) +
           " values per surfel");
    Attribute& column = out.attributes.add(kReflectivityAttribute, ScalarType::kFloat32, 1, from.size());
    for (size_t i = 0; i < from.size(); ++i) column.set(i, r->get(i));
  }
  return out;
}

void PaintedCloudMirror::reset(const SurfelCloud& cloud) {
  std::vector<uint32_t> fathers;
  SurfelCloud channels = renderChannels(cloud, "full cloud", &fathers);
  const uint32_t originals = fathers.empty() ? 0 : *std::max_element(fathers.begin(), fathers.end()) + 1;
  cloud_ = std::move(channels);
  colors_ = cloud_.hasColors();
  father_ = std::move(fathers);
  members_.assign(originals, {});
  slot_.resize(cloud_.size());
  for (size_t i = 0; i < cloud_.size(); ++i) {
    std::vector<uint32_t>& group = members_[father_[i]];
    slot_[i] = uint32_t(group.size());
    group.push_back(uint32_t(i));
  }
}

void PaintedCloudMirror::clear() {
  cloud_ = SurfelCloud();
  colors_ = false;
  father_.clear();
  slot_.clear();
  members_.clear();
}

const std::vector<uint32_t>& PaintedCloudMirror::surfelsOf(uint32_t original) const {
  static const std::vector<uint32_t> kNone;
  return original < members_.size() ? members_[original] : kNone;
}

void PaintedCloudMirror::push(const SurfelCloud& from, size_t i, uint32_t father) {
  cloud_.positions.push_back(from.positions[i]);
  cloud_.normals.push_back(from.normals[i]);
  cloud_.radii.push_back(from.radii[i]);
  if (colors_) cloud_.colors.push_back(from.colors[i]);
  if (Attribute* r = cloud_.attributes.find(kReflectivityAttribute)) {  // (0 where the delta has none)
    const Attribute* given = from.attributes.find(kReflectivityAttribute);
    pushFloat(*r, given ? floatAt(*given, i) : 0.0f);
  }
  if (father >= members_.size()) members_.resize(size_t(father) + 1);
  slot_.push_back(uint32_t(members_[father].size()));
  members_[father].push_back(uint32_t(cloud_.size() - 1));
  father_.push_back(father);
}

/// Moves the last surfel into `index` (its group's entry follows) and drops the last place. The caller has
/// already taken `index` out of its group.
void PaintedCloudMirror::removeAt(uint32_t index) {
  const uint32_t last = uint32_t(cloud_.size() - 1);
  if (index != last) {
    cloud_.positions[index] = cloud_.positions[last];
    cloud_.normals[index] = cloud_.normals[last];
    cloud_.radii[index] = cloud_.radii[last];
    if (colors_) cloud_.colors[index] = cloud_.colors[last];
    if (Attribute* r = cloud_.attributes.find(kReflectivityAttribute))
      std::memcpy(r->bytes.data() + sizeof(float) * index, r->bytes.data() + sizeof(float) * last,
                  sizeof(float));
    father_[index] = father_[last];
    slot_[index] = slot_[last];
    members_[father_[index]][slot_[index]] = index;
  }
  cloud_.positions.pop_back();
  cloud_.normals.pop_back();
  cloud_.radii.pop_back();
  if (colors_) cloud_.colors.pop_back();
  if (Attribute* r = cloud_.attributes.find(kReflectivityAttribute)) r->bytes.resize(sizeof(float) * last);
  father_.pop_back();
  slot_.pop_back();
}

void PaintedCloudMirror::applyDelta(const std::vector<uint32_t>& originals, const SurfelCloud& surfels,
                                    SurfelCloud* removed, SurfelCloud* added) {
  std::vector<uint32_t> fathers;
  const SurfelCloud channels = renderChannels(surfels, "delta", &fathers);
  if (cloud_.empty()) colors_ = channels.hasColors() || (channels.empty() && colors_);
  if (!channels.empty() && channels.hasColors() != colors_)
    throw std::invalid_argument(
        std::string("PaintedCloudMirror: delta: ") +
        (colors_ ? "no colours (the state has them)" : "colours (the state has none)"));
  const std::unordered_set<uint32_t> listed(originals.begin(), originals.end());
  for (size_t i = 0; i < fathers.size(); ++i)
    if (!listed.count(fathers[i]))
      throw std::invalid_argument("PaintedCloudMirror: delta: surfel " + std::to_string(i) + " has father " +
                                  std::to_string(fathers[i]) + ", which the delta does not list");
  for (const uint32_t original : originals) {  // (a repeated original finds its group empty)
    if (original >= members_.size()) continue;
    std::vector<uint32_t>& group = members_[original];
    while (!group.empty()) {
      const uint32_t index = group.back();
      group.pop_back();
      if (removed) copyChannels(cloud_, index, removed);
      removeAt(index);
    }
  }
  for (size_t i = 0; i < channels.size(); ++i) {
    push(channels, i, fathers[i]);
    if (added) copyChannels(channels, i, added);
  }
}

}  // namespace rc
