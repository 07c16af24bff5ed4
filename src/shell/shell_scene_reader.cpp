#include "relaxed_connectivity/shell/shell_scene_reader.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/io/yaml_reader.h"
#include "relaxed_connectivity/shell/shell_sheet_source.h"
#include "relaxed_connectivity/surface/analytic_shapes.h"
#include "relaxed_connectivity/surface/radius_estimation.h"

namespace rc {

namespace {

[[noreturn]] void raiseShellSceneError(const std::string& message) {
  throw ShellSceneError(message);
}

/// Area-weighted vertex normals of a mesh.
std::vector<Vec3> vertexNormals(const TriangleMesh& mesh) {
  std::vector<Vec3> n(mesh.vertices.size(), Vec3::Zero());
  for (const Triangle& t : mesh.triangles) {
    const Vec3& a = mesh.vertices.positions[t[0]];
    const Vec3 face = (mesh.vertices.positions[t[1]] - a).cross(mesh.vertices.positions[t[2]] - a);
    for (uint32_t v : t) n[v] += face;
  }
  for (Vec3& v : n) v = v.norm() > 0 ? Vec3(v.normalized()) : Vec3(Vec3::UnitZ());
  return n;
}

/// `count` area-uniform samples on the triangles, normals interpolated from the vertex normals.
SurfelCloud sampleMesh(const TriangleMesh& mesh, const std::vector<Vec3>& normals, size_t count) {
  std::vector<double> cumulative;
  double total = 0.0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3& a = mesh.vertices.positions[t[0]];
    total += 0.5 * (mesh.vertices.positions[t[1]] - a).cross(mesh.vertices.positions[t[2]] - a).norm();
    cumulative.push_back(total);
  }
  SurfelCloud cloud;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t s = 0; s < count; ++s) {
    const double pick = u(rng) * total;
    const size_t f =
        std::min(size_t(std::lower_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin()),
                 cumulative.size() - 1);
    double r1 = u(rng), r2 = u(rng);
    if (r1 + r2 > 1.0) r1 = 1.0 - r1, r2 = 1.0 - r2;
    const Triangle& t = mesh.triangles[f];
    const double w0 = 1.0 - r1 - r2;
    cloud.positions.push_back(w0 * mesh.vertices.positions[t[0]] + r1 * mesh.vertices.positions[t[1]] +
                              r2 * mesh.vertices.positions[t[2]]);
    Vec3 n = w0 * normals[t[0]] + r1 * normals[t[1]] + r2 * normals[t[2]];
    cloud.normals.push_back(n.norm() > 0 ? Vec3(n.normalized()) : normals[t[0]]);
  }
  // Random samples leave voids wider than the mean spacing: radii that cover the gaps between neighbours
  // (3.3) keep the rendered surface hole-free; capped at 2.5 mean spacings (isolated samples at sharp edges).
  RadiusEstimationConfig radii;
  radii.max_radius = 2.5 * std::sqrt(total / count);
  estimateRadii(cloud, radii);
  return cloud;
}

class SceneReader {
 public:
  SceneReader(const YamlReader& src, ShellScene* scene) : src_(src), scene_(*scene) {}

  void read(const YAML::Node& root) {
    src_.allowKeys(root, {"name",       "source",   "placement",  "velocity",   "nodes",    "material",
                          "plasticity", "fracture", "anisotropy", "weak_point", "dynamics", "ground",
                          "pins",       "balloon",  "frames",     "skinning",   "output",   "analysis",
                          "held",       "loads",    "static",     "modes",      "probes"},
                   "scene");
    if (root["name"]) scene_.name = src_.string(root["name"], "name");
    readSource(src_.require(root, "source", "scene"));
    if (root["placement"]) readPlacement(root["placement"]);
    if (root["velocity"]) scene_.initial_velocity = src_.vec3(root["velocity"], "velocity");
    readNodes(src_.require(root, "nodes", "scene"));
    readMaterial(src_.require(root, "material", "scene"));
    if (root["plasticity"]) readPlasticity(root["plasticity"]);
    if (root["fracture"]) readFracture(root["fracture"]);
    if (root["anisotropy"]) readAnisotropy(root["anisotropy"]);
    if (root["weak_point"]) readWeakPoint(root["weak_point"]);
    readDynamics(src_.require(root, "dynamics", "scene"));
    if (root["ground"]) readGround(root["ground"]);
    if (root["pins"]) readPins(root["pins"]);
    if (root["balloon"]) readBalloon(root["balloon"]);
    const bool dynamic =
        !root["analysis"] || (root["analysis"].IsScalar() && root["analysis"].Scalar() == "dynamic");
    if (root["frames"] || dynamic) readFrames(src_.require(root, "frames", "scene"));
    if (root["skinning"]) {
      src_.allowKeys(root["skinning"], {"nodes"}, "skinning");
      scene_.skinning_nodes =
          size_t(src_.integer(src_.require(root["skinning"], "nodes", "skinning"), "skinning.nodes", 2, 32));
    }
    if (root["output"]) readOutput(root["output"]);
    readAnalysis(root);
  }

