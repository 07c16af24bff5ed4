// Forces a user applies to a thin shell (the shell_sim node's ~apply_force): the nodes it acts on, chosen by
// index or by a ball around a point, and the simulated time it lasts.
#pragma once

#include <cstddef>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

/// A force acting on some nodes for a remaining simulated time.
struct ShellAppliedForce {
  std::vector<size_t> nodes;
  Vec3 force = Vec3::Zero();  ///< on each node
  double remaining = 0.0;     ///< simulated seconds left
};

/// Checks a force against the current node positions and selects its nodes: node >= 0 that node; node = -1
/// every node within `radius` of `point`. Throws std::invalid_argument ("apply_force: ...") naming the
/// problem: a non-finite or zero force, a duration that is not finite and > 0, a node index out of range,
/// node = -1 with a non-finite point or a radius that is not finite and > 0, or no node within the radius.
ShellAppliedForce shellAppliedForce(const Vec3& force, double duration, int node, const Vec3& point,
                                    double radius, const std::vector<Vec3>& positions);

}  // namespace rc
