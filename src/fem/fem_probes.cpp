#include "relaxed_connectivity/fem/fem_probes.h"

#include <algorithm>
#include <cmath>
#include <iomanip>

namespace rc {

double femBoxTolerance(const PolyhedralMesh& mesh) {
  if (mesh.numNodes() == 0) return 0.0;
  Vec3 lo = mesh.node(0), hi = mesh.node(0);
  for (int i = 0; i < mesh.numNodes(); ++i) lo = lo.cwiseMin(mesh.node(i)), hi = hi.cwiseMax(mesh.node(i));
  return 1e-9 * (hi - lo).norm();
}

FemBodiesMeasures measureFemBodies(const std::vector<const WarpedDynamics*>& bodies) {
  FemBodiesMeasures m;
  for (const WarpedDynamics* b : bodies) {
    m.kinetic_energy += b->kineticEnergy();
    m.elastic_energy += b->elasticEnergy();
    m.gravity_potential_energy += b->gravityPotentialEnergy();
    m.momentum += b->linearMomentum();
  }
  return m;
}

FemRegionMeasures measureFemRegion(const std::vector<const WarpedDynamics*>& bodies, const FemProbe& probe,
                                   double tolerance) {
  FemRegionMeasures m;
  Vec3 weighted = Vec3::Zero();
  for (const WarpedDynamics* b : bodies) {
    const Eigen::VectorXd &rest = b->restPositions(), &x = b->positions(), &mass = b->lumpedMasses();
    for (Eigen::Index i = 0; i < rest.size() / 3; ++i) {
      const Vec3 r = rest.segment<3>(3 * i);
      if (((r - probe.lo).array() < -tolerance).any() || ((probe.hi - r).array() < -tolerance).any())
        continue;
      const Vec3 u = x.segment<3>(3 * i) - r;
      ++m.nodes;
      m.mass += mass[3 * i];
      weighted += mass[3 * i] * u;
      m.max_displacement = std::max(m.max_displacement, u.norm());
      if (b->numHeldDofs() > 0) m.reaction += b->heldReactions().segment<3>(3 * i);
    }
  }
  if (m.mass > 0) m.mean_displacement = weighted / m.mass;
  return m;
}

void writeFemProbeHeader(std::ostream& out, const std::vector<FemProbe>& probes) {
  out << "time,kinetic_energy,elastic_energy,gravity_potential_energy,momentum_x,momentum_y,momentum_z";
  for (const FemProbe& p : probes)
    for (const char* column :
         {"nodes", "mass", "ux", "uy", "uz", "max_u", "reaction_x", "reaction_y", "reaction_z"})
      out << ',' << p.name << '_' << column;
  out << '\n';
}

void writeFemProbeRow(std::ostream& out, double time, const FemBodiesMeasures& bodies,
                      const std::vector<FemRegionMeasures>& regions) {
  out << std::setprecision(12) << time << ',' << bodies.kinetic_energy << ',' << bodies.elastic_energy << ','
      << bodies.gravity_potential_energy << ',' << bodies.momentum.x() << ',' << bodies.momentum.y() << ','
      << bodies.momentum.z();
  for (const FemRegionMeasures& r : regions)
    out << ',' << r.nodes << ',' << r.mass << ',' << r.mean_displacement.x() << ',' << r.mean_displacement.y()
        << ',' << r.mean_displacement.z() << ',' << r.max_displacement << ',' << r.reaction.x() << ','
        << r.reaction.y() << ',' << r.reaction.z();
  out << '\n';
}

}  // namespace rc