 private:
  void readSource(const YAML::Node& node) {
    src_.allowKeys(node, {"file", "sample_count", "fit_size", "flip_normals", "sheet", "sphere"}, "source");
    const int kinds = int(bool(node["file"])) + int(bool(node["sheet"])) + int(bool(node["sphere"]));
    if (kinds != 1) src_.fail(node, "source: give exactly one of 'file', 'sheet', 'sphere'");
    if (node["file"]) {
      readFile(node);
    } else {
      for (const char* key : {"sample_count", "fit_size", "flip_normals"})
        if (node[key]) src_.fail(node[key], std::string("source.") + key + ": only for a 'file' source");
      if (node["sheet"]) readSheet(node["sheet"]);
      if (node["sphere"]) readSphere(node["sphere"]);
    }
  }

  void readFile(const YAML::Node& node) {
    const std::string file = src_.string(node["file"], "source.file");
    std::filesystem::path path(file);
    if (path.is_relative()) path = std::filesystem::path(src_.sourceName()).parent_path() / path;
    TriangleMesh mesh;
    try {
      mesh = readMesh(path.string());
    } catch (const std::exception& e) {
      src_.fail(node["file"], "source.file: cannot read '" + path.string() + "': " + e.what());
    }
    if (mesh.vertices.empty()) src_.fail(node["file"], "source.file: '" + path.string() + "' has no points");
    SurfelCloud& cloud = scene_.surfels;
    if (node["sample_count"]) {
      const size_t count = size_t(src_.integer(node["sample_count"], "source.sample_count", 1, 100000000));
      if (mesh.triangles.empty())
        src_.fail(node["sample_count"], "source.sample_count: '" + path.string() + "' has no triangles");
      const std::vector<Vec3> normals =
          mesh.vertices.hasNormals() ? mesh.vertices.normals : vertexNormals(mesh);
      cloud = sampleMesh(mesh, normals, count);
    } else {
      cloud = mesh.vertices;
      if (!cloud.hasNormals()) {
        if (mesh.triangles.empty())
          src_.fail(node["file"], "source.file: '" + path.string() + "' has neither normals nor triangles");
        cloud.normals = vertexNormals(mesh);
      }
      for (Vec3& n : cloud.normals) n.normalize();
    }
    if (node["flip_normals"] && src_.boolean(node["flip_normals"], "source.flip_normals"))
      for (Vec3& n : cloud.normals) n = -n;
    if (node["fit_size"]) {
      const double size = src_.positive(node["fit_size"], "source.fit_size");
      Vec3 lo, hi;
      cloud.bounds(&lo, &hi);
      const double scale = size / (hi - lo).maxCoeff();
      const Vec3 center = 0.5 * (lo + hi);
      for (Vec3& p : cloud.positions) p = scale * (p - center);
      for (double& r : cloud.radii) r *= scale;
    }
  }

