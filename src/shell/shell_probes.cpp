#include "relaxed_connectivity/shell/shell_probes.h"

#include <algorithm>
#include <iomanip>

namespace rc {

ShellMeasures measureShell(const ShellSolver& solver) {
  ShellMeasures m;
  const std::vector<double>& mass = solver.energy().masses();
  const std::vector<Vec3>& x = solver.positions();
  const std::vector<Vec3>& v = solver.velocities();
  for (size_t i = 0; i < x.size(); ++i) {
    m.mass += mass[i];
    m.kinetic_energy += 0.5 * mass[i] * v[i].squaredNorm();
    m.gravity_potential_energy -= mass[i] * solver.gravity().dot(x[i]);
    m.momentum += mass[i] * v[i];
  }
  m.membrane_energy = solver.elasticEnergy().membrane;  // of the last force evaluation, at x
  m.bending_energy = solver.elasticEnergy().bending;
  return m;
}

ShellRegionMeasures measureShellRegion(const ShellSolver& solver, const std::vector<uint32_t>& nodes) {
  ShellRegionMeasures m;
  const std::vector<double>& mass = solver.energy().masses();
  const std::vector<Vec3>& rest = solver.nodes().rest_positions;
  const std::vector<Vec3>& gradient = solver.elasticGradient();
  Vec3 weighted = Vec3::Zero();
  for (uint32_t i : nodes) {
    const Vec3 u = solver.positions()[i] - rest[i];
    ++m.nodes;
    m.mass += mass[i];
    weighted += mass[i] * u;
    m.max_displacement = std::max(m.max_displacement, u.norm());
    if (solver.pinned(i)) m.reaction += gradient[i] - mass[i] * solver.gravity();
  }
  if (m.mass > 0) m.mean_displacement = weighted / m.mass;
  return m;
}

void writeShellProbeHeader(std::ostream& out, const std::vector<ShellProbe>& probes) {
  out << "time,mass,kinetic_energy,membrane_energy,bending_energy,gravity_potential_energy,momentum_x,"
         "momentum_y,"
         "momentum_z";
  for (const ShellProbe& p : probes)
    for (const char* column :
         {"nodes", "mass", "ux", "uy", "uz", "max_u", "reaction_x", "reaction_y", "reaction_z"})
      out << ',' << p.name << '_' << column;
  out << '\n';
}

void writeShellProbeRow(std::ostream& out, double time, const ShellMeasures& s,
                        const std::vector<ShellRegionMeasures>& regions) {
  out << std::setprecision(12) << time << ',' << s.mass << ',' << s.kinetic_energy << ',' << s.membrane_energy
      << ',' << s.bending_energy << ',' << s.gravity_potential_energy << ',' << s.momentum.x() << ','
      << s.momentum.y() << ',' << s.momentum.z();
  for (const ShellRegionMeasures& r : regions)
    out << ',' << r.nodes << ',' << r.mass << ',' << r.mean_displacement.x() << ',' << r.mean_displacement.y()
        << ',' << r.mean_displacement.z() << ',' << r.max_displacement << ',' << r.reaction.x() << ','
        << r.reaction.y() << ',' << r.reaction.z();
  out << '\n';
}

}  // namespace rc
