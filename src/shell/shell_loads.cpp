#include "relaxed_connectivity/shell/shell_loads.h"

#include <stdexcept>
#include <string>

namespace rc {

namespace {

void checkNodes(const std::vector<uint32_t>& nodes, size_t count, const std::string& what) {
  if (nodes.empty()) throw std::invalid_argument(what + " has no nodes");
  for (uint32_t i : nodes)
    if (i >= count)
      throw std::invalid_argument(what + ": node " + std::to_string(i) + " out of range (" +
                                  std::to_string(count) + " nodes)");
}

}  // namespace

std::vector<Vec3> shellLoadForces(const ShellEnergy& energy, const std::vector<ShellLoad>& loads,
                                  const Vec3& gravity) {
  const std::vector<double>& areas = energy.nodes().rest_areas;
  const std::vector<double>& masses = energy.masses();
  const size_t n = areas.size();
  std::vector<Vec3> f(n);
  for (size_t i = 0; i < n; ++i) f[i] = masses[i] * gravity;
  for (size_t k = 0; k < loads.size(); ++k) {
    const ShellLoad& load = loads[k];
    const std::string what = "load " + std::to_string(k + 1);
    checkNodes(load.nodes, n, what);
    if (!load.force.allFinite() || !load.traction.allFinite())
      throw std::invalid_argument(what + ": force and traction must be finite");
    double area = 0.0;
    for (uint32_t i : load.nodes) area += areas[i];
    for (uint32_t i : load.nodes)
      f[i] += (area > 0.0 ? areas[i] / area : 1.0 / double(load.nodes.size())) * load.force +
              areas[i] * load.traction;
  }
  return f;
}

std::vector<uint8_t> shellHeldMask(size_t node_count, const std::vector<ShellHeld>& held) {
  std::vector<uint8_t> mask(node_count, 0);
  for (size_t k = 0; k < held.size(); ++k) {
    checkNodes(held[k].nodes, node_count, "held region " + std::to_string(k + 1));
    const uint8_t bits =
        uint8_t(held[k].components[0] | held[k].components[1] << 1 | held[k].components[2] << 2);
    for (uint32_t i : held[k].nodes) mask[i] |= bits;
  }
  return mask;
}

}  // namespace rc
