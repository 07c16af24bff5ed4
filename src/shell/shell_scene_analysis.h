// The static and modal analyses of a shell scene (keys analysis, held, loads): its boxes and points resolved
// to the simulation's nodes, and the solves on the simulation's energy.
#pragma once

#include <string>
#include <vector>

#include "relaxed_connectivity/shell/shell_modal.h"
#include "relaxed_connectivity/shell/shell_scene_regions.h"
#include "relaxed_connectivity/shell/shell_simulation.h"
#include "relaxed_connectivity/shell/shell_static.h"

namespace rc {

/// analysis static: the equilibrium of the simulation's shell (its energy, with anisotropy and membrane
/// balance applied) under the scene's loads and gravity; the simulation's nodes are moved there.
ShellStaticResult solveShellSceneStatic(ShellSimulation& sim);
/// analysis modal: the scene's `modes` lowest modes about the rest shape.
ShellModalResult solveShellSceneModal(const ShellSimulation& sim);

}  // namespace rc