  /// Jittered grid on [-w/2, w/2] x [-h/2, h/2] in z = 0, normal +z, coloured like a printed poster.
  void readSheet(const YAML::Node& node) {
    src_.allowKeys(node, {"size", "spacing", "jitter", "colors", "tile"}, "source.sheet");
    const YAML::Node size_node = src_.require(node, "size", "source.sheet");
    if (!size_node.IsSequence() || size_node.size() != 2)
      src_.fail(size_node, "source.sheet.size: expected [w, h]");
    SheetSource sheet;
    sheet.width = src_.positive(size_node[0], "source.sheet.size");
    sheet.height = src_.positive(size_node[1], "source.sheet.size");
    sheet.spacing = src_.positive(src_.require(node, "spacing", "source.sheet"), "source.sheet.spacing");
    if (node["jitter"]) sheet.jitter = src_.unitInterval(node["jitter"], "source.sheet.jitter");
    if (node["colors"])
      sheet.colors = src_.choice<SheetColors>(
          node["colors"], "source.sheet.colors",
          {{"none", SheetColors::kNone}, {"checker", SheetColors::kChecker}, {"rings", SheetColors::kRings}});
    if (node["tile"]) sheet.tile = src_.positive(node["tile"], "source.sheet.tile");
    long nx = 0, ny = 0;
    try {
      sheetCells(sheet, &nx, &ny);
    } catch (const std::invalid_argument&) {
      src_.fail(node["spacing"], nx < 2 || ny < 2 ? "source.sheet.spacing: larger than the sheet"
                                                  : "source.sheet.spacing: too many surfels");
    }
    scene_.surfels = sheetSurfels(sheet);
  }

  void readSphere(const YAML::Node& node) {
    src_.allowKeys(node, {"radius", "count", "center"}, "source.sphere");
    const double r = src_.positive(src_.require(node, "radius", "source.sphere"), "source.sphere.radius");
    const size_t count = size_t(
        src_.integer(src_.require(node, "count", "source.sphere"), "source.sphere.count", 12, 50000000));
    const Vec3 c = node["center"] ? src_.vec3(node["center"], "source.sphere.center") : Vec3::Zero();
    scene_.surfels = AnalyticSphere(c, r).sample(count);
    scene_.surfels.radii.assign(count, 1.5 * std::sqrt(4.0 * r * r / count));
  }

  void readPlacement(const YAML::Node& node) {
    src_.allowKeys(node, {"rotation", "translation"}, "placement");
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    if (node["rotation"]) {
      const YAML::Node r = node["rotation"];
      src_.allowKeys(r, {"axis", "degrees"}, "placement.rotation");
      const Vec3 axis = src_.vec3(src_.require(r, "axis", "placement.rotation"), "placement.rotation.axis");
      if (!(axis.norm() > 0)) src_.fail(r["axis"], "placement.rotation.axis: must not be zero");
      const double deg =
          src_.number(src_.require(r, "degrees", "placement.rotation"), "placement.rotation.degrees");
      rotation = Eigen::AngleAxisd(deg * M_PI / 180.0, axis.normalized()).toRotationMatrix();
    }
    const Vec3 t =
        node["translation"] ? src_.vec3(node["translation"], "placement.translation") : Vec3::Zero();
    SurfelCloud& c = scene_.surfels;
    for (Vec3& p : c.positions) p = rotation * p + t;
    for (Vec3& n : c.normals) n = rotation * n;
    for (Vec3& a : c.axes1) a = rotation * a;
    for (Vec3& a : c.axes2) a = rotation * a;
  }

  void readNodes(const YAML::Node& node) {
    src_.allowKeys(node, {"spacing", "count", "neighbors", "relax_iterations"}, "nodes");
    if (bool(node["spacing"]) == bool(node["count"]))
      src_.fail(node, "nodes: give exactly one of 'spacing', 'count'");
    if (node["spacing"]) scene_.nodes.spacing = src_.positive(node["spacing"], "nodes.spacing");
    if (node["count"]) {
      scene_.nodes.target_count = size_t(src_.integer(node["count"], "nodes.count", 4, 10000000));
      if (scene_.nodes.target_count > scene_.surfels.size())
        src_.fail(node["count"], "nodes.count: more nodes than the " + std::to_string(scene_.surfels.size()) +
                                     " surfels of the source");
    }
    if (node["neighbors"])
      scene_.nodes.neighbor_count = size_t(src_.integer(node["neighbors"], "nodes.neighbors", 4, 16));
    if (node["relax_iterations"])
      scene_.nodes.relax_iterations =
          int(src_.integer(node["relax_iterations"], "nodes.relax_iterations", 0, 100));
  }

