// The running simulation of an FEM scene (thesis 9): bodies (one WarpedDynamics each), time and the
// scheduled plane and polygon cuts; a cut through a body separates it into several bodies. The object that
// rc_fem, the fem_sim node and the benchmarks step.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "relaxed_connectivity/fem/cholmod_solver.h"
#include "relaxed_connectivity/fem/fem_output.h"
#include "relaxed_connectivity/fem/fem_scene.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace rc {

/// Wall time per phase, seconds.
struct FemPhaseTimes {
  double integration = 0.0;  ///< element integration (changed elements only after a cut) and solver setup
  double dynamics = 0.0;     ///< WarpedDynamics::step: warping, assembly, solve, contact
  double rotations = 0.0;    ///< of dynamics: R_e, element forces, R_e K_e R_e^T (StepStatistics::warping_ms)
  double assembly = 0.0;     ///< of dynamics: K_w scatter, system matrix, right-hand side
  double solve = 0.0;        ///< of dynamics: linear solves
  double topology = 0.0;     ///< cutMeshByPlane, separateAlongPlane, state transfer
  double output = 0.0;
};

/// What one scheduled cut did.
struct FemCutReport {
  int bodies_cut = 0;        ///< bodies whose elements were split or separated
  int bodies_separated = 0;  ///< of these, the ones separated into two
  int split_elements = 0, new_nodes = 0, duplicated_nodes = 0;
  int crack_faces = 0;                        ///< polygon cuts: element faces that became crack faces
  int polygons = 0;                           ///< polygon cuts: polygons applied
  int slivers_removed = 0, slivers_kept = 0;  ///< thin cut elements merged / kept (CutSliverStats)
  /// Elements of the new bodies integrated anew (changed by the cut) / sharing the cut body's integration
  /// data (unchanged rest geometry, LinearElasticModel donor).
  int recomputed_elements = 0, reused_elements = 0;
};

/// The running simulation of a scene: bodies (one WarpedDynamics each), time, scheduled cuts.
class FemSimulation {
 public:
  /// One body: the scene mesh at rest with the scene's initial velocities.
  explicit FemSimulation(const FemScene& scene);

  const FemScene& scene() const { return scene_; }
  /// Replaces the loads (the scene's key loads of a dynamic run) and applies them to the current bodies.
  /// Returns per load the number of nodes its force is spread over now (0: none in its box).
  std::vector<size_t> setLoads(std::vector<FemLoad> loads);
  /// Replaces the held regions (the scene's key held) and holds them on the current bodies from the next step
  /// on; a later region's components replace an earlier one's on shared nodes; in-place regions hold their
  /// nodes where they are now (also after later calls and cuts: held nodes stay where they are held). Returns
  /// per region the number of nodes it holds now (0: none in its box). Throws std::invalid_argument for a
  /// non-finite box, displacement or path, path times that do not increase, or an in-place region with a
  /// displacement or path.
  std::vector<size_t> setHeld(std::vector<FemHeldRegion> regions);
  /// Per held region: the force its holder exerted on its held components during the last step, summed over
  /// the bodies (zero before the first step).
  std::vector<Vec3> heldReactions() const;
  int numBodies() const { return static_cast<int>(bodies_.size()); }
  const WarpedDynamics& body(int b) const { return *bodies_[b]; }
  std::vector<FemBodyState> bodyStates() const;
  int numNodes() const;
  int numElements() const;
  double time() const { return time_; }
  long steps() const { return steps_; }
  int cutsApplied() const { return next_cut_; }

  /// Applies the cuts that are due, then steps every body once. Throws std::runtime_error when a cut fails
  /// (naming it) or the state becomes non-finite (naming the step).
  void step();
  /// Cuts every body by the plane, or by all of cut.polygons at once for a polygon cut (also used by step()
  /// for the scheduled cuts, which applies a polygon cut's polygons at their times).
  FemCutReport applyCut(const FemSceneCut& cut);
  /// Progressive polygon cuts (ProgressiveCutMesh, rest frame) on every body whose rest bounding box meets a
  /// polygon's; each cut body is replaced by one body per connected component (crack faces kept).
  FemCutReport applyPolygonCuts(const std::vector<std::vector<Vec3>>& polygons,
                                double snap_relative_distance = 1e-6,
                                const CutSliverOptions& slivers = CutSliverOptions());
  /// Polygons of polygon cuts applied so far (all cuts).
  long polygonsApplied() const { return polygons_applied_; }
  /// Elements integrated anew after cuts / reused from the cut body (FemCutReport), all cuts so far.
  long recomputedElements() const { return recomputed_elements_; }
  long reusedElements() const { return reused_elements_; }
  /// Thin cut elements merged / kept after cuts (FemCutReport), all cuts so far.
  long sliversRemoved() const { return slivers_removed_; }
  long sliversKept() const { return slivers_kept_; }

