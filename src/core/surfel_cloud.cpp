#include "relaxed_connectivity/core/surfel_cloud.h"

#include <stdexcept>

namespace rc {

namespace {
template <typename T>
void resizeIfPresent(std::vector<T>& v, size_t n) {
  if (!v.empty()) v.resize(n);
}
template <typename T>
void selectIfPresent(std::vector<T>& v, const std::vector<size_t>& idx) {
  if (v.empty()) return;
  std::vector<T> out;
  out.reserve(idx.size());
  for (size_t i : idx) out.push_back(v[i]);
  v.swap(out);
}
template <typename T>
void appendChannel(std::vector<T>& dst, const std::vector<T>& src, bool dst_was_empty_cloud) {
  if (dst_was_empty_cloud) {
    dst = src;
  } else if (!dst.empty() && !src.empty()) {
    dst.insert(dst.end(), src.begin(), src.end());
  } else {
    dst.clear();
  }
}
template <typename T>
void checkSize(const std::vector<T>& v, size_t n, const char* name) {
  if (!v.empty() && v.size() != n)
    throw std::invalid_argument(std::string("surfel cloud: channel '") + name + "' has " +
                                std::to_string(v.size()) + " elements, expected " + std::to_string(n));
}
}  // namespace

void SurfelCloud::resize(size_t n) {
  positions.resize(n);
  resizeIfPresent(normals, n);
  resizeIfPresent(radii, n);
  resizeIfPresent(axes1, n);
  resizeIfPresent(axes2, n);
  resizeIfPresent(colors, n);
  resizeIfPresent(confidence, n);
  resizeIfPresent(curvature, n);
  attributes.resize(n);
}

void SurfelCloud::clear() {
  positions.clear();
  normals.clear();
  radii.clear();
  axes1.clear();
  axes2.clear();
  colors.clear();
  confidence.clear();
  curvature.clear();
  attributes.resize(0);
  width = height = 0;
}

void SurfelCloud::select(const std::vector<size_t>& idx) {
  selectIfPresent(positions, idx);
  selectIfPresent(normals, idx);
  selectIfPresent(radii, idx);
  selectIfPresent(axes1, idx);
  selectIfPresent(axes2, idx);
  selectIfPresent(colors, idx);
  selectIfPresent(confidence, idx);
  selectIfPresent(curvature, idx);
  attributes.select(idx);
  width = height = 0;
}

void SurfelCloud::append(const SurfelCloud& other) {
  const bool first = empty();
  if (first && attributes.empty())
    attributes = other.attributes;
  else
    for (size_t i = 0; i < other.size(); ++i) attributes.appendFrom(other.attributes, i);
  appendChannel(normals, other.normals, first);
  appendChannel(radii, other.radii, first);
  appendChannel(axes1, other.axes1, first);
  appendChannel(axes2, other.axes2, first);
  appendChannel(colors, other.colors, first);
  appendChannel(confidence, other.confidence, first);
  appendChannel(curvature, other.curvature, first);
  positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  if (first && frame_id.empty()) frame_id = other.frame_id;
}

void SurfelCloud::transform(const Eigen::Isometry3d& transform) {
  const Eigen::Matrix3d rotation = transform.linear();
  for (Vec3& p : positions) p = transform * p;
  for (Vec3& v : normals) v = rotation * v;
  for (Vec3& v : axes1) v = rotation * v;
  for (Vec3& v : axes2) v = rotation * v;
}

size_t SurfelCloud::removeNonFinite() {
  std::vector<size_t> keep;
  keep.reserve(size());
  for (size_t i = 0; i < size(); ++i) {
    bool ok = positions[i].allFinite();
    if (hasNormals()) ok = ok && normals[i].allFinite();
    if (hasRadii()) ok = ok && std::isfinite(radii[i]);
    if (ok) keep.push_back(i);
  }
  const size_t removed = size() - keep.size();
  if (removed > 0) {
    select(keep);
    width = height = 0;
  }
  return removed;
}

void SurfelCloud::validate() const {
  const size_t n = size();
  checkSize(normals, n, "normals");
  checkSize(radii, n, "radii");
  checkSize(axes1, n, "axes1");
  checkSize(axes2, n, "axes2");
  checkSize(colors, n, "colors");
  checkSize(confidence, n, "confidence");
  checkSize(curvature, n, "curvature");
  if (axes1.size() != axes2.size())
    throw std::invalid_argument("surfel cloud: axes1 and axes2 must both be present or both absent");
  for (const auto& a : attributes.columns())
    if (a.size() != n)
      throw std::invalid_argument("surfel cloud: attribute '" + a.name + "' has " + std::to_string(a.size()) +
                                  " elements, expected " + std::to_string(n));
}

bool SurfelCloud::bounds(Vec3* lo, Vec3* hi) const {
  if (empty()) return false;
  Vec3 a = positions[0], b = positions[0];
  for (const auto& p : positions) {
    a = a.cwiseMin(p);
    b = b.cwiseMax(p);
  }
  *lo = a;
  *hi = b;
  return true;
}

}  // namespace rc
