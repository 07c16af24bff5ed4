// Held nodes and loads of a thin shell (scene keys held and loads; thesis 7 leaves them to the scene): which
// components of which nodes are fixed, at what displacement, and which forces act on which nodes. Used by the
// static and modal analyses and by the dynamics (held components, constant loads).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "relaxed_connectivity/shell/shell_energy.h"

namespace rc {

/// The listed components of `nodes` are held at their rest position plus `displacement` (a roller or a
/// symmetry plane holds one component).
struct ShellHeld {
  std::vector<uint32_t> nodes;
  std::array<bool, 3> components = {true, true, true};
  Vec3 displacement = Vec3::Zero();
};

/// Forces on `nodes`: a total `force` spread in proportion to the nodes' rest areas (a point load when there
/// is one node) plus a `traction` per unit rest area (a distributed load), both constant in direction.
struct ShellLoad {
  std::vector<uint32_t> nodes;
  Vec3 force = Vec3::Zero();
  Vec3 traction = Vec3::Zero();
};

/// Nodal forces of the loads plus gravity on the node masses (m_i g). Throws std::invalid_argument for a load
/// without nodes, a node index out of range or a non-finite force.
std::vector<Vec3> shellLoadForces(const ShellEnergy& energy, const std::vector<ShellLoad>& loads,
                                  const Vec3& gravity);

/// Per node a bit mask of the held components (bit d: component d), from the held regions. Throws
/// std::invalid_argument for a region without nodes or a node index out of range.
std::vector<uint8_t> shellHeldMask(size_t node_count, const std::vector<ShellHeld>& held);

}  // namespace rc
