#include "relaxed_connectivity/shell/shell_scene_analysis.h"

namespace rc {

ShellStaticResult solveShellSceneStatic(ShellSimulation& sim) {
  const ShellScene& scene = sim.scene();
  const ShellNodes& nodes = sim.solver().nodes();
  ShellStaticResult result =
      solveShellStatic(sim.solver().energy(), resolveShellHeld(scene, nodes), resolveShellLoads(scene, nodes),
                       scene.solver.gravity, scene.static_options);
  sim.mutableSolver().setPositions(result.positions);
  sim.animateSurface();
  return result;
}

ShellModalResult solveShellSceneModal(const ShellSimulation& sim) {
  const ShellScene& scene = sim.scene();
  const ShellNodes& nodes = sim.solver().nodes();
  return solveShellModal(sim.solver().energy(), nodes.rest_positions, resolveShellHeld(scene, nodes),
                         scene.modes);
}

}  // namespace rc