  void readMaterial(const YAML::Node& node) {
    src_.allowKeys(
        node,
        {"stretch_stiffness", "bending_stiffness", "density", "damping", "bending_fit", "balance_membrane"},
        "material");
    ShellMaterial& m = scene_.material;
    m.stretch_stiffness =
        src_.nonNegative(src_.require(node, "stretch_stiffness", "material"), "material.stretch_stiffness");
    m.bending_stiffness =
        src_.nonNegative(src_.require(node, "bending_stiffness", "material"), "material.bending_stiffness");
    if (!(m.stretch_stiffness + m.bending_stiffness > 0))
      src_.fail(node, "material: stretch_stiffness and bending_stiffness are both 0");
    if (node["density"]) m.areal_density = src_.positive(node["density"], "material.density");
    if (node["damping"]) m.damping = src_.nonNegative(node["damping"], "material.damping");
    if (node["bending_fit"]) m.bending_fit = src_.positive(node["bending_fit"], "material.bending_fit");
    if (node["balance_membrane"])
      scene_.balance_membrane = src_.boolean(node["balance_membrane"], "material.balance_membrane");
  }

  void readPlasticity(const YAML::Node& node) {
    src_.allowKeys(node, {"stretch_yield", "bend_yield", "stretch_creep", "bend_creep", "weakening"},
                   "plasticity");
    ShellPlasticity& p = scene_.material_options.plasticity;
    if (node["stretch_yield"])
      p.stretch_yield = src_.nonNegative(node["stretch_yield"], "plasticity.stretch_yield");
    if (node["bend_yield"]) p.bend_yield = src_.nonNegative(node["bend_yield"], "plasticity.bend_yield");
    if (node["stretch_creep"])
      p.stretch_creep = src_.nonNegative(node["stretch_creep"], "plasticity.stretch_creep");
    if (node["bend_creep"]) p.bend_creep = src_.nonNegative(node["bend_creep"], "plasticity.bend_creep");
    if (node["weakening"]) p.weakening = src_.nonNegative(node["weakening"], "plasticity.weakening");
    scene_.plasticity = true;
  }

  void readFracture(const YAML::Node& node) {
    src_.allowKeys(
        node,
        {"stretch_threshold", "bend_threshold", "max_cracks_per_step", "min_fiber_length", "max_crack_speed"},
        "fracture");
    ShellFracture& f = scene_.material_options.fracture;
    if (!node["stretch_threshold"] && !node["bend_threshold"])
      src_.fail(node, "fracture: give stretch_threshold and / or bend_threshold");
    if (node["stretch_threshold"])
      f.stretch_threshold = src_.positive(node["stretch_threshold"], "fracture.stretch_threshold");
    if (node["bend_threshold"])
      f.bend_threshold = src_.positive(node["bend_threshold"], "fracture.bend_threshold");
    if (node["max_cracks_per_step"])
      f.max_cracks_per_step =
          size_t(src_.integer(node["max_cracks_per_step"], "fracture.max_cracks_per_step", 1, 100000));
    if (node["min_fiber_length"])
      f.min_fiber_length = src_.nonNegative(node["min_fiber_length"], "fracture.min_fiber_length");
    if (node["max_crack_speed"])
      f.max_crack_speed = src_.positive(node["max_crack_speed"], "fracture.max_crack_speed");
    scene_.fracture = true;
  }

  void readAnisotropy(const YAML::Node& node) {
    src_.allowKeys(node, {"direction", "stretch_ratio", "bend_ratio"}, "anisotropy");
    ShellSceneAnisotropy& a = scene_.anisotropy;
    a.direction = src_.vec3(src_.require(node, "direction", "anisotropy"), "anisotropy.direction");
    if (!(a.direction.norm() > 0)) src_.fail(node["direction"], "anisotropy.direction: must not be zero");
    a.direction.normalize();
    if (node["stretch_ratio"])
      a.stretch_ratio = src_.positive(node["stretch_ratio"], "anisotropy.stretch_ratio");
    if (node["bend_ratio"]) a.bend_ratio = src_.positive(node["bend_ratio"], "anisotropy.bend_ratio");
    a.enabled = true;
  }

