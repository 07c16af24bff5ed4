// The simulation objects of a loaded SPH scene: the solver with its force terms (elastic solids, collisions)
// and the thermal model. Used by runSphScene (the rc_sph tool), SphSimulation and the sph_sim node.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_scene.h"
#include "relaxed_connectivity/sph/sph_thermal.h"

namespace rc {

/// A solver for the scene (its config, particles and planes) with an SphElasticSolid force term per solid
/// (given the scene's planes and gravity, SphElasticSolid::setEnvironment) and, with `enable: [collisions]`,
/// an SphObjectPenalty term after them (told K_e of the solids with implicit goal springs,
/// SphObjectPenalty::setObjectStiffness; with implicit contact springs and `couple_global_implicit`, the
/// solids with global implicit goal springs solve their contacts in one system with them,
/// SphObjectPenalty::coupleGlobalImplicit).
SphFluidSolver makeSphSolver(const SphScene& scene);

/// Per particle of the solver: the docked lattice points (SphElasticSolid::dockedCounts) of the solids
/// with fracture (docking), 0 for other particles and before the first force evaluation. Returns false
/// (and zeros) when no solid of the solver has fracture.
bool sphDockedPoints(const SphFluidSolver& solver, std::vector<uint32_t>& docked);

/// The thermal model of a scene with `enable: [temperature]` (nullptr otherwise): its config, initial
/// temperatures, heated planes and held particles; the freezing solid is the solver's SphElasticSolid of the
/// freezing phase (solver made by makeSphSolver).
std::shared_ptr<SphThermalModel> makeSphThermal(const SphScene& scene, SphFluidSolver& solver);

}  // namespace rc
