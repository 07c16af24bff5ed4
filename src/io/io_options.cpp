#include "relaxed_connectivity/io/io_options.h"

#include <cmath>
#include <limits>

namespace rc {

namespace {
bool isFinite(const Vec3& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

// Indices of the surfels to keep; empty optional result means "keep all".
bool validIndices(const SurfelCloud& cloud, std::vector<size_t>* keep) {
  keep->clear();
  keep->reserve(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i)
    if (isFinite(cloud.positions[i])) keep->push_back(i);
  return keep->size() != cloud.size();
}
}  // namespace

void applyReadOptions(const ReadOptions& options, SurfelCloud* cloud) {
  if (options.keep_invalid) return;
  std::vector<size_t> keep;
  if (validIndices(*cloud, &keep)) cloud->select(keep);  // select() makes the cloud unorganised
}

void applyReadOptions(const ReadOptions& options, TriangleMesh* mesh) {
  if (options.keep_invalid) return;
  std::vector<size_t> keep;
  if (!validIndices(mesh->vertices, &keep)) return;
  constexpr uint32_t kDropped = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> new_index(mesh->vertices.size(), kDropped);
  for (size_t k = 0; k < keep.size(); ++k) new_index[keep[k]] = static_cast<uint32_t>(k);
  mesh->vertices.select(keep);
  std::vector<Triangle> kept;
  kept.reserve(mesh->triangles.size());
  for (const Triangle& t : mesh->triangles) {
    if (t[0] >= new_index.size() || t[1] >= new_index.size() || t[2] >= new_index.size())
      throw std::invalid_argument("applyReadOptions: a triangle indexes a vertex the mesh does not have");
    const Triangle r{new_index[t[0]], new_index[t[1]], new_index[t[2]]};
    if (r[0] != kDropped && r[1] != kDropped && r[2] != kDropped) kept.push_back(r);
  }
  mesh->triangles.swap(kept);
}

}  // namespace rc