  /// Whether bodies made by cuts start from the cut body's state (on by default): R_e of the elements (the
  /// same element's where the cut left it whole, a neighbour's otherwise) as the registrations' warm start,
  /// dv as the CG warm start. Off: identity rotations, zero dv (the same physics up to the registration and
  /// CG tolerances). Every new body analyses and factorises its own system (a cut changes the pattern).
  void setCarryStateAcrossCuts(bool carry) { carry_state_ = carry; }
  bool carryStateAcrossCuts() const { return carry_state_; }

  /// CHOLMOD work of all bodies so far (also of bodies replaced by cuts): symbolic analyses, numeric
  /// factorisations and their wall time in seconds; bodies built (the first and those made by cuts).
  struct SolverCounts {
    long analyses = 0, factorizations = 0;
    double analysis_seconds = 0.0, factorization_seconds = 0.0;
    long bodies_built = 0;
  };
  SolverCounts solverCounts() const;

  const FemPhaseTimes& phaseTimes() const { return times_; }
  FemPhaseTimes& phaseTimes() { return times_; }
  long solverIterations() const { return solver_iterations_; }
  int maxStepIterations() const { return max_step_iterations_; }
  long unconvergedSolves() const { return unconverged_; }
  /// min over nodes of n . x - offset (ground plane) or of x.z (no ground).
  double minGroundDistance() const;

 private:
  /// The scene's loads (dynamic runs: constant nodal forces) on the current bodies: each load's total force
  /// spread equally over the nodes whose rest positions lie in its box, over all bodies (after cuts too).
  std::vector<size_t> applyLoads();
  /// The held regions on the current bodies (held_region_ and WarpedDynamics::setHeld); node counts per
  /// region.
  std::vector<size_t> applyHeld();
  /// Held targets for the step ending at `time` (rest + displacementAt(time) of each dof's region).
  void setHeldTargets(double time);
  /// State of a cut body handed to a body made from it: R_e per new element (warm start of the
  /// registrations), dv per new node (CG warm start).
  struct CarriedState {
    std::vector<Eigen::Matrix3d> rotations;
    std::vector<Vec3> previous_dv;
  };
  /// donor: the model of the body the mesh was cut from (its unchanged elements' data is reused), or null.
  std::unique_ptr<WarpedDynamics> makeBody(PolyhedralMesh mesh, const std::vector<Vec3>& displacements,
                                           const std::vector<Vec3>& velocities,
                                           const LinearElasticModel* donor = nullptr,
                                           FemCutReport* report = nullptr, CarriedState* carried = nullptr);
  /// Adds the counts of the solver of a body replaced by a cut to retired_counts_ (null: none).
  void retireSolver(const CholmodSolver* solver);

  FemScene scene_;
  std::vector<std::unique_ptr<WarpedDynamics>> bodies_;
  std::vector<std::vector<int>> held_region_;  // per body, per dof: the region holding it (-1: free)
  std::vector<Eigen::VectorXd> held_anchor_;   // per body: positions when held (in-place regions' targets)
  double time_ = 0.0;
  long steps_ = 0;
  int next_cut_ = 0, next_polygon_ = 0;  // next_polygon_: of cut next_cut_
  long polygons_applied_ = 0, recomputed_elements_ = 0, reused_elements_ = 0;
  long slivers_removed_ = 0, slivers_kept_ = 0;
  FemPhaseTimes times_;
  bool carry_state_ = true;
  SolverCounts retired_counts_;  // of the solvers of replaced bodies (and the builds of all)
  long solver_iterations_ = 0, unconverged_ = 0;
  int max_step_iterations_ = 0;
};

}  // namespace rc
