// An FEM scene (thesis 9.4, parameters of appendix F.3): what config/fem/*.yaml describes. The placed rest
// mesh (built from a FemMeshSource), material, implicit warped dynamics with a ground plane, frames, plane
// and polygon cuts scheduled in time, and the outputs. fem_scene_reader reads it, FemSimulation
// (fem_simulation) steps it, runFemScene (fem_scene_run) runs its frames. The schema is documented at the top
// of config/fem/fig9_3_single_element.yaml.
#pragma once

#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "relaxed_connectivity/fem/fem_mesh_source.h"
#include "relaxed_connectivity/fem/fem_output.h"
#include "relaxed_connectivity/fem/fem_probes.h"
#include "relaxed_connectivity/fem/plane_cut.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace rc {

/// A bad scene file: the message reads "<file>:<line>:<column>: <problem>".
class FemSceneError : public std::runtime_error {
 public:
  explicit FemSceneError(const std::string& message) : std::runtime_error(message) {}
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

/// Files written while a scene runs: the initial state (frame 0) and every `every`-th frame.
struct FemSceneOutput {
  int every = 1;
  bool vtu = true, obj = false;
  VtuEncoding encoding = VtuEncoding::kAppendedRaw;
};

/// What a run computes (key analysis): the implicit warped dynamics over the frames, the linear static
/// equilibrium K U = F of the rest mesh with the held regions and loads (one solve; output frames 0 and 1),
/// or its natural modes. kModal: the lowest `modes` natural frequencies and mode shapes (fem_modal.h; output
/// frames 1..modes the shapes, scaled to a tenth of the mesh's diagonal).
enum class FemAnalysis { kDynamic, kStatic, kModal };

/// Key held: the nodes whose rest positions lie in the box [lo, hi] (closed, with a tolerance of 1e-9 of the
/// mesh's diagonal), or the listed nodes (key nodes), hold the listed components at `displacement` (a roller
/// or a symmetry plane holds one). Dynamic runs: the held components reach displacementAt(t) at the end of
/// each step (a constant `displacement` at the end of the first one); `path` (time, displacement) keyframes,
/// interpolated linearly and held constant before the first and after the last, prescribe a motion. Nodes
/// made by cuts inside the box are held too; a held node takes no ground contact.
struct FemHeldRegion {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  /// Key nodes (a node set): the rest positions of the listed nodes; only nodes at one of them are held
  /// (lo, hi: their bounding box). Empty: every node in the box.
  std::vector<Vec3> points;
  std::array<bool, 3> components = {true, true, true};
  Vec3 displacement = Vec3::Zero();
  std::vector<std::pair<double, Vec3>> path;  ///< keyframes, times increasing (empty: `displacement`)
  /// Hold the components where they are when the region is applied (fem_sim's ~hold; FemSimulation::setHeld),
  /// not at rest + displacement; displacement and path unused (zero / empty).
  bool in_place = false;
  std::vector<int> nodes;  ///< of the scene's rest mesh, filled by the reader
  Vec3 displacementAt(double time) const;
};

/// Key loads: a total force spread equally over the nodes in the box [lo, hi] (nodal forces; on a regular
/// grid face the consistent load differs at its rim, which a resolution study sees), or a traction (force per
/// rest area) on the boundary faces whose nodes all lie in the box, as consistent nodal forces
/// (femTractionForces).
struct FemLoad {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  std::vector<Vec3> points;  ///< key nodes: as FemHeldRegion::points
  Vec3 force = Vec3::Zero();
  bool is_traction = false;  ///< `traction` given: `force` is per unit area
  std::vector<int> nodes;    ///< filled by the reader (never empty)
};

/// Key static (analysis: static): linear (K U = F, one solve) or corotational: the equilibrium of the warped
/// internal forces f(x) = -sum_e R_e K_e u_e (9.1.4) with the loads, large rotations and small strains, by
/// iterations x += K_w^-1 (f(x) + F) (K_w = sum_e R_e K_e R_e^T) over `load_steps` equal load increments,
/// each until |residual| <= tolerance times the load (at most max_iterations).
struct FemStaticOptions {
  bool corotational = false;
  int load_steps = 10, max_iterations = 200;
  double tolerance = 1e-8;
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
  FemAnalysis analysis = FemAnalysis::kDynamic;
  std::vector<FemHeldRegion> held;  ///< every analysis (dynamic: FemSimulation holds them every step)
  FemStaticOptions static_options;  ///< analysis: static
  int modes = 6;                    ///< analysis: modal
  std::vector<FemLoad> loads;       ///< static; dynamic: constant nodal forces (FemSimulation::applyLoads)
  /// analysis: dynamic: <name>_probes.csv in the output folder (fem_probes.h), a row at the start and per
  /// frame.
  std::vector<FemProbe> probes;
  /// analysis: static: a body force per unit mass (e.g. gravity), f_i = m_i a on the lumped masses (9.21).
  Vec3 body_acceleration = Vec3::Zero();
  double frameTime() const { return steps_per_frame * dynamics.time_step; }
};

}  // namespace rc
