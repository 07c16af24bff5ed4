#include "sph/sph_scene_file.h"
#include "io/cloud_io.h"
#include "io/yaml_reader.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include <Eigen/Geometry>

#include "mesh/fast_winding_number.h"
#include "sph/sph_kernels.h"
#include "sph/sph_lattice.h"
#include "sph/sph_scene.h"

namespace rc {

namespace {

/// More particles than this in one scene is taken as a typo in a spacing.
constexpr double kMaxParticles = 2e8;

[[noreturn]] void raiseSphSceneError(const std::string& message) {
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

Box readBox(const Source& src, const YAML::Node& node, const std::string& where, int dimension) {
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
class SceneReader {
 public:
  SceneReader(const Source& src, SphScene* scene) : src_(src), scene_(*scene) {}

  void read(const YAML::Node& root) {
    src_.allowKeys(root,
                   {"name", "dimension", "spacing", "enable", "solver", "fluid", "solids", "boundary",
                    "moving", "frames", "output", "temperature", "phase_transition", "collisions", "sources"},
                   "scene");
    if (root["name"]) scene_.name = src_.string(root["name"], "name");
    dimension_ = int(src_.integer(src_.require(root, "dimension", "scene"), "dimension", 2, 3));
    scene_.config.dimension = dimension_;
    if (root["spacing"]) spacing_ = src_.positive(root["spacing"], "spacing");
    readEnable(root["enable"]);
    readSolver(src_.require(root, "solver", "scene"));
    const YAML::Node fluid = root["fluid"], solids = root["solids"];
    if (solids && !enabled("elasticity"))
      src_.fail(solids, "solids: needs 'elasticity' in the scene's 'enable' list");
    if (!fluid && !solids && !root["sources"])
      src_.fail(root, "scene: missing 'fluid' (or 'solids' with enable: [elasticity], or 'sources')");
    if (fluid) {
      if (!fluid.IsSequence() || fluid.size() == 0) src_.fail(fluid, "fluid: expected a list of boxes");
      for (size_t i = 0; i < fluid.size(); ++i) readFluid(fluid[i], "fluid[" + std::to_string(i) + "]");
    }
    if (solids) {
      if (!solids.IsSequence() || solids.size() == 0) src_.fail(solids, "solids: expected a list of solids");
      for (size_t i = 0; i < solids.size(); ++i) readSolid(solids[i], "solids[" + std::to_string(i) + "]");
    }
    if (root["boundary"]) readBoundary(root["boundary"]);
    if (root["moving"]) {
      const YAML::Node moving = root["moving"];
      if (!moving.IsSequence()) src_.fail(moving, "moving: expected a list of boxes");
      for (size_t i = 0; i < moving.size(); ++i) readMoving(moving[i], "moving[" + std::to_string(i) + "]");
    }
    readThermal(root["temperature"]);
    readPhaseTransition(root["phase_transition"]);
    readCollisions(root["collisions"]);
    if (root["sources"]) readSources(root["sources"]);
    readFrames(src_.require(root, "frames", "scene"));
    if (root["output"]) readOutput(root["output"]);
    if (enabled("surface")) finishSurface();
    if (enabled("skin")) finishSkins();
  }

 private:
  void readEnable(const YAML::Node& node) {
    if (!node) return;
    if (!node.IsSequence()) src_.fail(node, "enable: expected a list of physics names");
    const std::vector<std::string>& known = sphOptionalPhysics();
    std::string names;
    for (const std::string& k : known) names += (names.empty() ? "" : ", ") + k;
    for (size_t i = 0; i < node.size(); ++i) {
      const std::string what = src_.string(node[i], "enable[" + std::to_string(i) + "]");
      if (std::find(known.begin(), known.end(), what) == known.end())
        src_.fail(node[i], "enable: unknown physics '" + what + "' (known: " + names + ")");
      if (enabled(what)) src_.fail(node[i], "enable: '" + what + "' is listed twice");
      scene_.enabled_physics.push_back(what);
      enable_nodes_[what] = node[i];
    }
    for (const char* physics : {"collisions", "skin"})
      if (enabled(physics) && !enabled("elasticity"))
        src_.fail(enable_nodes_.at(physics),
                  std::string("enable: '") + physics + "' needs 'elasticity' in the 'enable' list");
    if (enabled("phase_transition"))
      for (const char* needed : {"temperature", "elasticity"})
        if (!enabled(needed))
          src_.fail(enable_nodes_.at("phase_transition"),
                    std::string("enable: 'phase_transition' needs '") + needed + "' in the 'enable' list");
  }

  /// Key `temperature` of a fluid box or solid: the start temperature of its particles [first, end).
  void readBlockTemperature(const YAML::Node& node, const std::string& where, size_t first) {
    const YAML::Node t = node["temperature"];
    if (!t) return;
    if (!enabled("temperature"))
      src_.fail(t, where + ".temperature: needs 'temperature' in the scene's 'enable' list");
    SphSceneTemperature range;
    range.first = first;
    range.count = scene_.particles.size() - first;
    range.temperature = src_.number(t, where + ".temperature");
    scene_.thermal.initial.push_back(range);
  }

  /// temperature: {conductivity, heat_capacity, initial, ambient, ambient_rate, stability_factor,
  /// heated_planes: [...], held: [...]}.
  void readThermal(const YAML::Node& node) {
    if (node && !enabled("temperature"))
      src_.fail(node, "temperature: needs 'temperature' in the scene's 'enable' list");
    if (!enabled("temperature")) return;
    if (!node)
      src_.fail(enable_nodes_.at("temperature"), "enable: 'temperature' needs a 'temperature' block");
    src_.allowKeys(node,
                   {"conductivity", "heat_capacity", "initial", "ambient", "ambient_rate", "stability_factor",
                    "heated_planes", "held"},
                   "temperature");
    SphSceneThermal& t = scene_.thermal;
    t.enabled = true;
    SphThermalConfig& c = t.config;
    c.rest_density = scene_.config.rest_density;
    c.num_threads = scene_.config.num_threads;
    optionalNumber(node, "conductivity", "temperature", &c.conductivity, &Source::nonNegative);
    optionalNumber(node, "heat_capacity", "temperature", &c.heat_capacity, &Source::positive);
    optionalNumber(node, "initial", "temperature", &c.initial_temperature, &Source::number);
    optionalNumber(node, "ambient", "temperature", &c.ambient_temperature, &Source::number);
    optionalNumber(node, "ambient_rate", "temperature", &c.ambient_rate, &Source::nonNegative);
    if (node["stability_factor"]) {
      c.stability_factor = src_.unitInterval(node["stability_factor"], "temperature.stability_factor");
      if (!(c.stability_factor > 0))
        src_.fail(node["stability_factor"], "temperature.stability_factor must be in (0, 1]");
    }
    if (const YAML::Node planes = node["heated_planes"]) {
      if (!planes.IsSequence()) src_.fail(planes, "temperature.heated_planes: expected a list");
      for (size_t i = 0; i < planes.size(); ++i) {
        const std::string where = "temperature.heated_planes[" + std::to_string(i) + "]";
        const YAML::Node p = planes[i];
        src_.allowKeys(
            p, {"normal", "offset", "point", "distance", "temperature", "transfer_rate", "heat_flux"}, where);
        SphHeatedPlane plane;
        planeGeometry(p, where, &plane.normal, &plane.offset);
        optionalNumber(p, "distance", where, &plane.distance, &Source::positive);
        optionalNumber(p, "temperature", where, &plane.temperature, &Source::number);
        optionalNumber(p, "transfer_rate", where, &plane.transfer_rate, &Source::nonNegative);
        optionalNumber(p, "heat_flux", where, &plane.heat_flux, &Source::number);
        t.planes.push_back(plane);
      }
    }
    if (const YAML::Node held = node["held"]) {
      if (!held.IsSequence()) src_.fail(held, "temperature.held: expected a list of boxes or cylinders");
      for (size_t i = 0; i < held.size(); ++i) {
        const std::string where = "temperature.held[" + std::to_string(i) + "]";
        const YAML::Node h = held[i];
        const bool cylinder = h.IsMap() && h["from"];
        if (cylinder)
          src_.allowKeys(h, {"from", "to", "radius", "temperature", "phase"}, where);
        else
          src_.allowKeys(h, {"lo", "hi", "temperature", "phase"}, where);
        Box box;
        Cylinder cyl;
        if (cylinder)
          cyl = readCylinder(h, where);
        else
          box = readBox(src_, h, where, dimension_);
        SphSceneHeld entry;
        entry.temperature = src_.number(src_.require(h, "temperature", where), where + ".temperature");
        if (h["phase"]) {
          if (!enabled("phase_transition"))
            src_.fail(h["phase"], where + ".phase: needs 'phase_transition' in the scene's 'enable' list");
          entry.phase = uint8_t(src_.integer(h["phase"], where + ".phase", 1, 255));
        }
        const SphParticles& particles = scene_.particles;
        for (size_t j = 0; j < particles.size(); ++j) {
          const Vec3& x = particles.positions[j];
          bool inside = true;
          if (cylinder) {
            inside = cyl.contains(x);
          } else {
            for (int k = 0; k < dimension_; ++k) inside = inside && x[k] >= box.lo[k] && x[k] <= box.hi[k];
          }
          if (inside) entry.indices.push_back(j);
        }
        if (entry.indices.empty())
          src_.fail(h, where + ": no particles inside the " + (cylinder ? "cylinder" : "box"));
        held_nodes_.push_back(h);
        t.held.push_back(std::move(entry));
      }
    }
    try {
      c.validate();
    } catch (const std::invalid_argument& e) {
      src_.fail(node, std::string("temperature: ") + e.what());
    }
  }

  /// phase_transition: {seed, melting: {rate, temperature, phase}, freezing: {rate, temperature, phase,
  /// min_solid_neighbors, max_relative_speed, max_lattice_force, material: {solid material keys}}}.
  void readPhaseTransition(const YAML::Node& node) {
    if (node && !enabled("phase_transition"))
      src_.fail(node, "phase_transition: needs 'phase_transition' in the scene's 'enable' list");
    if (!enabled("phase_transition")) return;
    if (!node)
      src_.fail(enable_nodes_.at("phase_transition"),
                "enable: 'phase_transition' needs a 'phase_transition' block");
    src_.allowKeys(node, {"seed", "melting", "freezing"}, "phase_transition");
    SphThermalConfig& c = scene_.thermal.config;
    if (node["seed"])
      c.seed =
          uint64_t(src_.integer(node["seed"], "phase_transition.seed", 0, std::numeric_limits<long>::max()));
    if (!node["melting"] && !node["freezing"])
      src_.fail(node, "phase_transition: give 'melting' and / or 'freezing'");
    if (const YAML::Node m = node["melting"]) {
      const std::string where = "phase_transition.melting";
      src_.allowKeys(m, {"rate", "temperature", "phase"}, where);
      c.melting = true;
      optionalNumber(m, "rate", where, &c.melting_rate, &Source::nonNegative);
      c.melting_temperature = src_.number(src_.require(m, "temperature", where), where + ".temperature");
      if (m["phase"]) {
        c.melting_phase = uint8_t(src_.integer(m["phase"], where + ".phase", 1, 255));
        if (!phases_.count(c.melting_phase))
          src_.fail(m["phase"], where + ".phase: no solid has phase " + std::to_string(c.melting_phase));
      }
    }
    if (const YAML::Node f = node["freezing"]) {
      const std::string where = "phase_transition.freezing";
      src_.allowKeys(f,
                     {"rate", "temperature", "phase", "min_solid_neighbors", "max_relative_speed",
                      "max_lattice_force", "material"},
                     where);
      c.freezing = true;
      optionalNumber(f, "rate", where, &c.freezing_rate, &Source::nonNegative);
      c.freezing_temperature = src_.number(src_.require(f, "temperature", where), where + ".temperature");
      optionalNumber(f, "min_solid_neighbors", where, &c.min_solid_neighbors, &Source::number);
      optionalNumber(f, "max_relative_speed", where, &c.max_relative_speed, &Source::positive);
      optionalNumber(f, "max_lattice_force", where, &c.max_lattice_force, &Source::positive);
      const YAML::Node phase = src_.require(f, "phase", where);
      c.freezing_phase = uint8_t(src_.integer(phase, where + ".phase", 1, 255));
      // The solid fluid freezes into: a scene solid of that phase, or a new (initially empty) one of
      // `material`.
      const YAML::Node material = f["material"];
      for (size_t s = 0; s < scene_.solids.size(); ++s)
        if (scene_.solids[s].phase == c.freezing_phase) scene_.thermal.freezing_solid = int(s);
      if (scene_.thermal.freezing_solid >= 0 && material)
        src_.fail(material, where + ".material: phase " + std::to_string(c.freezing_phase) +
                                " is a solid of the scene already (its material applies)");
      if (scene_.thermal.freezing_solid < 0) {
        if (!material)
          src_.fail(f, where + ": phase " + std::to_string(c.freezing_phase) +
                           " is no solid of the scene; give its 'material' (solid material keys)");
        src_.allowKeys(material,
                       {"spacing", "model", "youngs_modulus", "poisson_ratio", "hourglass_control",
                        "goal_stiffness", "deformation_allowance", "implicit_goal", "implicit_step_factor",
                        "implicit_tolerance", "anchor_boundary"},
                       where + ".material");
        SphSceneSolid solid;
        readElasticMaterial(material, where + ".material", &solid.elastic);
        // Boundary particles of the phase (a held rod seed) join the shape matching: ice holds on to them.
        if (material["anchor_boundary"])
          solid.elastic.anchor_boundary_particles =
              src_.boolean(material["anchor_boundary"], where + ".material.anchor_boundary");
        solid.phase = c.freezing_phase;
        solid.first = scene_.particles.size();
        solid.count = 0;
        phases_.insert(solid.phase);
        scene_.thermal.freezing_solid = int(scene_.solids.size());
        scene_.solids.push_back(solid);
      }
    }
    for (size_t i = 0; i < scene_.thermal.held.size(); ++i) {
      const uint8_t p = scene_.thermal.held[i].phase;
      if (p != 0 && p != c.freezing_phase)
        src_.fail(held_nodes_[i]["phase"], "temperature.held[" + std::to_string(i) + "].phase: " +
                                               std::to_string(p) + " is not the freezing phase");
    }
    for (const SphSceneHeld& h : scene_.thermal.held)
      if (h.phase != 0)
        for (size_t j : h.indices) scene_.particles.phases[j] = h.phase;
    try {
      c.validate();
    } catch (const std::invalid_argument& e) {
      src_.fail(node, std::string("phase_transition: ") + e.what());
    }
  }

  /// collisions: {stiffness, contact_distance, damping} (8.37) between the solids.
  void readCollisions(const YAML::Node& node) {
    if (node && !enabled("collisions"))
      src_.fail(node, "collisions: needs 'collisions' in the scene's 'enable' list");
    if (!enabled("collisions")) return;
    const YAML::Node at = node ? node : enable_nodes_.at("collisions");
    if (scene_.solids.size() < 2)
      src_.fail(at,
                "collisions: need two or more solids, the scene has " + std::to_string(scene_.solids.size()));
    SphSceneCollisions& c = scene_.collisions;
    c.enabled = true;
    SphObjectPenaltyConfig& p = c.config;
    p.contact_distance = scene_.solids[0].elastic.lattice_spacing;
    for (const SphSceneSolid& solid : scene_.solids)
      p.contact_distance = std::min(p.contact_distance, solid.elastic.lattice_spacing);
    const bool given = node && node["contact_distance"];
    if (node) {
      src_.allowKeys(node, {"stiffness", "contact_distance", "damping", "implicit", "couple_global_implicit"},
                     "collisions");
      if (node["implicit"]) p.implicit = src_.boolean(node["implicit"], "collisions.implicit");
      if (node["couple_global_implicit"])
        p.couple_global_implicit =
            src_.boolean(node["couple_global_implicit"], "collisions.couple_global_implicit");
      optionalNumber(node, "stiffness", "collisions", &p.stiffness, &Source::positive);
      optionalNumber(node, "contact_distance", "collisions", &p.contact_distance, &Source::positive);
      optionalNumber(node, "damping", "collisions", &p.damping, &Source::nonNegative);
    }
    const double h = scene_.config.smoothing_length;
    if (!(p.contact_distance <= h))
      src_.fail(given ? node["contact_distance"] : at,
                "collisions.contact_distance: " + std::to_string(p.contact_distance) +
                    " exceeds the smoothing length " + std::to_string(h));
    try {
      p.validate();
      SphObjectPenalty(p, SphKernels(dimension_, h));
    } catch (const std::invalid_argument& e) {
      src_.fail(at, std::string("collisions: ") + e.what());
    }
  }

  /// {from, to, radius} of a cylinder (3D only).
  Cylinder readCylinder(const YAML::Node& node, const std::string& where) const {
    if (dimension_ != 3) src_.fail(node, where + ": a cylinder needs a 3D scene (in 2D use a box)");
    Cylinder c;
    c.from = src_.vec(src_.require(node, "from", where), where + ".from", dimension_, false);
    c.to = src_.vec(src_.require(node, "to", where), where + ".to", dimension_, false);
    if (!((c.to - c.from).norm() > 0)) src_.fail(node["to"], where + ": 'from' and 'to' must differ");
    c.radius = src_.positive(src_.require(node, "radius", where), where + ".radius");
    return c;
  }

  /// sources: [{center, direction, radius, speed, spacing, start, stop, temperature, max_particles}].
  void readSources(const YAML::Node& node) {
    if (!node.IsSequence() || node.size() == 0) src_.fail(node, "sources: expected a list of sources");
    for (size_t i = 0; i < node.size(); ++i) {
      const std::string where = "sources[" + std::to_string(i) + "]";
      const YAML::Node s = node[i];
      if (!s.IsMap()) src_.fail(s, where + ": expected a map (center, direction, radius, speed, ...)");
      src_.allowKeys(s,
                     {"center", "direction", "radius", "speed", "spacing", "start", "stop", "temperature",
                      "max_particles"},
                     where);
      SphFluidSourceConfig c;
      c.dimension = dimension_;
      c.center = src_.vec(src_.require(s, "center", where), where + ".center", dimension_, false);
      const YAML::Node dir = src_.require(s, "direction", where);
      c.direction = src_.vec(dir, where + ".direction", dimension_, true);
      if (!(c.direction.norm() > 0)) src_.fail(dir, where + ".direction must be non-zero");
      c.direction.normalize();
      c.spacing = blockSpacing(s, where);
      const YAML::Node radius = src_.require(s, "radius", where);
      c.radius = src_.positive(radius, where + ".radius");
      if (!(c.radius >= 0.5 * c.spacing))
        src_.fail(radius, where + ".radius: " + std::to_string(c.radius) + " is below half the spacing " +
                              std::to_string(c.spacing) + " (no lattice point would fit)");
      c.speed = src_.positive(src_.require(s, "speed", where), where + ".speed");
      optionalNumber(s, "start", where, &c.start_time, &Source::nonNegative);
      optionalNumber(s, "stop", where, &c.stop_time, &Source::positive);
      if (s["stop"] && !(c.stop_time > c.start_time))
        src_.fail(s["stop"], where + ".stop: " + std::to_string(c.stop_time) + " must exceed start " +
                                 std::to_string(c.start_time));
      if (s["max_particles"])
        c.max_particles =
            size_t(src_.integer(s["max_particles"], where + ".max_particles", 1, long(kMaxParticles)));
      c.temperature = scene_.thermal.config.initial_temperature;
      if (const YAML::Node t = s["temperature"]) {
        if (!enabled("temperature"))
          src_.fail(t, where + ".temperature: needs 'temperature' in the scene's 'enable' list");
        c.temperature = src_.number(t, where + ".temperature");
      }
      try {
        c.validate();
        SphFluidSource(c, SphKernels(dimension_, scene_.config.smoothing_length), scene_.config.rest_density);
      } catch (const std::invalid_argument& e) {
        src_.fail(s, where + ": " + e.what());
      }
      scene_.sources.push_back(c);
    }
  }

  bool enabled(const std::string& physics) const {
    return std::find(scene_.enabled_physics.begin(), scene_.enabled_physics.end(), physics) !=
           scene_.enabled_physics.end();
  }

  /// A plane entry's unit `normal` and its `offset` (or a `point` on it).
  void planeGeometry(const YAML::Node& p, const std::string& where, Vec3* normal, double* offset) const {
    const YAML::Node n = src_.require(p, "normal", where);
    *normal = src_.vec(n, where + ".normal", dimension_, true);
    if (!(normal->norm() > 0)) src_.fail(n, where + ".normal must be non-zero");
    normal->normalize();
    if (p["offset"] && p["point"]) src_.fail(p["point"], where + ": give offset or point, not both");
    if (p["offset"]) *offset = src_.number(p["offset"], where + ".offset");
    if (p["point"]) *offset = normal->dot(src_.vec(p["point"], where + ".point", dimension_, false));
  }

  /// Reads an optional number key of `node` into `value` unless it is absent; `check` validates it.
  template <typename Check>
  void optionalNumber(const YAML::Node& node, const char* key, const std::string& where, double* value,
                      Check check) const {
    if (node[key]) *value = (src_.*check)(node[key], where + "." + key);
  }

  /// The material keys of a solid (spacing, model and its parameters) into *e, validated.
  void readElasticMaterial(const YAML::Node& node, const std::string& where, SphElasticConfig* elastic) {
    SphElasticConfig& e = *elastic;
    e.lattice_spacing = blockSpacing(node, where);
    if (!(e.lattice_spacing < scene_.config.smoothing_length))
      src_.fail(node, where + ": the lattice spacing must be below the smoothing length (no neighbours)");
    const std::string model = node["model"] ? src_.string(node["model"], where + ".model") : "goal_position";
    const char* strain_keys[] = {"youngs_modulus", "poisson_ratio", "hourglass_control"};
    const char* goal_keys[] = {"goal_stiffness", "deformation_allowance", "implicit_goal",
                               "implicit_step_factor", "implicit_tolerance"};
    if (model == "strain") {
      e.model = SphElasticModel::kStrain;
      for (const char* k : goal_keys)
        if (node[k]) src_.fail(node[k], where + "." + k + ": applies to model goal_position, not strain");
      optionalNumber(node, "youngs_modulus", where, &e.youngs_modulus, &Source::positive);
      optionalNumber(node, "poisson_ratio", where, &e.poisson_ratio, &Source::number);
      optionalNumber(node, "hourglass_control", where, &e.hourglass_control, &Source::nonNegative);
    } else if (model == "goal_position") {
      e.model = SphElasticModel::kGoalPosition;
      for (const char* k : strain_keys)
        if (node[k]) src_.fail(node[k], where + "." + k + ": applies to model strain, not goal_position");
      optionalNumber(node, "goal_stiffness", where, &e.goal_stiffness, &Source::positive);
      optionalNumber(node, "deformation_allowance", where, &e.deformation_allowance, &Source::unitInterval);
      if (node["implicit_goal"]) {  // true | false | global (SphElasticConfig::global_implicit_goal)
        const YAML::Node& g = node["implicit_goal"];
        e.global_implicit_goal = g.IsScalar() && g.Scalar() == "global";
        e.implicit_goal = e.global_implicit_goal || src_.boolean(g, where + ".implicit_goal");
      }
      optionalNumber(node, "implicit_step_factor", where, &e.implicit_step_factor, &Source::nonNegative);
      optionalNumber(node, "implicit_tolerance", where, &e.implicit_tolerance, &Source::positive);
    } else {
      src_.fail(node["model"], where + ".model: unknown model '" + model + "' (strain, goal_position)");
    }
    try {
      e.validate();
    } catch (const std::invalid_argument& ex) {
      src_.fail(node, where + ": " + ex.what());
    }
  }

  /// Keys `fracture` (docking, 8.2.5) and `plasticity` of a solid into *e (fixed or adaptive steps).
  void readFracturePlasticity(const YAML::Node& node, const std::string& where, SphElasticConfig* elastic) {
    SphElasticConfig& e = *elastic;
    const YAML::Node f = node["fracture"], p = node["plasticity"];
    if (!f && !p) return;
    if (f) {
      const std::string w = where + ".fracture";
      src_.allowKeys(f,
                     {"strain", "rate", "max_docking_rate", "docking_rate_increase", "docking_rate_decrease",
                      "docking_distance", "seed"},
                     w);
      e.docking = true;
      optionalNumber(f, "strain", w, &e.fracture_strain, &Source::nonNegative);
      optionalNumber(f, "rate", w, &e.fracture_rate, &Source::nonNegative);
      optionalNumber(f, "max_docking_rate", w, &e.max_docking_rate, &Source::nonNegative);
      optionalNumber(f, "docking_rate_increase", w, &e.docking_rate_increase, &Source::nonNegative);
      optionalNumber(f, "docking_rate_decrease", w, &e.docking_rate_decrease, &Source::nonNegative);
      optionalNumber(f, "docking_distance", w, &e.docking_distance, &Source::positive);
      if (f["seed"]) e.seed = uint64_t(src_.integer(f["seed"], w + ".seed", 0, 2147483647L));
    }
    if (p) {
      const std::string w = where + ".plasticity";
      src_.allowKeys(p, {"yield_strain", "flow_rate", "max_strain"}, w);
      e.yield_strain = src_.nonNegative(src_.require(p, "yield_strain", w), w + ".yield_strain");
      optionalNumber(p, "flow_rate", w, &e.plastic_flow_rate, &Source::nonNegative);
      optionalNumber(p, "max_strain", w, &e.max_plastic_strain, &Source::positive);
    }
    // The solver announces every step's dt (SphForceTerm::beginStep); time_step only covers evaluations
    // outside a step.
    e.time_step = scene_.config.fixed_dt > 0.0 ? scene_.config.fixed_dt : scene_.config.max_dt;
    try {
      e.validate();
    } catch (const std::invalid_argument& ex) {
      src_.fail(f ? f : p, where + ": " + ex.what());
    }
  }

  /// A triangle mesh file (OBJ, PLY or OFF) named by `node`; a relative path is relative to the scene file's
  /// folder.
  TriangleMesh readMeshFile(const YAML::Node& node, const std::string& what) const {
    const std::string file = src_.string(node, what);
    std::filesystem::path path(file);
    if (path.is_relative()) path = std::filesystem::path(src_.sourceName()).parent_path() / path;
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (ext != ".obj" && ext != ".ply" && ext != ".off")
      src_.fail(node, what + ": '" + file + "' is not an OBJ, PLY or OFF file");
    if (!std::filesystem::is_regular_file(path))
      src_.fail(node, what + ": mesh file '" + path.string() + "' does not exist");
    TriangleMesh mesh;
    try {
      mesh = readMesh(path.string());
    } catch (const std::exception& e) {
      src_.fail(node, what + ": " + e.what());
    }
    if (mesh.triangles.empty()) src_.fail(node, what + ": '" + path.string() + "' has no triangles");
    const std::vector<Vec3>& v = mesh.vertices.positions;
    for (size_t i = 0; i < v.size(); ++i)
      if (!v[i].allFinite())
        src_.fail(node, what + ": '" + path.string() + "': vertex " + std::to_string(i) + " is not finite");
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      for (uint32_t k : mesh.triangles[t])
        if (k >= v.size())
          src_.fail(node, what + ": '" + path.string() + "': triangle " + std::to_string(t) +
                              " has a vertex index out of range");
    return mesh;
  }

  /// Solid keys `mesh`, `scale` (a number or [sx, sy, sz]) and `translation` of shape mesh: the mesh in
  /// the body frame, x -> scale x - c (c: the centre of the scaled bounds), and the centre of the placed
  /// solid, translation + R c (the world mesh is translation + R (scale x)).
  TriangleMesh readSolidMesh(const YAML::Node& node, const std::string& where,
                             const Eigen::Matrix3d& rotation, Vec3* center, Vec3* half) const {
    if (dimension_ != 3)
      src_.fail(node["shape"], where + ".shape: mesh needs a 3D scene (a 2D solid is a box or a disc)");
    TriangleMesh mesh = readMeshFile(src_.require(node, "mesh", where), where + ".mesh");
    Vec3 scale = Vec3::Ones();
    if (const YAML::Node s = node["scale"]) {
      if (s.IsSequence()) {
        scale = src_.vec(s, where + ".scale", dimension_, false);
        if (!(scale.minCoeff() > 0) || !scale.allFinite())
          src_.fail(s, where + ".scale: every factor must be finite and > 0");
      } else {
        scale = Vec3::Constant(src_.positive(s, where + ".scale"));
      }
    }
    const Vec3 translation = node["translation"]
                                 ? src_.vec(node["translation"], where + ".translation", dimension_, false)
                                 : Vec3::Zero();
    std::vector<Vec3>& v = mesh.vertices.positions;
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (Vec3& x : v) {
      x = scale.cwiseProduct(x);
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
    const Vec3 c = 0.5 * (lo + hi);
    for (Vec3& x : v) x -= c;
    // Normals follow the (possibly non-uniform) scale: n -> scale^-1 n, renormalised.
    for (Vec3& n : mesh.vertices.normals) n = scale.cwiseInverse().cwiseProduct(n).normalized();
    *center = translation + rotation * c;
    *half = 0.5 * (hi - lo);
    return mesh;
  }

  /// An elastic object (thesis 8.2): a box, a sphere (2D: disc) or a closed triangle mesh (3D; scans with
  /// small holes work: the generalised winding number decides inside) sampled on the closest-packing lattice
  /// (8.20) around its centre, rotated by `rotation`, with its own phase id.
  void readSolid(const YAML::Node& node, const std::string& where) {
    const std::string shape = node["shape"] ? src_.string(node["shape"], where + ".shape") : "box";
    std::set<std::string> keys = {"shape",
                                  "spacing",
                                  "model",
                                  "youngs_modulus",
                                  "poisson_ratio",
                                  "hourglass_control",
                                  "goal_stiffness",
                                  "deformation_allowance",
                                  "implicit_goal",
                                  "implicit_step_factor",
                                  "implicit_tolerance",
                                  "velocity",
                                  "phase",
                                  "rotation",
                                  "temperature",
                                  "fracture",
                                  "plasticity",
                                  "anchor",
                                  "skin"};
    if (shape == "box") {
      keys.insert({"lo", "hi"});
    } else if (shape == "sphere") {
      keys.insert({"center", "radius"});
    } else if (shape == "mesh") {
      keys.insert({"mesh", "scale", "translation"});
    } else {
      src_.fail(node["shape"], where + ".shape: unknown shape '" + shape + "' (box, sphere, mesh)");
    }
    src_.allowKeys(node, keys, where);
    SphSceneSolid solid;
    readElasticMaterial(node, where, &solid.elastic);
    readFracturePlasticity(node, where, &solid.elastic);
    const SphElasticConfig& e = solid.elastic;
    // Phase id: given (unique, 1..255) or the next unused one.
    if (node["phase"]) {
      solid.phase = uint8_t(src_.integer(node["phase"], where + ".phase", 1, 255));
      if (phases_.count(solid.phase))
        src_.fail(node["phase"],
                  where + ".phase: " + std::to_string(solid.phase) + " is already used by another solid");
    } else {
      int next = 1;
      while (next <= 255 && phases_.count(uint8_t(next))) ++next;
      if (next > 255) src_.fail(node, where + ": more than 255 solids");
      solid.phase = uint8_t(next);
    }
    phases_.insert(solid.phase);
    if (const YAML::Node r = node["rotation"]) {
      src_.allowKeys(r, {"axis", "angle"}, where + ".rotation");
      Vec3 axis = Vec3::UnitZ();
      if (r["axis"]) axis = src_.vec(r["axis"], where + ".rotation.axis", dimension_, false);
      if (!(axis.norm() > 0)) src_.fail(r["axis"], where + ".rotation.axis must be non-zero");
      axis.normalize();
      if (dimension_ == 2 && (axis.x() != 0 || axis.y() != 0))
        src_.fail(r["axis"], where + ".rotation.axis: must be [0, 0, 1] in 2D");
      const double degrees =
          src_.number(src_.require(r, "angle", where + ".rotation"), where + ".rotation.angle");
      solid.orientation = Eigen::AngleAxisd(degrees * M_PI / 180.0, axis).toRotationMatrix();
    }
    const Vec3 velocity =
        node["velocity"] ? src_.vec(node["velocity"], where + ".velocity", dimension_, true) : Vec3::Zero();
    // Sample in the body frame around the centre (a lattice point, so never empty), then rotate and move.
    const double d = e.lattice_spacing;
    Vec3 center, half;
    TriangleMesh body_mesh;  // shape mesh: the mesh in the body frame
    if (shape == "box") {
      const Box box = readBox(src_, node, where, dimension_);
      center = 0.5 * (box.lo + box.hi);
      half = 0.5 * (box.hi - box.lo);
    } else if (shape == "mesh") {
      body_mesh = readSolidMesh(node, where, solid.orientation, &center, &half);
    } else {
      center = src_.vec(src_.require(node, "center", where), where + ".center", dimension_, false);
      half = Vec3::Constant(src_.positive(src_.require(node, "radius", where), where + ".radius"));
    }
    if (dimension_ == 2) center.z() = half.z() = 0.0;
    reserveLattice(node, where, center - half, center + half, d, 0);
    SphParticles& particles = scene_.particles;
    solid.first = particles.size();
    try {
      const SphLattice lattice(dimension_, d);
      const SphKernels kernels(dimension_, scene_.config.smoothing_length);
      std::vector<Vec3> local;
      if (shape == "box") {
        local = sampleLatticeBox(lattice, -half, half, SphLatticeFrame());
      } else if (shape == "sphere") {
        local = sampleLatticeSphere(lattice, Vec3::Zero(), half.x());
      } else {
        const FastWindingNumber winding(body_mesh);
        local = sampleLattice(lattice, SphLatticeFrame(), -half, half,
                              [&](const Vec3& x) { return std::abs(winding(x)) > 0.5; });
        if (local.empty())
          src_.fail(node["mesh"], where + ".mesh: '" + src_.string(node["mesh"], where + ".mesh") +
                                      "' holds no lattice point of spacing " + std::to_string(d) +
                                      " (mesh too small for the spacing, or not closed?)");
      }
      std::vector<Vec3> positions;
      positions.reserve(local.size());
      for (const Vec3& p : local) positions.push_back(center + solid.orientation * p);
      const SphElasticSolid check(e, kernels, solid.phase, solid.orientation);
      check.addParticles(particles, positions, lattice.particleMass(kernels, scene_.config.rest_density),
                         velocity);
    } catch (const std::invalid_argument& ex) {
      src_.fail(node, where + ": " + ex.what());
    }
    solid.count = particles.size() - solid.first;
    if (const YAML::Node a = node["anchor"]) {  // Fig. 8.7 (c): the solid is fixed to a wall
      src_.allowKeys(a, {"lo", "hi"}, where + ".anchor");
      const Box box = readBox(src_, a, where + ".anchor", dimension_);
      size_t anchored = 0;
      for (size_t i = solid.first; i < particles.size(); ++i) {
        const Vec3& x = particles.positions[i];
        bool inside = true;
        for (int k = 0; k < dimension_; ++k) inside = inside && x[k] >= box.lo[k] && x[k] <= box.hi[k];
        if (!inside) continue;
        particles.kinds[i] = SphParticleKind::kStaticBoundary;
        particles.velocities[i].setZero();
        ++anchored;
      }
      if (anchored == 0) src_.fail(a, where + ".anchor: the box holds no particle of the solid");
      solid.elastic.anchor_boundary_particles = true;
    }
    scene_.solids.push_back(solid);
    readBlockTemperature(node, where, solid.first);
    if (node["skin"]) readSkin(node["skin"], where + ".skin", shape, center, half, body_mesh);
  }

  /// Solid key `skin` (8.2.7): {mesh: file | resolution: n, transforms, orphans, every, obj, ply}; a solid
  /// of shape mesh may give `mesh: same` (its own mesh, placed). The rest mesh is read or made here; it is
  /// bound once all particles exist (finishSkins).
  void readSkin(const YAML::Node& node, const std::string& where, const std::string& shape,
                const Vec3& center, const Vec3& half, const TriangleMesh& body_mesh) {
    if (!enabled("skin")) src_.fail(node, where + ": needs 'skin' in the scene's 'enable' list");
    src_.allowKeys(node, {"mesh", "resolution", "transforms", "orphans", "every", "obj", "ply"}, where);
    const YAML::Node mesh = node["mesh"], resolution = node["resolution"];
    if (mesh && resolution) src_.fail(resolution, where + ": give mesh or resolution, not both");
    if (!mesh && !resolution)
      src_.fail(node, where + ": give 'mesh' (an OBJ, PLY or OFF file) or 'resolution' (the solid's shape)");
    const SphSceneSolid& solid = scene_.solids.back();
    PendingSkin pending;
    pending.node = mesh ? mesh : resolution;
    pending.where = where;
    SphSceneSkin& skin = pending.skin;
    skin.solid = scene_.solids.size() - 1;
    const bool same = mesh && mesh.IsScalar() && mesh.Scalar() == "same";
    if (same && shape != "mesh")
      src_.fail(mesh, where + ".mesh: 'same' needs a solid of shape mesh (give a file or 'resolution')");
    if (resolution && shape == "mesh")
      src_.fail(resolution, where + ".resolution: a mesh solid's own surface is 'mesh: same'");
    if (mesh && !same) {
      skin.rest = readMeshFile(mesh, where + ".mesh");
    } else if (same) {
      skin.rest = body_mesh;
      for (Vec3& x : skin.rest.vertices.positions) x = center + solid.orientation * x;
      for (Vec3& normal : skin.rest.vertices.normals) normal = solid.orientation * normal;
    } else {
      const int n = int(src_.integer(resolution, where + ".resolution", 1, 1000));
      if (dimension_ != 3)
        src_.fail(resolution, where + ".resolution: the solid's own surface needs a 3D scene (a 2D solid " +
                                  "has no surface mesh; give a 'mesh' instead)");
      skin.rest = shape == "box" ? sphBoxSkinMesh(half, n) : sphSphereSkinMesh(half.x(), n);
      for (Vec3& x : skin.rest.vertices.positions) x = center + solid.orientation * x;
      for (Vec3& normal : skin.rest.vertices.normals) normal = solid.orientation * normal;
    }
    if (const YAML::Node t = node["transforms"]) {
      const std::string s = src_.string(t, where + ".transforms");
      if (s == "lattice")
        skin.lattice_transforms = true;
      else if (s != "fitted")
        src_.fail(t, where + ".transforms: unknown choice '" + s + "' (fitted, lattice)");
    }
    if (const YAML::Node o = node["orphans"]) {
      const std::string s = src_.string(o, where + ".orphans");
      if (s == "nearest")
        pending.orphans = SphSkinOrphanPolicy::kNearestParticle;
      else if (s != "error")
        src_.fail(o, where + ".orphans: unknown choice '" + s + "' (error, nearest)");
    }
    if (node["every"]) {
      skin.every = int(src_.integer(node["every"], where + ".every", 1, 100000000));
      pending.every_given = true;
    }
    if (node["obj"]) skin.obj = src_.boolean(node["obj"], where + ".obj");
    if (node["ply"]) skin.ply = src_.boolean(node["ply"], where + ".ply");
    if (!skin.obj && !skin.ply)
      src_.fail(node["obj"] ? node["obj"] : node["ply"],
                where + ": obj and ply are both false (nothing to write)");
    pending_skins_.push_back(std::move(pending));
  }

  /// `enable: [skin]`: binds every skin to the rest particles of its solid (8.38); the output follows the
  /// particle output's every unless the skin gives its own.
  void finishSkins() {
    if (pending_skins_.empty())
      src_.fail(enable_nodes_.at("skin"), "enable: 'skin' but no solid has a 'skin' key");
    for (PendingSkin& pending : pending_skins_) {
      SphSceneSkin& skin = pending.skin;
      const SphSceneSolid& solid = scene_.solids[skin.solid];
      if (!pending.every_given && scene_.output.every > 0) skin.every = scene_.output.every;
      SphSkinRest rest;
      rest.positions = scene_.particles.positions;
      rest.solid.resize(solid.count);
      for (size_t i = 0; i < solid.count; ++i) rest.solid[i] = uint32_t(solid.first + i);
      rest.uniform_transform = solid.orientation;  // A_i^0 of SphElasticSolid::latticeTransforms()
      SphSkinConfig config;
      config.support_radius = scene_.config.smoothing_length;
      config.orphans = pending.orphans;
      config.dimension = dimension_;
      try {
        skin.skin = SphSkin(rest, skin.rest.vertices.positions, config);
      } catch (const std::invalid_argument& e) {
        src_.fail(pending.node, pending.where + ": " + e.what());
      }
      scene_.skins.push_back(std::move(skin));
    }
    pending_skins_.clear();
  }

  void readSolver(const YAML::Node& node) {
    src_.allowKeys(node,
                   {"smoothing_length", "smoothing_ratio", "rest_density", "stiffness", "speed_of_sound",
                    "gamma", "negative_pressure_scale", "pressure_kernel", "boundary_pressure", "viscosity",
                    "xsph", "gravity", "cfl", "fixed_dt", "max_dt", "instability_energy_growth", "threads"},
                   "solver");
    SphFluidConfig& c = scene_.config;
    auto field = [&](const char* key, const char* config_field) -> YAML::Node {
      const YAML::Node v = node[key];
      if (v) field_nodes_[config_field] = v;
      return v;
    };
    // h: kernel support radius, given directly or as a multiple of the scene spacing.
    const YAML::Node h = field("smoothing_length", "smoothing_length");
    const YAML::Node ratio = field("smoothing_ratio", "smoothing_length");
    if (h && ratio) src_.fail(ratio, "solver: give smoothing_length or smoothing_ratio, not both");
    if (h) {
      c.smoothing_length = src_.positive(h, "solver.smoothing_length");
    } else if (ratio) {
      if (spacing_ <= 0) src_.fail(ratio, "solver.smoothing_ratio needs the scene's 'spacing'");
      c.smoothing_length = src_.positive(ratio, "solver.smoothing_ratio") * spacing_;
    } else {
      src_.fail(node, "solver: missing 'smoothing_length' (or 'smoothing_ratio')");
    }
    if (field("rest_density", "rest_density"))
      c.rest_density = src_.positive(node["rest_density"], "solver.rest_density");
    if (field("gamma", "gamma")) c.gamma = src_.number(node["gamma"], "solver.gamma");
    const YAML::Node stiffness = field("stiffness", "stiffness");
    const YAML::Node sound = field("speed_of_sound", "stiffness");
    if (stiffness && sound) src_.fail(sound, "solver: give stiffness or speed_of_sound, not both");
    if (stiffness) c.stiffness = src_.positive(stiffness, "solver.stiffness");
    if (sound) {  // c^2 = K Gamma / rho_0
      const double speed = src_.positive(sound, "solver.speed_of_sound");
      if (!(c.gamma >= 1)) src_.fail(node["gamma"], "solver.gamma must be >= 1");
      c.stiffness = speed * speed * c.rest_density / c.gamma;
    }
    if (field("negative_pressure_scale", "negative_pressure_scale"))
      c.negative_pressure_scale =
          src_.number(node["negative_pressure_scale"], "solver.negative_pressure_scale");
    if (const YAML::Node k = field("pressure_kernel", "pressure_kernel")) {
      const std::string s = src_.string(k, "solver.pressure_kernel");
      if (s == "spiky")
        c.pressure_kernel = SphPressureKernel::kSpiky;
      else if (s == "poly6")
        c.pressure_kernel = SphPressureKernel::kPoly6;
      else
        src_.fail(k, "solver.pressure_kernel: unknown kernel '" + s + "' (spiky, poly6)");
    }
    if (const YAML::Node b = field("boundary_pressure", "boundary_pressure")) {
      const std::string s = src_.string(b, "solver.boundary_pressure");
      if (s == "extrapolated")
        c.boundary_pressure = SphBoundaryPressure::kExtrapolated;
      else if (s == "summation")
        c.boundary_pressure = SphBoundaryPressure::kSummation;
      else
        src_.fail(b, "solver.boundary_pressure: unknown method '" + s + "' (extrapolated, summation)");
    }
    if (field("viscosity", "viscosity")) c.viscosity = src_.number(node["viscosity"], "solver.viscosity");
    if (field("xsph", "xsph")) c.xsph = src_.number(node["xsph"], "solver.xsph");
    if (field("gravity", "gravity"))
      c.gravity = src_.vec(node["gravity"], "solver.gravity", dimension_, true);
    if (field("cfl", "cfl")) c.cfl = src_.number(node["cfl"], "solver.cfl");
    if (field("fixed_dt", "fixed_dt")) c.fixed_dt = src_.number(node["fixed_dt"], "solver.fixed_dt");
    if (field("max_dt", "max_dt")) c.max_dt = src_.number(node["max_dt"], "solver.max_dt");
    if (field("instability_energy_growth", "instability_energy_growth"))
      c.instability_energy_growth =
          src_.number(node["instability_energy_growth"], "solver.instability_energy_growth");
    if (field("threads", "num_threads"))
      c.num_threads = int(src_.integer(node["threads"], "solver.threads", 0, 4096));
    try {
      c.validate();
    } catch (const std::invalid_argument& e) {
      // "SphFluidConfig.<field>: ..." -> the line of that field.
      const std::string message = e.what();
      const std::string prefix = "SphFluidConfig.";
      YAML::Node at = node;
      if (message.rfind(prefix, 0) == 0) {
        const std::string name = message.substr(prefix.size(), message.find(':') - prefix.size());
        const auto it = field_nodes_.find(name);
        if (it != field_nodes_.end()) at = it->second;
      }
      src_.fail(at, "solver: " + message);
    }
  }

  double blockSpacing(const YAML::Node& node, const std::string& where) const {
    if (node["spacing"]) return src_.positive(node["spacing"], where + ".spacing");
    if (spacing_ <= 0)
      src_.fail(node, where + ": missing 'spacing' (and the scene has no default 'spacing')");
    return spacing_;
  }

  /// Mass of a lattice particle of spacing dx (rest density with full support).
  double massFor(double dx) {
    auto it = masses_.find(dx);
    if (it == masses_.end())
      it = masses_
               .emplace(dx, latticeParticleMass(SphKernels(dimension_, scene_.config.smoothing_length),
                                                scene_.config.rest_density, dx))
               .first;
    return it->second;
  }

  /// Guards against a typo in a spacing before anything is allocated.
  void reserveLattice(const YAML::Node& node, const std::string& where, const Vec3& lo, const Vec3& hi,
                      double dx, int layers) {
    double n = 1;
    for (int k = 0; k < dimension_; ++k) n *= std::floor((hi[k] - lo[k]) / dx + 1e-9) + 2.0 * layers;
    planned_ += n;
    if (planned_ > kMaxParticles)
      src_.fail(node, where + ": the scene would exceed " + std::to_string(long(kMaxParticles)) +
                          " particles (spacing too small?)");
  }

  void addBox(const YAML::Node& node, const std::string& where, const Box& box, double dx,
              SphParticleKind kind, const Vec3& velocity) {
    reserveLattice(node, where, box.lo, box.hi, dx, 0);
    const size_t first = scene_.particles.size();
    try {
      addLatticeBox(scene_.particles, box.lo, box.hi, dx, massFor(dx), dimension_, kind);
    } catch (const std::invalid_argument& e) {
      src_.fail(node, where + ": " + e.what());
    }
    for (size_t i = first; i < scene_.particles.size(); ++i) scene_.particles.velocities[i] = velocity;
  }

  void readFluid(const YAML::Node& node, const std::string& where) {
    src_.allowKeys(node, {"lo", "hi", "spacing", "velocity", "temperature"}, where);
    const Box box = readBox(src_, node, where, dimension_);
    const double dx = blockSpacing(node, where);
    const Vec3 v =
        node["velocity"] ? src_.vec(node["velocity"], where + ".velocity", dimension_, true) : Vec3::Zero();
    const size_t first = scene_.particles.size();
    addBox(node, where, box, dx, SphParticleKind::kFluid, v);
    readBlockTemperature(node, where, first);
  }

  void readMoving(const YAML::Node& node, const std::string& where) {
    src_.allowKeys(node, {"lo", "hi", "spacing", "velocity"}, where);
    const Box box = readBox(src_, node, where, dimension_);
    const double dx = blockSpacing(node, where);
    const Vec3 v = src_.vec(src_.require(node, "velocity", where), where + ".velocity", dimension_, true);
    addBox(node, where, box, dx, SphParticleKind::kMovingBoundary, v);
  }

  void readBoundary(const YAML::Node& node) {
    src_.allowKeys(node, {"walls", "boxes", "cylinders", "planes", "box_planes"}, "boundary");
    auto list = [&](const char* key) {
      const YAML::Node l = node[key];
      if (l && !l.IsSequence()) src_.fail(l, std::string("boundary.") + key + ": expected a list");
      return l ? l : YAML::Node(YAML::NodeType::Sequence);
    };
    const YAML::Node walls = list("walls");
    for (size_t i = 0; i < walls.size(); ++i) {
      const std::string where = "boundary.walls[" + std::to_string(i) + "]";
      const YAML::Node w = walls[i];
      src_.allowKeys(w, {"lo", "hi", "spacing", "layers", "closed_top"}, where);
      const Box box = readBox(src_, w, where, dimension_);
      const double dx = blockSpacing(w, where);
      const int layers = w["layers"] ? int(src_.integer(w["layers"], where + ".layers", 1, 100)) : 3;
      const bool closed_top = w["closed_top"] ? src_.boolean(w["closed_top"], where + ".closed_top") : false;
      reserveLattice(w, where, box.lo, box.hi, dx, layers);
      try {
        addBoundaryWalls(scene_.particles, box.lo, box.hi, dx, layers, massFor(dx), dimension_, closed_top);
      } catch (const std::invalid_argument& e) {
        src_.fail(w, where + ": " + e.what());
      }
    }
    const YAML::Node boxes = list("boxes");
    for (size_t i = 0; i < boxes.size(); ++i) {
      const std::string where = "boundary.boxes[" + std::to_string(i) + "]";
      src_.allowKeys(boxes[i], {"lo", "hi", "spacing"}, where);
      addBox(boxes[i], where, readBox(src_, boxes[i], where, dimension_), blockSpacing(boxes[i], where),
             SphParticleKind::kStaticBoundary, Vec3::Zero());
    }
    const YAML::Node cylinders = list("cylinders");
    for (size_t i = 0; i < cylinders.size(); ++i) {
      const std::string where = "boundary.cylinders[" + std::to_string(i) + "]";
      const YAML::Node c = cylinders[i];
      src_.allowKeys(c, {"from", "to", "radius", "spacing"}, where);
      const Cylinder cyl = readCylinder(c, where);
      const double dx = blockSpacing(c, where);
      const double length = (cyl.to - cyl.from).norm();
      const double r = std::floor(cyl.radius / dx + 1e-9);
      planned_ += (std::floor(length / dx) + 1.0) * (2.0 * r + 1.0) * (2.0 * r + 1.0);
      if (planned_ > kMaxParticles)
        src_.fail(c, where + ": the scene would exceed " + std::to_string(long(kMaxParticles)) +
                         " particles (spacing too small?)");
      try {
        addLatticeCylinder(scene_.particles, cyl.from, cyl.to, cyl.radius, dx, massFor(dx),
                           SphParticleKind::kStaticBoundary);
      } catch (const std::invalid_argument& e) {
        src_.fail(c, where + ": " + e.what());
      }
    }
    const YAML::Node planes = list("planes");
    for (size_t i = 0; i < planes.size(); ++i) {
      const std::string where = "boundary.planes[" + std::to_string(i) + "]";
      const YAML::Node p = planes[i];
      src_.allowKeys(p, {"normal", "offset", "point", "restitution", "friction"}, where);
      SphPlane plane;
      planeGeometry(p, where, &plane.normal, &plane.offset);
      if (p["restitution"]) plane.restitution = src_.unitInterval(p["restitution"], where + ".restitution");
      if (p["friction"]) plane.friction = src_.unitInterval(p["friction"], where + ".friction");
      scene_.planes.push_back(plane);
    }
    const YAML::Node box_planes = list("box_planes");
    for (size_t i = 0; i < box_planes.size(); ++i) {
      const std::string where = "boundary.box_planes[" + std::to_string(i) + "]";
      const YAML::Node b = box_planes[i];
      src_.allowKeys(b, {"lo", "hi", "closed_top", "restitution", "friction"}, where);
      const Box box = readBox(src_, b, where, dimension_);
      const bool closed_top = b["closed_top"] ? src_.boolean(b["closed_top"], where + ".closed_top") : false;
      const double restitution =
          b["restitution"] ? src_.unitInterval(b["restitution"], where + ".restitution") : 0.0;
      const double friction = b["friction"] ? src_.unitInterval(b["friction"], where + ".friction") : 0.0;
      for (const SphPlane& plane : boxPlanes(box.lo, box.hi, dimension_, closed_top, restitution, friction))
        scene_.planes.push_back(plane);
    }
  }

  void readFrames(const YAML::Node& node) {
    src_.allowKeys(node, {"count", "time"}, "frames");
    scene_.frame_count =
        int(src_.integer(src_.require(node, "count", "frames"), "frames.count", 1, 100000000));
    scene_.frame_time = src_.positive(src_.require(node, "time", "frames"), "frames.time");
  }

  void readOutput(const YAML::Node& node) {
    src_.allowKeys(node, {"particles", "surface"}, "output");
    if (const YAML::Node surface = node["surface"]) {
      if (!enabled("surface"))
        src_.fail(surface, "output.surface: needs 'surface' in the scene's 'enable' list");
      readSurface(surface);
    }
    const YAML::Node p = node["particles"];
    if (!p) return;
    src_.allowKeys(p, {"every", "formats"}, "output.particles");
    SphParticleOutput& out = scene_.output;
    out.every = p["every"] ? int(src_.integer(p["every"], "output.particles.every", 1, 100000000)) : 1;
    const YAML::Node formats = src_.require(p, "formats", "output.particles");
    if (!formats.IsSequence()) src_.fail(formats, "output.particles.formats: expected a list (ply, vtp)");
    for (size_t i = 0; i < formats.size(); ++i) {
      const std::string f = src_.string(formats[i], "output.particles.formats");
      if (f == "ply")
        out.ply = true;
      else if (f == "vtp")
        out.vtp = true;
      else
        src_.fail(formats[i], "output.particles.formats: unknown format '" + f + "' (ply, vtp)");
    }
  }

  /// output.surface: {every, formats: [obj, ply], cell_size, iso_value, particles: fluid | all}.
  void readSurface(const YAML::Node& node) {
    src_.allowKeys(node, {"every", "formats", "cell_size", "iso_value", "particles"}, "output.surface");
    SphSurfaceOutput& out = scene_.surface;
    if (node["every"]) {
      out.every = int(src_.integer(node["every"], "output.surface.every", 1, 100000000));
      surface_every_given_ = true;
    }
    if (const YAML::Node formats = node["formats"]) {
      if (!formats.IsSequence() || formats.size() == 0)
        src_.fail(formats, "output.surface.formats: expected a list (obj, ply)");
      out.obj = out.ply = false;
      for (size_t i = 0; i < formats.size(); ++i) {
        const std::string f = src_.string(formats[i], "output.surface.formats");
        if (f == "obj")
          out.obj = true;
        else if (f == "ply")
          out.ply = true;
        else
          src_.fail(formats[i], "output.surface.formats: unknown format '" + f + "' (obj, ply)");
      }
    }
    if (node["cell_size"])
      out.config.cell_size = src_.positive(node["cell_size"], "output.surface.cell_size");
    if (node["iso_value"])
      out.config.iso_value = src_.positive(node["iso_value"], "output.surface.iso_value");
    if (const YAML::Node p = node["particles"]) {
      const std::string s = src_.string(p, "output.surface.particles");
      if (s == "fluid")
        out.config.particles = SphSurfaceParticles::kFluid;
      else if (s == "all")
        out.config.particles = SphSurfaceParticles::kFluidAndBoundary;
      else
        src_.fail(p, "output.surface.particles: unknown choice '" + s + "' (fluid, all)");
    }
  }

  /// `enable: [surface]`: the surface follows the solver's h, rest density and threads; every frame of the
  /// particle output unless output.surface.every is given.
  void finishSurface() {
    if (dimension_ != 3)
      src_.fail(enable_nodes_.at("surface"), "enable: 'surface' needs a 3D scene (marching cubes)");
    SphSurfaceOutput& out = scene_.surface;
    out.enabled = true;
    if (!surface_every_given_ && scene_.output.every > 0) out.every = scene_.output.every;
    out.config.smoothing_length = scene_.config.smoothing_length;
    out.config.rest_density = scene_.config.rest_density;
    out.config.num_threads = scene_.config.num_threads;
    out.config.validate();
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

}  // namespace

const std::vector<std::string>& sphOptionalPhysics() {
  // elasticity (8.2), phase_transition (8.2.4), temperature (heat conduction driving 8.2.4), surface (8.2.7).
  // collisions: the penalty (8.37) between solids (8.2.6). skin: surfaces bound to solids (8.38).
  static const std::vector<std::string> names = {"elasticity",  "collisions", "phase_transition",
                                                 "temperature", "surface",    "skin"};
  return names;
}

SphScene parseSphScene(const std::string& yaml_text, const std::string& source_name) {
  const Source src{source_name};
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw SphSceneError(source_name + ":" + std::to_string(e.mark.line + 1) + ":" +
                        std::to_string(e.mark.column + 1) + ": YAML syntax: " + e.msg);
  }
  if (!root.IsMap()) src.fail(root, "expected a map of scene keys (dimension, solver, fluid, frames, ...)");
  SphScene scene;
  scene.path = source_name;
  scene.name = std::filesystem::path(source_name).stem().string();
  SceneReader(src, &scene).read(root);
  return scene;
}

SphScene loadSphScene(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SphSceneError(path + ": cannot open the scene file");
  std::stringstream text;
  text << in.rdbuf();
  return parseSphScene(text.str(), path);
}

}  // namespace rc
