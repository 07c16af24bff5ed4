// Probes of a dynamic FEM run (issue 22): per frame the bodies' energies and momentum, and per probe region
// (the nodes whose rest positions lie in a box, over all bodies, so also after cuts) the mass-weighted mean
// displacement and the largest displacement, for scenes that check a run against a reference (the scene key
// `probes`; runFemScene writes one CSV row at the start and after every frame).
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace rc {

/// Key probes: a named box of rest positions (closed, with a tolerance).
struct FemProbe {
  std::string name;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
};

/// The tolerance of the scene's boxes: 1e-9 of the rest mesh's bounding-box diagonal.
double femBoxTolerance(const PolyhedralMesh& mesh);

/// The bodies together.
struct FemBodiesMeasures {
  double kinetic_energy = 0.0, elastic_energy = 0.0, gravity_potential_energy = 0.0;
  Vec3 momentum = Vec3::Zero();
};
FemBodiesMeasures measureFemBodies(const std::vector<const WarpedDynamics*>& bodies);

/// One probe region: its nodes (over all bodies), their lumped mass, the mass-weighted mean displacement
/// sum m_i (x_i - X_i) / sum m_i, the largest |x_i - X_i| and the reaction of its held components (the force
/// the holders exerted during the last step, WarpedDynamics::heldReactions). A region without nodes (cut
/// away) has zeros.
struct FemRegionMeasures {
  size_t nodes = 0;
  double mass = 0.0, max_displacement = 0.0;
  Vec3 mean_displacement = Vec3::Zero(), reaction = Vec3::Zero();
};
FemRegionMeasures measureFemRegion(const std::vector<const WarpedDynamics*>& bodies, const FemProbe& probe,
                                   double tolerance);

/// CSV: the header, then one row per call (time, the bodies' measures, then per probe its measures).
void writeFemProbeHeader(std::ostream& out, const std::vector<FemProbe>& probes);
void writeFemProbeRow(std::ostream& out, double time, const FemBodiesMeasures& bodies,
                      const std::vector<FemRegionMeasures>& regions);

}  // namespace rc
