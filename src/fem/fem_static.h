// The static analysis of an FEM scene (key analysis: static): the linear equilibrium K U = F (9.16) of the
// placed rest mesh, or the corotational one (key static.corotational, FemStaticOptions), with the scene's
// held regions (any subset of components) and loads (nodal forces, tractions and a body force on the lumped
// masses), and what a check against a reference reads off it.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "relaxed_connectivity/fem/fem_scene.h"

namespace rc {

struct FemStaticResult {
  Eigen::VectorXd displacements;         ///< (u_x, u_y, u_z) per node
  double max_displacement = 0.0;         ///< max |u| over the nodes
  std::vector<Vec3> held_reactions;      ///< per held region: the sum of its nodes' reactions (K U - F)
  int iterations = 1;                    ///< corotational: iterations over all load steps
  double residual = 0.0;                 ///< corotational: final |f(x) + F| over the free dofs / |F|
  std::vector<Vec3> load_displacements;  ///< per load region: the mean displacement of its nodes
  double seconds = 0.0;
};

/// Throws std::invalid_argument for a scene that is not static and std::runtime_error if the held regions
/// leave a rigid motion free or the corotational iterations do not converge (naming the load step).
FemStaticResult solveFemStatic(const FemScene& scene);

}  // namespace rc
