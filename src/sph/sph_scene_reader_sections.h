// The SPH scene reader's shared parts (internal to sph_scene_reader*.cpp): the error context, value types and
// the SceneReader class whose section readers live in sph_scene_reader.cpp (solver, particles, boundaries,
// frames), sph_scene_reader_solids.cpp, sph_scene_reader_thermal.cpp and sph_scene_reader_output.cpp.
#pragma once

#include <yaml-cpp/yaml.h>

#include <map>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/io/yaml_reader.h"
#include "relaxed_connectivity/sph/sph_scene.h"

namespace rc::sph_scene_reading {

/// More particles than this in one scene is taken as a typo in a spacing.
inline constexpr double kMaxParticles = 2e8;

[[noreturn]] inline void raiseSphSceneError(const std::string& message) {
  throw SphSceneError(message);
}

/// Error context ("<file>:<line>:<column>: <problem>") and the scene's value types.
struct Source : YamlReader {
  explicit Source(std::string name) : YamlReader(std::move(name), &raiseSphSceneError) {}

  /// [x, y, z]; in 2D also [x, y] (z = 0). With `planar` (velocities, directions) z must be 0 in 2D.
  Vec3 vec(const YAML::Node& node, const std::string& what, int dimension, bool planar) const {
    const bool ok = node.IsSequence() && (node.size() == 3 || (dimension == 2 && node.size() == 2));
    if (!ok) fail(node, what + (dimension == 2 ? ": expected [x, y] or [x, y, z]" : ": expected [x, y, z]"));
    Vec3 v(number(node[0], what), number(node[1], what), node.size() == 3 ? number(node[2], what) : 0.0);
    if (dimension == 2 && planar && v.z() != 0) fail(node[2], what + ": z must be 0 in 2D");
    return v;
  }
};

/// A box [lo, hi] with lo < hi in the simulated dimensions.
struct Box {
  Vec3 lo, hi;
};

inline Box readBox(const Source& src, const YAML::Node& node, const std::string& where, int dimension) {
  Box b;
  b.lo = src.vec(src.require(node, "lo", where), where + ".lo", dimension, false);
  b.hi = src.vec(src.require(node, "hi", where), where + ".hi", dimension, false);
  for (int k = 0; k < dimension; ++k)
    if (!(b.lo[k] < b.hi[k])) src.fail(node["hi"], where + ": hi must exceed lo in every coordinate");
  return b;
}

/// A cylinder of `radius` around the segment from -> to (from != to).
struct Cylinder {
  Vec3 from = Vec3::Zero(), to = Vec3::Zero();
  double radius = 0.0;
  /// Distance of x to the segment within radius (relative tolerance 1e-9).
  bool contains(const Vec3& x) const {
    const Vec3 axis = to - from;
    const double t = std::clamp((x - from).dot(axis) / axis.squaredNorm(), 0.0, 1.0);
    return (x - (from + t * axis)).squaredNorm() <= radius * radius * (1.0 + 1e-9);
  }
};

/// Reads the scene after the YAML has been parsed.

/// Reads the scene after the YAML has been parsed (one SceneReader per file).
class SceneReader {
 public:
  SceneReader(const Source& src, SphScene* scene) : src_(src), scene_(*scene) {}

  void read(const YAML::Node& root);

 private:
  // sph_scene_reader.cpp: solver, particles, boundaries, frames
  void readEnable(const YAML::Node& node);
  bool enabled(const std::string& physics) const;
  /// A plane entry's unit `normal` and its `offset` (or a `point` on it).
  void planeGeometry(const YAML::Node& p, const std::string& where, Vec3* normal, double* offset) const;
  void readSolver(const YAML::Node& node);
  /// Adds "<file>:<line>:<column>: warning: <problem>" to the scene's warnings.
  void warn(const YAML::Node& node, const std::string& problem);
  double blockSpacing(const YAML::Node& node, const std::string& where) const;
  /// Mass of a lattice particle of spacing dx (rest density with full support).
  double massFor(double dx);
  /// Guards against a typo in a spacing before anything is allocated.
  void reserveLattice(const YAML::Node& node, const std::string& where, const Vec3& lo, const Vec3& hi,
                      double dx, int layers);
  void addBox(const YAML::Node& node, const std::string& where, const Box& box, double dx,
              SphParticleKind kind, const Vec3& velocity);
  void readFluid(const YAML::Node& node, const std::string& where);
  /// A block's `velocity`: [vx, vy(, vz)] (uniform), or a field {uniform: [..], gradient: [[..], ..] (v = A
  /// (x - about)), rotation: w (2D, about z) | [wx, wy, wz] (v = w x (x - about)), about: [..] (default
  /// `centre`), file: samples (each particle adds the velocity of the nearest sample)} set on the particles
  /// from `first` on.
  void readVelocityField(const YAML::Node& node, const std::string& where, const Vec3& centre, size_t first);
  /// Velocity samples of a text file (relative to the scene file): per line x y (z) vx vy (vz), '#' starts a
  /// comment, commas count as spaces; errors name the file's line.
  void readVelocitySamples(const YAML::Node& node, const std::string& what, std::vector<Vec3>* points,
                           std::vector<Vec3>* velocities) const;
  void readMoving(const YAML::Node& node, const std::string& where);
  void readBoundary(const YAML::Node& node);
  void readFrames(const YAML::Node& node);

