#include "relaxed_connectivity/shell/shell_applied_force.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rc {

ShellAppliedForce shellAppliedForce(const Vec3& force, double duration, int node, const Vec3& point,
                                    double radius, const std::vector<Vec3>& positions) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("apply_force: " + what); };
  ShellAppliedForce applied;
  applied.force = force;
  if (!applied.force.allFinite()) fail("force is not finite");
  if (!(applied.force.norm() > 0)) fail("force is zero");
  if (!(duration > 0) || !std::isfinite(duration))
    fail("duration must be finite and > 0 s (got " + std::to_string(duration) + ")");
  applied.remaining = duration;
  if (node >= 0) {
    if (size_t(node) >= positions.size())
      fail("node " + std::to_string(node) + " is out of range (" + std::to_string(positions.size()) +
           " nodes)");
    applied.nodes.push_back(size_t(node));
    return applied;
  }
  if (node != -1)
    fail("node must be a node index >= 0 or -1 (nodes near point), got " + std::to_string(node));
  if (!point.allFinite()) fail("point is not finite");
  if (!(radius > 0) || !std::isfinite(radius))
    fail("radius must be finite and > 0 (got " + std::to_string(radius) + ")");
  for (size_t i = 0; i < positions.size(); ++i)
    if ((positions[i] - point).squaredNorm() <= radius * radius) applied.nodes.push_back(i);
  if (applied.nodes.empty())
    fail("no node within " + std::to_string(radius) + " m of the point (" + std::to_string(point.x()) + ", " +
         std::to_string(point.y()) + ", " + std::to_string(point.z()) + ")");
  return applied;
}

}  // namespace rc
