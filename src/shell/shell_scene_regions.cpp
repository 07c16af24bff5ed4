#include "relaxed_connectivity/shell/shell_scene_regions.h"

#include <cstdio>
#include <limits>
#include <string>

namespace rc {

namespace {

std::string boxText(const Vec3& lo, const Vec3& hi) {
  char text[160];
  std::snprintf(text, sizeof text, "[%g, %g, %g] .. [%g, %g, %g]", lo.x(), lo.y(), lo.z(), hi.x(), hi.y(),
                hi.z());
  return text;
}

}  // namespace

std::vector<uint32_t> shellNodesInBox(const ShellNodes& nodes, const Vec3& lo, const Vec3& hi,
                                      const std::string& what) {
  Vec3 min = nodes.rest_positions[0], max = min;
  for (const Vec3& p : nodes.rest_positions) min = min.cwiseMin(p), max = max.cwiseMax(p);
  const double tolerance = 1e-9 * (max - min).norm();
  std::vector<uint32_t> inside;
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Vec3& p = nodes.rest_positions[i];
    if (((p - lo).array() >= -tolerance).all() && ((hi - p).array() >= -tolerance).all())
      inside.push_back(uint32_t(i));
  }
  if (inside.empty())
    throw ShellSceneError(what + " " + boxText(lo, hi) + " holds no node (" + std::to_string(nodes.size()) +
                          " nodes, spacing " + std::to_string(nodes.spacing) + "): widen the box");
  return inside;
}

std::vector<ShellHeld> resolveShellHeld(const ShellScene& scene, const ShellNodes& nodes) {
  std::vector<ShellHeld> held;
  for (size_t k = 0; k < scene.held.size(); ++k) {
    const ShellSceneHeld& h = scene.held[k];
    ShellHeld region;
    region.nodes = shellNodesInBox(nodes, h.lo, h.hi, scene.path + ": held[" + std::to_string(k) + "]");
    region.components = h.components;
    region.displacement = h.displacement;
    held.push_back(std::move(region));
  }
  return held;
}

std::vector<ShellLoad> resolveShellLoads(const ShellScene& scene, const ShellNodes& nodes) {
  std::vector<ShellLoad> loads;
  for (size_t k = 0; k < scene.loads.size(); ++k) {
    const ShellSceneLoad& l = scene.loads[k];
    ShellLoad load;
    if (l.at_point) {
      uint32_t nearest = 0;
      double best = std::numeric_limits<double>::infinity();
      for (size_t i = 0; i < nodes.size(); ++i) {
        const double d = (nodes.rest_positions[i] - l.point).squaredNorm();
        if (d < best) best = d, nearest = uint32_t(i);
      }
      load.nodes = {nearest};
    } else {
      load.nodes = shellNodesInBox(nodes, l.lo, l.hi, scene.path + ": loads[" + std::to_string(k) + "]");
    }
    load.force = l.force;
    load.traction = l.traction;
    loads.push_back(std::move(load));
  }
  return loads;
}

}  // namespace rc