  void readWeakPoint(const YAML::Node& node) {
    src_.allowKeys(node, {"center", "radius", "stretch_threshold", "bend_threshold"}, "weak_point");
    if (!scene_.fracture) src_.fail(node, "weak_point: needs a 'fracture' block");
    ShellSceneWeakPoint& w = scene_.weak_point;
    w.center = src_.vec3(src_.require(node, "center", "weak_point"), "weak_point.center");
    w.radius = src_.positive(src_.require(node, "radius", "weak_point"), "weak_point.radius");
    if (!node["stretch_threshold"] && !node["bend_threshold"])
      src_.fail(node, "weak_point: give stretch_threshold and / or bend_threshold");
    if (node["stretch_threshold"])
      w.stretch_threshold = src_.positive(node["stretch_threshold"], "weak_point.stretch_threshold");
    if (node["bend_threshold"])
      w.bend_threshold = src_.positive(node["bend_threshold"], "weak_point.bend_threshold");
    w.enabled = true;
  }

  void readDynamics(const YAML::Node& node) {
    src_.allowKeys(node, {"time_step", "step_safety", "step_update_interval", "gravity", "blowup_factor"},
                   "dynamics");
    ShellSolverOptions& o = scene_.solver;
    if (node["time_step"]) {
      const YAML::Node t = node["time_step"];
      if (!(t.IsScalar() && t.Scalar() == "auto"))
        o.time_step = src_.positive(t, "dynamics.time_step (or auto)");
    }
    if (node["step_safety"]) {
      o.step_safety = src_.positive(node["step_safety"], "dynamics.step_safety");
      if (o.step_safety > 1.0) src_.fail(node["step_safety"], "dynamics.step_safety must be <= 1");
    }
    if (node["step_update_interval"])
      o.step_update_interval =
          int(src_.integer(node["step_update_interval"], "dynamics.step_update_interval", 1, 100000));
    if (node["gravity"]) o.gravity = src_.vec3(node["gravity"], "dynamics.gravity");
    if (node["blowup_factor"])
      o.blowup_factor = src_.positive(node["blowup_factor"], "dynamics.blowup_factor");
  }

  void readGround(const YAML::Node& node) {
    src_.allowKeys(node, {"point", "normal", "restitution", "friction"}, "ground");
    ShellSolverOptions& o = scene_.solver;
    o.ground = true;
    if (node["point"]) o.ground_point = src_.vec3(node["point"], "ground.point");
    if (node["normal"]) {
      o.ground_normal = src_.vec3(node["normal"], "ground.normal");
      if (!(o.ground_normal.norm() > 0)) src_.fail(node["normal"], "ground.normal: must not be zero");
      o.ground_normal.normalize();
    }
    if (node["restitution"])
      o.ground_restitution = src_.unitInterval(node["restitution"], "ground.restitution");
    if (node["friction"]) o.ground_friction = src_.unitInterval(node["friction"], "ground.friction");
  }

  void readPins(const YAML::Node& node) {
    src_.forEachEntry(
        node, "pins", "{lo, hi[, velocity]}", [&](const YAML::Node& entry, const std::string& where) {
          src_.allowKeys(entry, {"lo", "hi", "velocity"}, where);
          ShellScenePin pin;
          src_.box(entry, where, &pin.lo, &pin.hi);
          if (entry["velocity"]) pin.velocity = src_.vec3(entry["velocity"], where + ".velocity");
          size_t inside = 0;
          for (const Vec3& p : scene_.surfels.positions)
            inside += (p.array() >= pin.lo.array()).all() && (p.array() <= pin.hi.array()).all();
          if (inside == 0) src_.fail(entry, where + ": the box holds no surfel of the source");
          scene_.pins.push_back(pin);
        });
  }

