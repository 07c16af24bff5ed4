// FEM scene files (YAML, config/fem/*.yaml; thesis 9.4, parameters of appendix F.3) and their simulation: a
// polyhedral mesh (one convex element, grids, a cube split by random planes, TetGen meshes), material,
// implicit warped dynamics with a ground plane, frames, and plane cuts scheduled in time. A cut through a
// body separates it into two bodies; each body is one WarpedDynamics. The schema is documented at the top of
// config/fem/fig9_3_single_element.yaml.
#pragma once

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "fem/fem_output.h"
#include "fem/plane_cut.h"
#include "fem/polyhedral_mesh.h"
#include "fem/warped_dynamics.h"

namespace rc {

/// A bad scene file: the message reads "<file>:<line>:<column>: <problem>".
class FemSceneError : public std::runtime_error {
 public:
  explicit FemSceneError(const std::string& message) : std::runtime_error(message) {}
};

/// Where the initial mesh comes from (key mesh.type).
enum class FemMeshType {
  kConvexHull,     ///< one element: the convex hull of `points`
  kHexGrid,        ///< PolyhedralMesh::hexahedralGrid(lo, hi, cells)
  kTetGrid,        ///< PolyhedralMesh::tetrahedralGrid(lo, hi, cells, split)
  kRandomPlanes,   ///< PolyhedralMesh::randomPlaneCut(lo, hi, cells, planes, seed, min_relative_gap)
  kRandomSplits,   ///< randomElementSplits(lo, hi, cells, planes, seed, min_relative_gap) (Fig. 9.4)
  kTetgenSurface,  ///< TetGen mesh of a closed triangle surface (OBJ / OFF / PLY), scaled and centred
  kTetgenFiles,    ///< TetGen's .node / .ele pair
};

struct FemMeshSource {
  FemMeshType type = FemMeshType::kHexGrid;
  std::vector<Vec3> points;
  Vec3 lo = Vec3::Zero(), hi = Vec3::Ones();
  int cells[3] = {1, 1, 1};
  PolyhedralMesh::TetrahedronSplit split = PolyhedralMesh::TetrahedronSplit::kSix;
  int planes = 0;
  unsigned seed = 1;
  double min_relative_gap = 0.02;
  std::string surface, node_file, ele_file;  ///< resolved against the scene file's folder
  double size = 0.0;  ///< tetgen_surface: bounding-box diagonal after scaling (0: as is)
  double max_volume = 0.0, max_radius_edge_ratio = 2.0;
  double min_dihedral_degrees = 0.0;  ///< tetgen_surface: TetgenOptions::min_dihedral_degrees
  bool close_holes = false;           ///< tetgen_surface: closeSurfaceHoles before meshing (open scans)
  int decimate_vertices = 0;          ///< tetgen_surface: decimateSurface to this many vertices (0: no)
};

/// A plane cut applied at `time` (before the first step starting at or after it). The plane is given in the
/// rest frame of the placed mesh (the world frame at t = 0). region: optional convex polygon in the plane
/// (PlaneCutOptions::region). A cut that splits every crossed element of a body (no element left whole
/// across the plane) separates the body into two when `separate` is set; otherwise the elements are only
/// split (the cut stays closed).
///
/// Progressive polygon cut (thesis 9.3.2) when `polygons` is non-empty: a cut surface as a sequence of convex
/// polygons (rest frame; a blade sweep, non-planar when consecutive polygons are not coplanar) applied with
/// ProgressiveCutMesh, polygon k (of n) at time + duration * k / n. Partial cuts leave internal cracks (the
/// body stays one mesh with crack faces); a body falling apart becomes several bodies. point, normal, region
/// and separate are unused then.
///
/// Key sliver_relative_thickness (default 0.01, 0: off): thin elements the cut creates (relative thickness
/// below it, CutSliverOptions) are merged into their neighbours after the cut; off keeps them (the behaviour
/// before automatic removal).
struct FemSceneCut {
  double time = 0.0;
  Vec3 point = Vec3::Zero(), normal = Vec3::UnitX();
  std::vector<Vec3> region;
  bool separate = true;
  double snap_relative_distance = 1e-6;
  CutSliverOptions slivers;
  std::vector<std::vector<Vec3>> polygons;
  double duration = 0.0;
  bool isPolygonCut() const { return !polygons.empty(); }
  double polygonTime(int k) const {
    return time + (polygons.empty() ? 0.0 : duration * k / static_cast<double>(polygons.size()));
  }
};

/// The polygons of a blade sweep: the blade segment (blade[0], blade[1]) translated by path[k] and path[k +
/// 1] spans quad k (path.size() - 1 quads, planar by construction). Throws std::invalid_argument for fewer
/// than 2 path points, a zero-length blade or a path step parallel to the blade.
std::vector<std::vector<Vec3>> bladeSweepPolygons(const Vec3& blade_start, const Vec3& blade_end,
                                                  const std::vector<Vec3>& path);

/// Files written while a scene runs: the initial state (frame 0) and every `every`-th frame.
struct FemSceneOutput {
  int every = 1;
  bool vtu = true, obj = false;
  VtuEncoding encoding = VtuEncoding::kAppendedRaw;
};

/// A loaded scene: the placed rest mesh, material, dynamics options (incl. ground), initial velocities.
struct FemScene {
  std::string name;  ///< `name:` or the file name without extension
  std::string path;
  FemMeshSource source;
  std::shared_ptr<const PolyhedralMesh> mesh;  ///< rest mesh after placement
  std::vector<Vec3> initial_velocities;        ///< per node (placement.velocity + angular_velocity x r)
  double youngs_modulus = 50.0, poisson_ratio = 0.3, density = 1.0;
  /// material.vertex_sample_blend / face_sample_blend: integration sample placement (9.1.3; thesis 0.8 / 0.9,
  /// the default). Samples nearer the centroid lock less on coarse meshes (bench_fem_accuracy: cantilever
  /// error -9.1% at 0.8 / 0.9, -1.0% at 0.5 / 0.5 on hex n = 4) at the same cost.
  ElementQuadratureOptions quadrature;
  WarpedDynamicsOptions dynamics;
  int frame_count = 1, steps_per_frame = 1;
  std::vector<FemSceneCut> cuts;  ///< sorted by time
  FemSceneOutput output;
  double frameTime() const { return steps_per_frame * dynamics.time_step; }
};

/// Reads a scene file. Throws FemSceneError naming the file, line and problem (syntax, unknown key, wrong
/// type, bad value, a mesh that cannot be built).
FemScene loadFemScene(const std::string& path);
/// Same for YAML text; `source_name` stands for the file name in error messages, relative mesh files are
/// resolved against `base_dir` (empty: the working directory).
FemScene parseFemScene(const std::string& yaml_text, const std::string& source_name,
                       const std::string& base_dir = "");

/// The mesh of a source (unplaced). Throws std::invalid_argument / std::runtime_error / IoError.
PolyhedralMesh buildFemMesh(const FemMeshSource& source);

/// Fig. 9.4's partition: the nx x ny x nz hexahedral grid of [lo, hi], then `num_splits` times a random
/// element (chosen with probability proportional to its volume) split by a random plane near its centroid
/// (a region-restricted cutMeshByPlane: neighbours only get T-junction nodes). Planes passing closer than
/// min_relative_gap * |hi - lo| to a node of the chosen element are redrawn. Result: nx ny nz + num_splits
/// elements. Throws std::runtime_error if no admissible plane is found in 1000 draws.
PolyhedralMesh randomElementSplits(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz, int num_splits,
                                   unsigned seed, double min_relative_gap = 0.02);

/// Values at the nodes of cut.mesh from values at the nodes of `mesh` (the cut's input) through
/// PlaneCutResult::node_stencils (old nodes keep theirs, a new node on edge (a, b) gets the linear
/// interpolation, nodes of merged slivers theirs); without stencils, along the parent element's edges.
std::vector<Vec3> interpolateCutValues(const PolyhedralMesh& mesh, const PlaneCutResult& cut,
                                       const std::vector<Vec3>& values);

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

/// Progress after one frame.
struct FemFrameReport {
  int frame = 0;  ///< 1-based
  int frame_count = 0;
  double time = 0.0;
  long steps = 0;
  int nodes = 0, elements = 0, bodies = 0, cuts = 0;
  long frame_iterations = 0;  ///< solver iterations of this frame
  double frame_seconds = 0.0;
};

struct FemRunOptions {
  std::string out_dir;  ///< files go here (created); empty: none are written
  std::function<void(const FemFrameReport&)> on_frame;
};

struct FemRunStats {
  std::string scene;
  int nodes_start = 0, elements_start = 0;
  int nodes = 0, elements = 0, bodies = 0, cuts = 0;
  int crack_faces = 0;                         ///< at the end, all bodies
  long slivers_removed = 0, slivers_kept = 0;  ///< thin cut elements merged / kept, all cuts
  int frames = 0, frame_count = 0;
  long steps = 0;
  double simulated_time = 0.0;
  FemPhaseTimes times;
  double wall_seconds = 0.0;  ///< integration + dynamics + topology (no output)
  long solver_iterations = 0;
  int max_step_iterations = 0;
  long unconverged_solves = 0;
  double min_ground_distance = 0.0;  ///< at the end
  double kinetic_energy = 0.0;       ///< at the end, all bodies
  std::string error;                 ///< empty: completed; else why the run stopped
  std::vector<std::string> files;
};

/// Runs scene.frame_count frames of scene.steps_per_frame steps, writing the outputs the scene asks for.
/// A failing step or cut stops the run (reported in FemRunStats::error); I/O errors throw.
FemRunStats runFemScene(const FemScene& scene, const FemRunOptions& options = {});

/// The statistics as one line of JSON (no newline); non-finite numbers become null.
std::string femRunStatsJson(const FemRunStats& stats);

}  // namespace rc