  // sph_scene_reader_solids.cpp: elastic solids, skins, collisions
  /// The material keys of a solid (spacing, model and its parameters) into *e, validated.
  void readElasticMaterial(const YAML::Node& node, const std::string& where, SphElasticConfig* elastic);
  /// Keys `fracture` (docking, 8.2.5) and `plasticity` of a solid into *e (fixed or adaptive steps).
  void readFracturePlasticity(const YAML::Node& node, const std::string& where, SphElasticConfig* elastic);
  /// A triangle mesh file (OBJ, PLY or OFF) named by `node`; a relative path is relative to the scene file's
  /// folder.
  TriangleMesh readMeshFile(const YAML::Node& node, const std::string& what) const;
  /// Solid keys `mesh`, `scale` (a number or [sx, sy, sz]) and `translation` of shape mesh: the mesh in
  /// the body frame, x -> scale x - c (c: the centre of the scaled bounds), and the centre of the placed
  /// solid, translation + R c (the world mesh is translation + R (scale x)).
  TriangleMesh readSolidMesh(const YAML::Node& node, const std::string& where,
                             const Eigen::Matrix3d& rotation, Vec3* center, Vec3* half) const;
  /// An elastic object (thesis 8.2): a box, a sphere (2D: disc) or a closed triangle mesh (3D; scans with
  /// small holes work: the generalised winding number decides inside) sampled on the closest-packing lattice
  /// (8.20) around its centre, rotated by `rotation`, with its own phase id.
  void readSolid(const YAML::Node& node, const std::string& where);
  /// Solid key `skin` (8.2.7): {mesh: file | resolution: n, transforms, orphans, every, obj, ply}; a solid
  /// of shape mesh may give `mesh: same` (its own mesh, placed). The rest mesh is read or made here; it is
  /// bound once all particles exist (finishSkins).
  void readSkin(const YAML::Node& node, const std::string& where, const std::string& shape,
                const Vec3& center, const Vec3& half, const TriangleMesh& body_mesh);
  /// `enable: [skin]`: binds every skin to the rest particles of its solid (8.38); the output follows the
  /// particle output's every unless the skin gives its own.
  void finishSkins();
  /// collisions: {stiffness, contact_distance, damping} (8.37) between the solids.
  void readCollisions(const YAML::Node& node);

  // sph_scene_reader_thermal.cpp: temperature, phase transition, sources
  /// Key `temperature` of a fluid box or solid: the start temperature of its particles [first, end).
  void readBlockTemperature(const YAML::Node& node, const std::string& where, size_t first);
  /// temperature: {conductivity, heat_capacity, initial, ambient, ambient_rate, stability_factor,
  /// heated_planes: [...], held: [...]}.
  void readThermal(const YAML::Node& node);
  /// phase_transition: {seed, melting: {rate, temperature, phase}, freezing: {rate, temperature, phase,
  /// min_solid_neighbors, max_relative_speed, max_lattice_force, material: {solid material keys}}}.
  void readPhaseTransition(const YAML::Node& node);
  /// {from, to, radius} of a cylinder (3D only).
  Cylinder readCylinder(const YAML::Node& node, const std::string& where) const;
  /// sources: [{center, direction, radius, speed, spacing, start, stop, temperature, max_particles}].
  void readSources(const YAML::Node& node);

  // sph_scene_reader_output.cpp: particle and surface outputs
  void readOutput(const YAML::Node& node);
  /// output.surface: {every, formats: [obj, ply], cell_size, iso_value, particles: fluid | all}.
  void readSurface(const YAML::Node& node);
  /// `enable: [surface]`: the surface follows the solver's h, rest density and threads; every frame of the
  /// particle output unless output.surface.every is given.
  void finishSurface();

  /// Reads an optional number key of `node` into `value` unless it is absent; `check` validates it.
  template <typename Check>
  void optionalNumber(const YAML::Node& node, const char* key, const std::string& where, double* value,
                      Check check) const {
    if (node[key]) *value = (src_.*check)(node[key], where + "." + key);
  }

  /// A solid's skin until all particles exist; `node`: where binding errors point.
  struct PendingSkin {
    SphSceneSkin skin;
    YAML::Node node;
    std::string where;
    SphSkinOrphanPolicy orphans = SphSkinOrphanPolicy::kThrow;
    bool every_given = false;
  };

  const Source& src_;
  SphScene& scene_;
  std::vector<PendingSkin> pending_skins_;
  std::map<std::string, YAML::Node> enable_nodes_;
  std::vector<YAML::Node> held_nodes_;
  std::set<uint8_t> phases_;
  bool surface_every_given_ = false;
  int dimension_ = 3;
  double spacing_ = 0.0;
  double planned_ = 0.0;
  std::map<double, double> masses_;
  std::map<std::string, YAML::Node> field_nodes_;
};

}  // namespace rc::sph_scene_reading