  void readBalloon(const YAML::Node& node) {
    src_.allowKeys(node, {"pressure", "start_pressure", "ramp_time", "vent_time"}, "balloon");
    ShellSceneBalloon& b = scene_.balloon;
    b.pressure = src_.number(src_.require(node, "pressure", "balloon"), "balloon.pressure");
    if (node["start_pressure"])
      b.start_pressure = src_.number(node["start_pressure"], "balloon.start_pressure");
    if (node["ramp_time"]) b.ramp_time = src_.nonNegative(node["ramp_time"], "balloon.ramp_time");
    if (node["vent_time"]) b.vent_time = src_.nonNegative(node["vent_time"], "balloon.vent_time");
    b.enabled = true;
  }

  void readFrames(const YAML::Node& node) {
    src_.allowKeys(node, {"count", "steps_per_frame", "time"}, "frames");
    scene_.frame_count = int(src_.integer(src_.require(node, "count", "frames"), "frames.count", 1, 1000000));
    if (bool(node["steps_per_frame"]) == bool(node["time"]))
      src_.fail(node, "frames: give exactly one of 'steps_per_frame', 'time'");
    if (node["steps_per_frame"])
      scene_.steps_per_frame =
          int(src_.integer(node["steps_per_frame"], "frames.steps_per_frame", 1, 100000000));
    if (node["time"]) scene_.frame_time = src_.positive(node["time"], "frames.time");
  }

  void readAnalysis(const YAML::Node& root) {
    if (const YAML::Node a = root["analysis"])
      scene_.analysis = src_.choice<ShellAnalysis>(a, "analysis",
                                                   {{"dynamic", ShellAnalysis::kDynamic},
                                                    {"static", ShellAnalysis::kStatic},
                                                    {"modal", ShellAnalysis::kModal}});
    const bool is_static = scene_.analysis == ShellAnalysis::kStatic;
    const bool is_modal = scene_.analysis == ShellAnalysis::kModal;
    if (root["loads"] && is_modal) src_.fail(root["loads"], "loads: for analysis static or dynamic");
    if (root["static"] && !is_static) src_.fail(root["static"], "static: for analysis static");
    if (root["modes"] && !is_modal) src_.fail(root["modes"], "modes: for analysis modal");
    if (root["held"]) readHeld(root["held"]);
    if (root["loads"]) readLoads(root["loads"]);
    if (!is_static && !is_modal)  // dynamic: held components stay where they are (pins move with a velocity)
      for (size_t k = 0; k < scene_.held.size(); ++k)
        if (scene_.held[k].displacement.squaredNorm() > 0)
          src_.fail(root["held"][k],
                    "held[" + std::to_string(k) +
                        "].displacement: for analysis static (dynamic runs move nodes with pins' "
                        "velocity)");
    if (is_static && scene_.held.empty())
      src_.fail(root, "analysis static: give held regions (a free shell has no equilibrium under loads)");
    if (is_static && scene_.loads.empty() && scene_.solver.gravity.squaredNorm() == 0) {
      bool displaced = false;
      for (const ShellSceneHeld& h : scene_.held) displaced = displaced || h.displacement.squaredNorm() > 0;
      if (!displaced)
        src_.fail(root, "analysis static: nothing loads the shell (loads, gravity or a held displacement)");
    }
    if (const YAML::Node s = root["static"]) {
      src_.allowKeys(s, {"load_steps", "max_iterations", "tolerance"}, "static");
      ShellStaticOptions& o = scene_.static_options;
      if (s["load_steps"]) o.load_steps = int(src_.integer(s["load_steps"], "static.load_steps", 1, 100000));
      if (s["max_iterations"])
        o.max_iterations = int(src_.integer(s["max_iterations"], "static.max_iterations", 1, 10000));
      if (s["tolerance"]) o.tolerance = src_.positive(s["tolerance"], "static.tolerance");
    }
    if (root["modes"]) scene_.modes = int(src_.integer(root["modes"], "modes", 1, 1000));
    if (const YAML::Node probes = root["probes"]) {
      if (is_static || is_modal)
        src_.fail(probes, "probes: for analysis dynamic (static runs report in their JSON)");
      readProbes(probes);
    }
  }

