// Crack planes of a fracturing thin shell (thesis 7.3.2): discs in the rest configuration that cut material
// connections, the visibility rule (nodes separated by a crack disc are never neighbours) and the
// recomputation of node neighbourhoods under that rule.
#pragma once

#include <cstdint>
#include <vector>

#include "relaxed_connectivity/shell/shell_nodes.h"

namespace rc {

/// A crack disc in rest (material) coordinates: centred on the rest position of the node where the fiber
/// broke, normal along that fiber's rest tangent, radius the mean rest distance to the node's neighbours.
struct ShellCrack {
  Vec3 center = Vec3::Zero();
  Vec3 normal = Vec3::UnitX();  ///< unit
  double radius = 0.0;
  uint32_t node = 0;    ///< node the crack started at
  uint32_t fiber = 0;   ///< index of the broken fiber at the time of the crack
  bool stretch = true;  ///< broke by tensile stretch (7.24 first line), else by bending
  double time = 0.0;    ///< simulation time at which the crack was made
};

/// Side of point p with respect to the crack plane: +1 where (p - c) . n >= 0, else -1 (a node on the plane,
/// such as the crack's own node, belongs to the + side).
int crackSide(const ShellCrack& crack, const Vec3& p);

/// True if the segment a-b joins the two sides of the crack plane at a point inside the disc.
bool crackSeparates(const ShellCrack& crack, const Vec3& a, const Vec3& b);

/// True if no crack separates a and b (7.3.2 visibility).
bool crackVisible(const std::vector<ShellCrack>& cracks, const Vec3& a, const Vec3& b);

/// Recomputes the neighbourhoods (and fans) of every node that has a neighbour it cannot see: its
/// `neighbor_count` nearest visible nodes among the 4 * neighbor_count nearest (fewer if not enough are
/// visible), fan-ordered as in selectShellNodes. Rest positions, normals and areas stay. Returns the
/// recomputed nodes (ascending). If the neighbourhoods already see past cracks[0 .. first_new_crack) (they
/// came from an earlier call), only the newer cracks are tested to find the nodes to recompute (same result,
/// less work); the recomputation itself respects all cracks.
std::vector<uint32_t> recomputeVisibleNeighborhoods(ShellNodes& nodes, const std::vector<ShellCrack>& cracks,
                                                    size_t neighbor_count, size_t first_new_crack = 0);

}  // namespace rc
