// A shell scene's boxes and points (keys held, loads, probes) resolved to the nodes the simulation chose.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "relaxed_connectivity/shell/shell_loads.h"
#include "relaxed_connectivity/shell/shell_scene.h"

namespace rc {

/// The nodes whose rest positions lie in [lo, hi] (closed, within 1e-9 of the shell's diagonal). Throws
/// ShellSceneError "<what> [lo] .. [hi] holds no node ..." when there is none.
std::vector<uint32_t> shellNodesInBox(const ShellNodes& nodes, const Vec3& lo, const Vec3& hi,
                                      const std::string& what);

/// The scene's held regions on `nodes`: the nodes whose rest positions lie in each box (closed, within 1e-9
/// of the shell's diagonal). Throws ShellSceneError naming the region for a box without nodes.
std::vector<ShellHeld> resolveShellHeld(const ShellScene& scene, const ShellNodes& nodes);
/// The scene's loads on `nodes` (a point load acts on the nearest node). Throws ShellSceneError for a box
/// without nodes.
std::vector<ShellLoad> resolveShellLoads(const ShellScene& scene, const ShellNodes& nodes);

}  // namespace rc