  void readProbes(const YAML::Node& node) {
    src_.forEachEntry(node, "probes", "{name, lo, hi}",
                      [&](const YAML::Node& entry, const std::string& where) {
                        src_.allowKeys(entry, {"name", "lo", "hi"}, where);
                        ShellProbe probe;
                        const YAML::Node name = src_.require(entry, "name", where);
                        probe.name = src_.word(name, where + ".name");
                        for (const ShellProbe& other : scene_.probes)
                          if (other.name == probe.name)
                            src_.fail(name, where + ".name: '" + probe.name + "' is taken");
                        src_.box(entry, where, &probe.lo, &probe.hi);
                        requireSurfelIn(entry, where, probe.lo, probe.hi);
                        scene_.probes.push_back(std::move(probe));
                      });
  }

  /// Fails unless the box holds a surfel of the source (the nodes are chosen among them when the run starts).
  void requireSurfelIn(const YAML::Node& entry, const std::string& where, const Vec3& lo,
                       const Vec3& hi) const {
    for (const Vec3& p : scene_.surfels.positions)
      if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) return;
    src_.fail(entry, where + ": the box holds no surfel of the source");
  }

  void readHeld(const YAML::Node& node) {
    src_.forEachEntry(node, "held", "regions {lo, hi, components, displacement}",
                      [&](const YAML::Node& entry, const std::string& where) {
                        src_.allowKeys(entry, {"lo", "hi", "components", "displacement"}, where);
                        ShellSceneHeld held;
                        src_.box(entry, where, &held.lo, &held.hi);
                        requireSurfelIn(entry, where, held.lo, held.hi);
                        if (const YAML::Node c = entry["components"])
                          held.components = src_.components(c, where + ".components");
                        if (entry["displacement"])
                          held.displacement = src_.vec3(entry["displacement"], where + ".displacement");
                        scene_.held.push_back(held);
                      });
  }

  void readLoads(const YAML::Node& node) {
    src_.forEachEntry(node, "loads", "{lo, hi | point, force and / or traction}",
                      [&](const YAML::Node& entry, const std::string& where) {
                        src_.allowKeys(entry, {"lo", "hi", "point", "force", "traction"}, where);
                        ShellSceneLoad load;
                        if (entry["point"]) {
                          if (entry["lo"] || entry["hi"])
                            src_.fail(entry["point"], where + ": give point or lo / hi, not both");
                          load.at_point = true;
                          load.point = src_.vec3(entry["point"], where + ".point");
                          if (entry["traction"])
                            src_.fail(entry["traction"],
                                      where + ".traction: a point load has no area (give force)");
                        } else {
                          src_.box(entry, where, &load.lo, &load.hi);
                          requireSurfelIn(entry, where, load.lo, load.hi);
                        }
                        if (!entry["force"] && !entry["traction"])
                          src_.fail(entry, where + ": give force and / or traction");
                        if (entry["force"]) load.force = src_.vec3(entry["force"], where + ".force");
                        if (entry["traction"])
                          load.traction = src_.vec3(entry["traction"], where + ".traction");
                        scene_.loads.push_back(load);
                      });
  }

  void readOutput(const YAML::Node& node) {
    src_.allowKeys(node, {"every", "surfels", "cracks"}, "output");
    if (node["every"]) scene_.output.every = int(src_.integer(node["every"], "output.every", 0, 1000000));
    if (node["surfels"]) scene_.output.surfels = src_.boolean(node["surfels"], "output.surfels");
    if (node["cracks"]) scene_.output.cracks = src_.boolean(node["cracks"], "output.cracks");
  }

  const YamlReader& src_;
  ShellScene& scene_;
};

}  // namespace

ShellScene parseShellScene(const std::string& yaml_text, const std::string& source_name) {
  const YamlReader src(source_name, &raiseShellSceneError);
  const YAML::Node root = src.parseMap(
      yaml_text, "expected a map of scene keys (source, nodes, material, dynamics, frames, ...)");
  ShellScene scene;
  scene.path = source_name;
  scene.name = std::filesystem::path(source_name).stem().string();
  SceneReader(src, &scene).read(root);
  return scene;
}

ShellScene loadShellScene(const std::string& path) {
  return parseShellScene(YamlReader::readFile(path, &raiseShellSceneError), path);
}

}  // namespace rc
