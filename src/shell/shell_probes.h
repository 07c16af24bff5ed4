// Probes of a dynamic shell run (issue 22, scene key probes): per frame the shell's energies and momentum,
// and per probe region (the nodes whose rest positions lie in a box) the mass-weighted mean displacement, the
// largest displacement and the force its held nodes exert on the shell. runShellScene writes one CSV row at
// the start and after every frame to <scene>_probes.csv.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "relaxed_connectivity/shell/shell_solver.h"

namespace rc {

/// Key probes: a named box of rest positions.
struct ShellProbe {
  std::string name;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
};

/// The whole shell.
struct ShellMeasures {
  double mass = 0.0;  ///< all nodes
  double kinetic_energy = 0.0, membrane_energy = 0.0, bending_energy = 0.0, gravity_potential_energy = 0.0;
  Vec3 momentum = Vec3::Zero();
};
ShellMeasures measureShell(const ShellSolver& solver);

/// One region: its nodes, their mass, sum m_i (x_i - X_i) / sum m_i, the largest |x_i - X_i|, and over its
/// pinned nodes (pins, pulled edges) the force they exert on the shell, sum (dE/dx_i - m_i g): the reaction a
/// clamp or a puller measures (external forces such as a balloon's pressure are left out).
struct ShellRegionMeasures {
  size_t nodes = 0;
  double mass = 0.0, max_displacement = 0.0;
  Vec3 mean_displacement = Vec3::Zero(), reaction = Vec3::Zero();
};
ShellRegionMeasures measureShellRegion(const ShellSolver& solver, const std::vector<uint32_t>& nodes);

/// CSV: the header, then one row per call (time, the shell's measures, then per probe its measures).
void writeShellProbeHeader(std::ostream& out, const std::vector<ShellProbe>& probes);
void writeShellProbeRow(std::ostream& out, double time, const ShellMeasures& shell,
                        const std::vector<ShellRegionMeasures>& regions);

}  // namespace rc
