#include "relaxed_connectivity/paint/painted_surface_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/ply_io.h"
#include "relaxed_connectivity/paint/paint_attributes.h"

namespace rc {

namespace {

enum SurfelKind : uint8_t { kEnabledOriginal = 0, kDisabledOriginal = 1, kChild = 2 };

}  // namespace

void savePaintedSurface(const std::string& path, const PaintSurface& surface, bool atomic) {
  SurfelCloud cloud = surface.originals();
  for (const char* name : {kSurfelKind, kSurfelFather})
    if (cloud.attributes.has(name)) cloud.attributes.remove(name);
  if (!hasPaintAttributes(cloud)) addPaintAttributes(cloud, PaintState(), false);
  const size_t n = surface.originalCount();
  const size_t total = n + surface.childCount();
  // Children need radii; originals without radii get 0 (dropped again on load).
  if (!cloud.hasRadii() && surface.childCount() > 0) cloud.radii.assign(n, 0.0);
  cloud.resize(total);
  for (std::vector<Vec3>* axes : {&cloud.axes1, &cloud.axes2})
    if (!axes->empty()) std::fill(axes->begin() + long(n), axes->end(), Vec3::Zero());
  Attribute& kind = cloud.attributes.add(kSurfelKind, ScalarType::kUInt8, 1, total);
  Attribute& father = cloud.attributes.add(kSurfelFather, ScalarType::kUInt32, 1, total);
  PaintColumns columns(cloud);
  size_t k = n;
  for (size_t i = 0; i < n; ++i) {
    columns.write(i, surface.originalPaint(i));
    kind.set(i, surface.enabled(i) ? kEnabledOriginal : kDisabledOriginal);
    father.set(i, double(i));
    for (const ChildSurfel& c : surface.children(i)) {
      cloud.positions[k] = c.position;
      cloud.normals[k] = c.normal;
      cloud.radii[k] = c.radius;
      if (cloud.hasColors()) {
        const Vec3 rgb = visibleColour(c.paint).rgb;  // (5.8)
        cloud.colors[k] = {colourByte(rgb[0]), colourByte(rgb[1]), colourByte(rgb[2]), 255};
      }
      columns.write(k, c.paint);
      kind.set(k, kChild);
      father.set(k, double(i));
      ++k;
    }
  }
  WriteOptions options;
  options.double_precision = true;
  if (!atomic) return writePlyCloud(path, cloud, options);
  const std::string tmp = path + ".tmp";
  writePlyCloud(tmp, cloud, options);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw IoError(path, "cannot replace the file with " + tmp);
  }
}

std::unique_ptr<PaintSurface> loadPaintedSurface(const std::string& path, const LoadProgress& progress) {
  const auto report = [&](double fraction, const std::string& stage) {
    if (progress) progress(fraction, stage);
  };
  report(0.0, "reading");
  SurfelCloud cloud = readPlyCloud(path);
  report(0.4, "checking the father/child structure");
  const Attribute* kind = cloud.attributes.find(kSurfelKind);
  const Attribute* father = cloud.attributes.find(kSurfelFather);
  if (!kind || !father || !hasPaintAttributes(cloud))
    throw IoError(path,
                  "not a painted state: the columns surfel_kind, father and the paint columns "
                  "(paint_wet_rgb, ...) are required (save it with savePaintedSurface)");
  if (!cloud.hasNormals()) throw IoError(path, "the surfels have no normals");
  const auto where = [](size_t v) { return "element 'vertex' #" + std::to_string(v); };
  size_t n = 0;
  while (n < cloud.size() && kind->get(n) != kChild) ++n;
  if (n == 0) throw IoError(path, "no original surfels (surfel_kind 0 or 1) before the children");
  std::vector<std::vector<ChildSurfel>> children(n);
  std::vector<uint8_t> enabled(n);
  const PaintColumns columns(cloud);
  for (size_t v = 0; v < cloud.size(); ++v) {
    const double k = kind->get(v), f = father->get(v);
    if (v < n) {
      if (k != kEnabledOriginal && k != kDisabledOriginal)
        throw IoError(path, where(v), "surfel_kind " + std::to_string(k) + " is not 0, 1 or 2");
      if (f != double(v)) throw IoError(path, where(v), "an original's father must be its own index");
      enabled[v] = k == kEnabledOriginal;
      continue;
    }
    if (k != kChild)
      throw IoError(path, where(v),
                    "an original (surfel_kind " + std::to_string(int(k)) +
                        ") after the children: originals come first");
    if (!(f >= 0 && f < double(n)))
      throw IoError(path, where(v),
                    "father " + std::to_string(f) + " is not an original (0.." + std::to_string(n - 1) + ")");
    if (!cloud.hasRadii()) throw IoError(path, where(v), "a child without a radius");
    children[size_t(f)].push_back({cloud.positions[v], cloud.normals[v], cloud.radii[v], columns.read(v)});
  }
  std::vector<size_t> originals(n);
  for (size_t i = 0; i < n; ++i) originals[i] = i;
  cloud.select(originals);
  cloud.attributes.remove(kSurfelKind);
  cloud.attributes.remove(kSurfelFather);
  if (cloud.hasRadii() &&
      std::all_of(cloud.radii.begin(), cloud.radii.end(), [](double r) { return r == 0; }))
    cloud.radii.clear();  // the originals had no radii (savePaintedSurface wrote 0)
  report(0.5, "building the collision structures");
  std::unique_ptr<PaintSurface> surface;
  try {
    surface = std::make_unique<PaintSurface>(std::move(cloud));
  } catch (const std::invalid_argument& e) {
    throw IoError(path, e.what());
  }
  report(0.9, "restoring the children");
  for (size_t i = 0; i < n; ++i)
    surface->restoreOriginal(i, enabled[i], std::as_const(*surface).originalPaint(i), std::move(children[i]));
  surface->takeChangedOriginals();  // a loaded state has no changes yet
  report(1.0, "done");
  return surface;
}

}  // namespace rc
