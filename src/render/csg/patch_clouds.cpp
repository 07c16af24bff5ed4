#include "relaxed_connectivity/render/csg/patch_clouds.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace rc {
namespace {

std::string countOf(size_t bad, size_t n) {
  return std::to_string(bad) + " of " + std::to_string(n) + " surfels";
}

}  // namespace

void checkRenderableCloud(const SurfelCloud& cloud, bool require_patch_id) {
  const size_t n = cloud.size();
  if (n == 0) throw std::invalid_argument("empty cloud (0 surfels)");
  cloud.validate();
  if (!cloud.hasNormals()) throw std::invalid_argument("no normals (fields normal_x, normal_y, normal_z)");
  if (!cloud.hasRadii() && !cloud.hasAxes())
    throw std::invalid_argument("no surfel extent (field radius or tangent axes t1x..t2z)");
  size_t bad_position = 0, bad_normal = 0, bad_extent = 0;
  for (size_t i = 0; i < n; ++i) {
    bad_position += !cloud.positions[i].allFinite();
    const double normal_length = cloud.normals[i].norm();
    bad_normal += !(std::isfinite(normal_length) && normal_length > 1e-6);
    if (cloud.hasAxes()) {
      const double a = cloud.axes1[i].norm(), b = cloud.axes2[i].norm();
      bad_extent += !(std::isfinite(a) && std::isfinite(b) && a > 0 && b > 0);
    } else {
      bad_extent += !(std::isfinite(cloud.radii[i]) && cloud.radii[i] > 0);
    }
  }
  if (bad_position) throw std::invalid_argument(countOf(bad_position, n) + " have non-finite positions");
  if (bad_normal) throw std::invalid_argument(countOf(bad_normal, n) + " have zero or non-finite normals");
  if (bad_extent)
    throw std::invalid_argument(countOf(bad_extent, n) + " have non-positive or non-finite " +
                                (cloud.hasAxes() ? "tangent axes" : "radii"));
  if (const Attribute* roles = cloud.attributes.find(kSurfelRoleAttribute)) {
    size_t bad_role = 0;
    for (size_t i = 0; i < n; ++i) {
      const double role = roles->get(i);
      bad_role += !(role == 0 || role == 1 || role == 2);
    }
    if (bad_role)
      throw std::invalid_argument(countOf(bad_role, n) +
                                  " have a surfel_role other than 0 (surface), 1 or 2 (discontinuity)");
  }
  if (!require_patch_id) return;
  const Attribute* ids = cloud.attributes.find(kPatchIdAttribute);
  if (!ids) throw std::invalid_argument("no patch_id field (required on this topic)");
  size_t bad_id = 0;
  for (size_t i = 0; i < n; ++i) {
    const double id = ids->get(i);
    bad_id += !(std::isfinite(id) && id >= 0 && id == std::floor(id) && id < 2147483647.0);
  }
  if (bad_id)
    throw std::invalid_argument(countOf(bad_id, n) + " have a patch_id that is not an integer >= 0");
}

SurfelCloud mergePatchClouds(const std::vector<PatchCloudInput>& inputs, const std::string& frame_id,
                             const Rgba& default_color) {
  size_t total = 0;
  bool all_axes = !inputs.empty(), any_color = false, all_radii = !inputs.empty();
  for (const PatchCloudInput& in : inputs) {
    if (!in.cloud) throw std::invalid_argument("mergePatchClouds: null cloud");
    checkRenderableCloud(*in.cloud, in.patch_id < 0);
    total += in.cloud->size();
    all_axes = all_axes && in.cloud->hasAxes();
    all_radii = all_radii && in.cloud->hasRadii();
    any_color = any_color || in.cloud->hasColors();
  }
  SurfelCloud merged;
  merged.frame_id = frame_id;
  merged.positions.reserve(total);
  merged.normals.reserve(total);
  merged.radii.reserve(total);
  if (all_axes) {
    merged.axes1.reserve(total);
    merged.axes2.reserve(total);
  }
  if (any_color) merged.colors.reserve(total);
  Attribute& ids = merged.attributes.add(kPatchIdAttribute, ScalarType::kInt32, 1, total);
  Attribute& roles = merged.attributes.add(kSurfelRoleAttribute, ScalarType::kInt32, 1, total);
  int32_t* id_out = reinterpret_cast<int32_t*>(ids.bytes.data());
  int32_t* role_out = reinterpret_cast<int32_t*>(roles.bytes.data());
  for (const PatchCloudInput& in : inputs) {
    const SurfelCloud& c = *in.cloud;
    const Attribute* id_in = c.attributes.find(kPatchIdAttribute);
    const Attribute* role_in = c.attributes.find(kSurfelRoleAttribute);
    for (size_t i = 0; i < c.size(); ++i) {
      merged.positions.push_back(c.positions[i]);
      merged.normals.push_back(c.normals[i].normalized());
      if (all_radii || !c.hasAxes())
        merged.radii.push_back(c.radii[i]);
      else
        merged.radii.push_back(std::max(c.axes1[i].norm(), c.axes2[i].norm()));
      if (all_axes) {
        merged.axes1.push_back(c.axes1[i]);
        merged.axes2.push_back(c.axes2[i]);
      }
      if (any_color) merged.colors.push_back(c.hasColors() ? c.colors[i] : default_color);
      *id_out++ = in.patch_id >= 0 ? in.patch_id : static_cast<int32_t>(id_in->get(i));
      *role_out++ = role_in ? static_cast<int32_t>(role_in->get(i)) : 0;
    }
  }
  return merged;
}

std::vector<int> patchIds(const SurfelCloud& cloud) {
  const Attribute* ids = cloud.attributes.find(kPatchIdAttribute);
  if (!ids) return {};
  std::set<int> distinct;
  for (size_t i = 0; i < ids->size(); ++i) distinct.insert(static_cast<int>(ids->get(i)));
  return {distinct.begin(), distinct.end()};
}

}  // namespace rc
