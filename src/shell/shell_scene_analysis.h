// The static and modal analyses of a shell scene (keys analysis, held, loads): its boxes and points resolved
// to the simulation's nodes, and the solves on the simulation's energy.
#pragma once

#include <string>
#include <vector>

#include "relaxed_connectivity/shell/shell_modal.h"
#include "relaxed_connectivity/shell/shell_simulation.h"
#include "relaxed_connectivity/shell/shell_static.h"

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

/// analysis static: the equilibrium of the simulation's shell (its energy, with anisotropy and membrane
/// balance applied) under the scene's loads and gravity; the simulation's nodes are moved there.
ShellStaticResult solveShellSceneStatic(ShellSimulation& sim);
/// analysis modal: the scene's `modes` lowest modes about the rest shape.
ShellModalResult solveShellSceneModal(const ShellSimulation& sim);

}  // namespace rc
