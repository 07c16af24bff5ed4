#include "relaxed_connectivity/fem/fem_scene_reader.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <Eigen/Geometry>

#include "relaxed_connectivity/fem/fem_cut_polygon.h"
#include "relaxed_connectivity/fem/fem_mesh_source.h"
#include "relaxed_connectivity/fem/fem_scene_regions.h"
#include "relaxed_connectivity/io/yaml_reader.h"

namespace rc {

namespace {

[[noreturn]] void raiseFemSceneError(const std::string& message) {
  throw FemSceneError(message);
}

struct Source : YamlReader {
  explicit Source(std::string name) : YamlReader(std::move(name), &raiseFemSceneError) {}

  std::vector<Vec3> points(const YAML::Node& node, const std::string& what, size_t min_count) const {
    if (!node.IsSequence() || node.size() < min_count)
      fail(node, what + ": expected a list of at least " + std::to_string(min_count) + " points [x, y, z]");
    std::vector<Vec3> out;
    for (size_t i = 0; i < node.size(); ++i)
      out.push_back(vec3(node[i], what + "[" + std::to_string(i) + "]"));
    return out;
  }
};

std::string resolvePath(const std::string& base_dir, const std::string& file) {
  const std::filesystem::path p(file);
  if (p.is_absolute() || base_dir.empty()) return file;
  return (std::filesystem::path(base_dir) / p).string();
}

class SceneReader {
 public:
  SceneReader(const Source& src, FemScene* scene, std::string base_dir)
      : src_(src), scene_(*scene), base_dir_(std::move(base_dir)) {}

  void read(const YAML::Node& root) {
    src_.allowKeys(root,
                   {"name", "mesh", "placement", "material", "dynamics", "ground", "frames", "cuts", "output",
                    "analysis", "held", "loads", "body_acceleration", "modes", "probes", "static"},
                   "scene");
    if (root["name"]) scene_.name = src_.string(root["name"], "name");
    if (const YAML::Node a = root["analysis"])
      scene_.analysis = src_.choice<FemAnalysis>(a, "analysis",
                                                 {{"dynamic", FemAnalysis::kDynamic},
                                                  {"static", FemAnalysis::kStatic},
                                                  {"modal", FemAnalysis::kModal}});
    const bool dynamic = scene_.analysis == FemAnalysis::kDynamic;
    const bool modal = scene_.analysis == FemAnalysis::kModal;
    if (root["body_acceleration"] && dynamic)
      src_.fail(root["body_acceleration"],
                "body_acceleration: only with analysis: static (dynamic runs: dynamics.gravity)");
    for (const char* key : {"loads", "body_acceleration"})
      if (root[key] && modal) src_.fail(root[key], std::string(key) + ": not with analysis: modal");
    if (root["modes"] && !modal) src_.fail(root["modes"], "modes: only with analysis: modal");
    if (const YAML::Node s = root["static"]) {
      if (scene_.analysis != FemAnalysis::kStatic) src_.fail(s, "static: only with analysis: static");
      readStaticOptions(s);
    }
    if (root["probes"] && !dynamic)
      src_.fail(root["probes"],
                "probes: only with analysis: dynamic (static and modal runs report in their JSON)");
    if (root["modes"]) scene_.modes = int(src_.integer(root["modes"], "modes", 1, 1000));
    for (const char* key : {"ground", "cuts"})
      if (root[key] && !dynamic) src_.fail(root[key], std::string(key) + ": only with analysis: dynamic");
    readMaterial(src_.require(root, "material", "scene"));
    if (dynamic || root["dynamics"]) readDynamics(src_.require(root, "dynamics", "scene"));
    if (root["ground"]) readGround(root["ground"]);
    if (dynamic || root["frames"]) readFrames(src_.require(root, "frames", "scene"));
    if (!dynamic) scene_.frame_count = modal ? scene_.modes : 1;  // static: the rest state, the equilibrium
    if (root["cuts"]) readCuts(root["cuts"]);
    if (root["output"]) readOutput(root["output"]);
    const YAML::Node mesh = src_.require(root, "mesh", "scene");
    readMesh(mesh);
    const Placement placement = readPlacement(root["placement"]);
    if (root["body_acceleration"])
      scene_.body_acceleration = src_.vec3(root["body_acceleration"], "body_acceleration");
    // (everything that needs no mesh is checked above; held regions, loads and probes select its nodes)
    PolyhedralMesh built = buildMesh(mesh);
    place(placement, std::move(built), mesh);
    if (root["held"]) readHeld(root["held"], dynamic);
    if (root["loads"]) readLoads(root["loads"]);
    if (root["probes"]) readProbes(root["probes"]);
    if (!dynamic && scene_.held.empty())
      src_.fail(root, std::string("analysis: ") + (modal ? "modal" : "static") +
                          " needs 'held' regions (else the body is free to move rigidly)");
    if (modal)
      for (size_t r = 0; r < scene_.held.size(); ++r)
        if (scene_.held[r].displacement != Vec3::Zero())
          src_.fail(root["held"][r],
                    "held[" + std::to_string(r) + "].displacement: not with analysis: modal");
  }

 private:
  void readMaterial(const YAML::Node& node) {
    src_.allowKeys(node,
                   {"youngs_modulus", "poisson_ratio", "density", "vertex_sample_blend", "face_sample_blend"},
                   "material");
    scene_.youngs_modulus =
        src_.positive(src_.require(node, "youngs_modulus", "material"), "material.youngs_modulus");
    const YAML::Node nu = src_.require(node, "poisson_ratio", "material");
    scene_.poisson_ratio = src_.number(nu, "material.poisson_ratio");
    if (!(scene_.poisson_ratio > -1.0 && scene_.poisson_ratio < 0.5))
      src_.fail(nu, "material.poisson_ratio must be in (-1, 0.5), got " + nu.Scalar());
    if (node["density"]) scene_.density = src_.positive(node["density"], "material.density");
    for (const char* key : {"vertex_sample_blend", "face_sample_blend"}) {
      if (!node[key]) continue;
      const double b = src_.number(node[key], std::string("material.") + key);
      if (!(b > 0.0 && b <= 1.0))
        src_.fail(node[key],
                  std::string("material.") + key + " must be in (0, 1], got " + node[key].Scalar());
      (std::string(key) == "vertex_sample_blend" ? scene_.quadrature.vertex_sample_blend
                                                 : scene_.quadrature.face_sample_blend) = b;
    }
  }

  void readDynamics(const YAML::Node& node) {
    src_.allowKeys(node,
                   {"time_step", "gravity", "stiffness_warping", "mass_damping", "stiffness_damping",
                    "solver", "rotation_weights"},
                   "dynamics");
    WarpedDynamicsOptions& d = scene_.dynamics;
    d.time_step = src_.positive(src_.require(node, "time_step", "dynamics"), "dynamics.time_step");
    if (node["gravity"]) d.gravity = src_.vec3(node["gravity"], "dynamics.gravity");
    if (node["stiffness_warping"])
      d.stiffness_warping = src_.boolean(node["stiffness_warping"], "dynamics.stiffness_warping");
    if (node["mass_damping"])
      d.mass_damping = src_.nonNegative(node["mass_damping"], "dynamics.mass_damping");
    if (node["stiffness_damping"])
      d.stiffness_damping = src_.nonNegative(node["stiffness_damping"], "dynamics.stiffness_damping");
    using Options = WarpedDynamicsOptions;
    if (const YAML::Node w = node["rotation_weights"])
      d.rotation_weights = src_.choice<Options::RotationWeights>(
          w, "dynamics.rotation_weights",
          {{"lumped_masses", Options::RotationWeights::kLumpedMasses},
           {"node_volume_fractions", Options::RotationWeights::kNodeVolumeFractions}});
    if (const YAML::Node s = node["solver"]) {
      src_.allowKeys(s,
                     {"type", "preconditioner", "tolerance", "max_iterations", "warm_start",
                      "refactor_iterations", "extension_iterations", "contact_updates"},
                     "dynamics.solver");
      if (const YAML::Node t = s["type"])
        d.solver = src_.choice<Options::Solver>(t, "dynamics.solver.type",
                                                {{"cg", Options::Solver::kConjugateGradient},
                                                 {"ldlt", Options::Solver::kSimplicialLDLT},
                                                 {"cholmod", Options::Solver::kCholmod},
                                                 {"cholmod_pcg", Options::Solver::kCholmodPcg}});
      if (const YAML::Node p = s["preconditioner"])
        d.preconditioner = src_.choice<Options::Preconditioner>(
            p, "dynamics.solver.preconditioner",
            {{"jacobi", Options::Preconditioner::kJacobi},
             {"incomplete_cholesky", Options::Preconditioner::kIncompleteCholesky}});
      if (s["tolerance"]) d.cg_tolerance = src_.positive(s["tolerance"], "dynamics.solver.tolerance");
      if (s["max_iterations"])
        d.cg_max_iterations =
            int(src_.integer(s["max_iterations"], "dynamics.solver.max_iterations", 1, 1000000));
      if (s["warm_start"]) d.cg_warm_start = src_.boolean(s["warm_start"], "dynamics.solver.warm_start");
      if (s["refactor_iterations"])
        d.pcg_refactor_iterations =
            int(src_.integer(s["refactor_iterations"], "dynamics.solver.refactor_iterations", 1, 1000000));
      if (s["extension_iterations"])
        d.pcg_extension_iterations =
            int(src_.integer(s["extension_iterations"], "dynamics.solver.extension_iterations", 0, 1000000));
      if (s["contact_updates"])
        d.pcg_contact_updates =
            int(src_.integer(s["contact_updates"], "dynamics.solver.contact_updates", 0, 1000000));
    }
  }

  /// The nodes of the placed mesh in the closed box of `node` (keys lo, hi); fails if none is.
  std::vector<int> nodesInBox(const YAML::Node& node, const std::string& where, Vec3* lo, Vec3* hi) const {
    src_.box(node, where, lo, hi);
    const PolyhedralMesh& mesh = *scene_.mesh;
    const double tolerance = femBoxTolerance(mesh);
    std::vector<int> nodes;
    for (int i = 0; i < mesh.numNodes(); ++i)
      if (((mesh.node(i) - *lo).array() >= -tolerance).all() &&
          ((*hi - mesh.node(i)).array() >= -tolerance).all())
        nodes.push_back(i);
    if (nodes.empty()) src_.fail(node, where + ": the box holds no node of the mesh");
    return nodes;
  }

  /// A region's nodes: the box (keys lo, hi) or a node set (key nodes: indices into the placed mesh, then
  /// lo, hi their bounding box and points their rest positions); fails if none is selected.
  std::vector<int> selectedNodes(const YAML::Node& entry, const std::string& where, Vec3* lo, Vec3* hi,
                                 std::vector<Vec3>* points) const {
    const YAML::Node list = entry["nodes"];
    if (!list) return nodesInBox(entry, where, lo, hi);
    if (entry["lo"] || entry["hi"]) src_.fail(list, where + ".nodes: give a box (lo, hi) or nodes, not both");
    if (!list.IsSequence() || list.size() == 0)
      src_.fail(list, where + ".nodes: expected a list of node indices");
    const PolyhedralMesh& mesh = *scene_.mesh;
    std::vector<int> nodes;
    for (size_t k = 0; k < list.size(); ++k) {
      const int i =
          int(src_.integer(list[k], where + ".nodes[" + std::to_string(k) + "]", 0, mesh.numNodes() - 1));
      if (std::find(nodes.begin(), nodes.end(), i) != nodes.end())
        src_.fail(list[k], where + ".nodes: node " + std::to_string(i) + " is listed twice");
      nodes.push_back(i);
      points->push_back(mesh.node(i));
    }
    *lo = *hi = points->front();
    for (const Vec3& p : *points) *lo = lo->cwiseMin(p), *hi = hi->cwiseMax(p);
    return nodes;
  }

  /// Key path: [[t, ux, uy, uz], ...] with increasing times.
  std::vector<std::pair<double, Vec3>> readPath(const YAML::Node& node, const std::string& what) const {
    if (!node.IsSequence() || node.size() == 0)
      src_.fail(node, what + ": expected a list of keyframes [t, ux, uy, uz]");
    std::vector<std::pair<double, Vec3>> path;
    for (size_t k = 0; k < node.size(); ++k) {
      const std::string key = what + "[" + std::to_string(k) + "]";
      const YAML::Node row = node[k];
      if (!row.IsSequence() || row.size() != 4) src_.fail(row, key + ": expected [t, ux, uy, uz]");
      const double t = src_.number(row[0], key + ".t");
      if (!path.empty() && !(t > path.back().first))
        src_.fail(row[0], key + ": times must increase (" + std::to_string(t) + " after " +
                              std::to_string(path.back().first) + ")");
      path.emplace_back(t, Vec3(src_.number(row[1], key + ".ux"), src_.number(row[2], key + ".uy"),
                                src_.number(row[3], key + ".uz")));
    }
    return path;
  }

  void readHeld(const YAML::Node& node, bool dynamic) {
    src_.forEachEntry(
        node, "held", "regions {lo, hi | nodes, components, displacement | path}",
        [&](const YAML::Node& entry, const std::string& where) {
          src_.allowKeys(entry, {"lo", "hi", "nodes", "components", "displacement", "path"}, where);
          FemHeldRegion region;
          region.nodes = selectedNodes(entry, where, &region.lo, &region.hi, &region.points);
          if (const YAML::Node c = entry["components"])
            region.components = src_.components(c, where + ".components");
          if (entry["displacement"] && entry["path"])
            src_.fail(entry["path"], where + ".path: give displacement or path, not both");
          if (entry["displacement"])
            region.displacement = src_.vec3(entry["displacement"], where + ".displacement");
          if (const YAML::Node p = entry["path"]) {
            if (!dynamic) src_.fail(p, where + ".path: only with analysis: dynamic");
            region.path = readPath(p, where + ".path");
          }
          for (const FemHeldRegion& other : scene_.held)
            for (int k = 0; k < 3; ++k)
              if (other.components[size_t(k)] && region.components[size_t(k)])
                for (int i : region.nodes)
                  if (std::find(other.nodes.begin(), other.nodes.end(), i) != other.nodes.end())
                    src_.fail(entry, where + ": node " + std::to_string(i) + " already holds " +
                                         std::string(1, char('x' + k)) + " in an earlier region");
          scene_.held.push_back(std::move(region));
        });
  }

  void readLoads(const YAML::Node& node) {
    src_.forEachEntry(
        node, "loads", "{lo, hi | nodes, force | traction}",
        [&](const YAML::Node& entry, const std::string& where) {
          src_.allowKeys(entry, {"lo", "hi", "nodes", "force", "traction"}, where);
          FemLoad load;
          load.nodes = selectedNodes(entry, where, &load.lo, &load.hi, &load.points);
          if (entry["force"] && entry["traction"])
            src_.fail(entry["traction"], where + ".traction: give force or traction, not both");
          if (const YAML::Node t = entry["traction"]) {
            load.is_traction = true;
            load.force = src_.vec3(t, where + ".traction");
            double area = 0.0;
            femTractionForces(*scene_.mesh, load, femBoxTolerance(*scene_.mesh), &area);
            if (!(area > 0.0))
              src_.fail(entry,
                        where + ": no boundary face lies in the box or node set (a traction needs one)");
          } else {
            load.force = src_.vec3(src_.require(entry, "force", where), where + ".force");
          }
          scene_.loads.push_back(std::move(load));
        });
  }

  void readProbes(const YAML::Node& node) {
    src_.forEachEntry(node, "probes", "{name, lo, hi}",
                      [&](const YAML::Node& entry, const std::string& where) {
                        src_.allowKeys(entry, {"name", "lo", "hi"}, where);
                        FemProbe probe;
                        const YAML::Node name = src_.require(entry, "name", where);
                        probe.name = src_.word(name, where + ".name");
                        for (const FemProbe& other : scene_.probes)
                          if (other.name == probe.name)
                            src_.fail(name, where + ".name: '" + probe.name + "' is taken");
                        nodesInBox(entry, where, &probe.lo, &probe.hi);  // fails for a box without nodes
                        scene_.probes.push_back(std::move(probe));
                      });
  }

  void readStaticOptions(const YAML::Node& node) {
    src_.allowKeys(node, {"corotational", "load_steps", "max_iterations", "tolerance"}, "static");
    FemStaticOptions& o = scene_.static_options;
    if (node["corotational"]) o.corotational = src_.boolean(node["corotational"], "static.corotational");
    if (node["load_steps"])
      o.load_steps = int(src_.integer(node["load_steps"], "static.load_steps", 1, 100000));
    if (node["max_iterations"])
      o.max_iterations = int(src_.integer(node["max_iterations"], "static.max_iterations", 1, 1000000));
    if (node["tolerance"]) o.tolerance = src_.positive(node["tolerance"], "static.tolerance");
    if (!o.corotational)
      for (const char* key : {"load_steps", "max_iterations", "tolerance"})
        if (node[key])
          src_.fail(node[key], std::string("static.") + key + ": only with static.corotational: true");
  }

  void readGround(const YAML::Node& node) {
    src_.allowKeys(node, {"normal", "offset", "friction"}, "ground");
    GroundPlane& g = scene_.dynamics.ground;
    g.enabled = true;
    if (const YAML::Node n = node["normal"]) {
      g.normal = src_.vec3(n, "ground.normal");
      if (!(g.normal.norm() > 0)) src_.fail(n, "ground.normal must be non-zero");
      g.normal.normalize();
    }
    if (node["offset"]) g.offset = src_.number(node["offset"], "ground.offset");
    if (node["friction"]) g.friction = src_.nonNegative(node["friction"], "ground.friction");
  }

  void readFrames(const YAML::Node& node) {
    src_.allowKeys(node, {"count", "steps_per_frame"}, "frames");
    scene_.frame_count =
        int(src_.integer(src_.require(node, "count", "frames"), "frames.count", 1, 10000000));
    if (node["steps_per_frame"])
      scene_.steps_per_frame =
          int(src_.integer(node["steps_per_frame"], "frames.steps_per_frame", 1, 10000000));
  }

  void readCuts(const YAML::Node& node) {
    if (!node.IsSequence()) src_.fail(node, "cuts: expected a list of plane or polygon cuts");
    for (size_t i = 0; i < node.size(); ++i) {
      const std::string where = "cuts[" + std::to_string(i) + "]";
      const YAML::Node c = node[i];
      FemSceneCut cut;
      if (c.IsMap() && (c["polygons"] || c["blade"])) {
        src_.allowKeys(c,
                       {"time", "duration", "polygons", "blade", "path", "snap_relative_distance",
                        "sliver_relative_thickness"},
                       where);
        cut.time = src_.nonNegative(src_.require(c, "time", where), where + ".time");
        if (c["duration"]) cut.duration = src_.nonNegative(c["duration"], where + ".duration");
        if (const YAML::Node polygons = c["polygons"]) {
          if (c["blade"] || c["path"]) src_.fail(c, where + ": give either polygons or blade + path");
          if (!polygons.IsSequence() || polygons.size() == 0)
            src_.fail(polygons, where + ".polygons: expected a list of polygons (lists of points)");
          for (size_t k = 0; k < polygons.size(); ++k)
            cut.polygons.push_back(
                src_.points(polygons[k], where + ".polygons[" + std::to_string(k) + "]", 3));
        } else {
          const std::vector<Vec3> blade = src_.points(c["blade"], where + ".blade", 2);
          if (blade.size() != 2)
            src_.fail(c["blade"], where + ".blade: expected two points (the cutting edge)");
          const YAML::Node path = src_.require(c, "path", where);
          try {
            cut.polygons = bladeSweepPolygons(blade[0], blade[1], src_.points(path, where + ".path", 2));
          } catch (const std::invalid_argument& e) {
            src_.fail(path, where + ": " + e.what());
          }
        }
        for (size_t k = 0; k < cut.polygons.size(); ++k) {
          const std::vector<Vec3>& poly = cut.polygons[k];
          Vec3 normal = Vec3::Zero(), center = Vec3::Zero();
          double scale = 0.0;
          for (size_t j = 0; j < poly.size(); ++j) {
            normal += poly[j].cross(poly[(j + 1) % poly.size()]);
            center += poly[j] / double(poly.size());
            scale = std::max(scale, (poly[j] - poly[0]).norm());
          }
          if (!(normal.norm() > 1e-12 * scale * scale))
            src_.fail(c, where + ": polygon " + std::to_string(k) + " has zero area");
          normal.normalize();
          for (const Vec3& p : poly)
            if (std::abs(normal.dot(p - center)) > 1e-9 * scale)
              src_.fail(c, where + ": polygon " + std::to_string(k) + " is not planar");
        }
      } else {
        src_.allowKeys(c,
                       {"time", "point", "normal", "region", "separate", "snap_relative_distance",
                        "sliver_relative_thickness"},
                       where);
        cut.time = src_.nonNegative(src_.require(c, "time", where), where + ".time");
        cut.point = src_.vec3(src_.require(c, "point", where), where + ".point");
        const YAML::Node n = src_.require(c, "normal", where);
        cut.normal = src_.vec3(n, where + ".normal");
        if (!(cut.normal.norm() > 0)) src_.fail(n, where + ".normal must be non-zero");
        cut.normal.normalize();
        if (const YAML::Node r = c["region"]) {
          cut.region = src_.points(r, where + ".region", 3);
          for (size_t k = 0; k < cut.region.size(); ++k)
            if (std::abs(cut.normal.dot(cut.region[k] - cut.point)) > 1e-9 * (1.0 + cut.region[k].norm()))
              src_.fail(r[k], where + ".region[" + std::to_string(k) + "] does not lie in the cut plane");
        }
        if (c["separate"]) cut.separate = src_.boolean(c["separate"], where + ".separate");
      }
      if (c["snap_relative_distance"])
        cut.snap_relative_distance =
            src_.nonNegative(c["snap_relative_distance"], where + ".snap_relative_distance");
      if (const YAML::Node t = c["sliver_relative_thickness"]) {
        const double value = src_.nonNegative(t, where + ".sliver_relative_thickness");
        if (!(value < 1.0)) src_.fail(t, where + ".sliver_relative_thickness must be below 1 (0: off)");
        cut.slivers.enabled = value > 0.0;
        cut.slivers.relative_thickness = value;
      }
      scene_.cuts.push_back(cut);
    }
    std::stable_sort(scene_.cuts.begin(), scene_.cuts.end(),
                     [](const FemSceneCut& a, const FemSceneCut& b) { return a.time < b.time; });
  }

  void readOutput(const YAML::Node& node) {
    src_.allowKeys(node, {"every", "vtu", "obj", "encoding"}, "output");
    FemSceneOutput& o = scene_.output;
    if (node["every"]) o.every = int(src_.integer(node["every"], "output.every", 0, 10000000));
    if (node["vtu"]) o.vtu = src_.boolean(node["vtu"], "output.vtu");
    if (node["obj"]) o.obj = src_.boolean(node["obj"], "output.obj");
    if (const YAML::Node e = node["encoding"])
      o.encoding = src_.choice<VtuEncoding>(
          e, "output.encoding", {{"ascii", VtuEncoding::kAscii}, {"appended", VtuEncoding::kAppendedRaw}});
  }

  void readCells(const YAML::Node& node, FemMeshSource& s) {
    const YAML::Node c = node["cells"];
    if (!c) return;
    if (!c.IsSequence() || c.size() != 3) src_.fail(c, "mesh.cells: expected [nx, ny, nz]");
    for (int k = 0; k < 3; ++k) s.cells[k] = int(src_.integer(c[k], "mesh.cells", 1, 1000));
  }

  void readBox(const YAML::Node& node, FemMeshSource& s) {
    s.lo = src_.vec3(src_.require(node, "lo", "mesh"), "mesh.lo");
    s.hi = src_.vec3(src_.require(node, "hi", "mesh"), "mesh.hi");
    for (int k = 0; k < 3; ++k)
      if (!(s.lo[k] < s.hi[k])) src_.fail(node["hi"], "mesh: hi must exceed lo in every coordinate");
    readCells(node, s);
  }

  void readMesh(const YAML::Node& node) {
    FemMeshSource& s = scene_.source;
    const YAML::Node type_node = src_.require(node, "type", "mesh");
    s.type = src_.choice<FemMeshType>(type_node, "mesh.type",
                                      {{"convex_hull", FemMeshType::kConvexHull},
                                       {"hex_grid", FemMeshType::kHexGrid},
                                       {"tet_grid", FemMeshType::kTetGrid},
                                       {"random_planes", FemMeshType::kRandomPlanes},
                                       {"random_splits", FemMeshType::kRandomSplits},
                                       {"tetgen_surface", FemMeshType::kTetgenSurface},
                                       {"tetgen_files", FemMeshType::kTetgenFiles}});
    switch (s.type) {
      case FemMeshType::kConvexHull:
        src_.allowKeys(node, {"type", "points"}, "mesh");
        s.points = src_.points(src_.require(node, "points", "mesh"), "mesh.points", 4);
        break;
      case FemMeshType::kHexGrid:
      case FemMeshType::kTetGrid:
        src_.allowKeys(node, {"type", "lo", "hi", "cells", "split", "face_diagonals"}, "mesh");
        readBox(node, s);
        if (const YAML::Node d = node["face_diagonals"]) {
          if (s.type != FemMeshType::kHexGrid) src_.fail(d, "mesh.face_diagonals: only for type hex_grid");
          s.face_diagonals = src_.choice<PolyhedralMesh::FaceDiagonals>(
              d, "mesh.face_diagonals",
              {{"fan", PolyhedralMesh::FaceDiagonals::kFan},
               {"symmetric", PolyhedralMesh::FaceDiagonals::kMirrorSymmetric}});
        }
        if (const YAML::Node sp = node["split"]) {
          if (s.type != FemMeshType::kTetGrid) src_.fail(sp, "mesh.split: only for type tet_grid");
          const long n = src_.integer(sp, "mesh.split", 5, 6);
          s.split = n == 5 ? PolyhedralMesh::TetrahedronSplit::kFive : PolyhedralMesh::TetrahedronSplit::kSix;
        }
        break;
      case FemMeshType::kRandomPlanes:
      case FemMeshType::kRandomSplits:
        src_.allowKeys(node, {"type", "lo", "hi", "cells", "planes", "seed", "min_relative_gap"}, "mesh");
        readBox(node, s);
        s.planes = int(src_.integer(src_.require(node, "planes", "mesh"), "mesh.planes", 0, 100000));
        if (node["seed"]) s.seed = unsigned(src_.integer(node["seed"], "mesh.seed", 0, 4294967295L));
        if (node["min_relative_gap"]) {
          s.min_relative_gap = src_.nonNegative(node["min_relative_gap"], "mesh.min_relative_gap");
          if (!(s.min_relative_gap < 0.5))
            src_.fail(node["min_relative_gap"], "mesh.min_relative_gap must be < 0.5");
        }
        break;
      case FemMeshType::kTetgenSurface:
        src_.allowKeys(node,
                       {"type", "surface", "size", "max_volume", "max_radius_edge_ratio",
                        "min_dihedral_degrees", "close_holes", "decimate_vertices"},
                       "mesh");
        s.surface =
            resolvePath(base_dir_, src_.string(src_.require(node, "surface", "mesh"), "mesh.surface"));
        if (node["size"]) s.size = src_.positive(node["size"], "mesh.size");
        if (node["max_volume"]) s.max_volume = src_.nonNegative(node["max_volume"], "mesh.max_volume");
        if (node["max_radius_edge_ratio"])
          s.max_radius_edge_ratio =
              src_.nonNegative(node["max_radius_edge_ratio"], "mesh.max_radius_edge_ratio");
        if (node["min_dihedral_degrees"])
          s.min_dihedral_degrees =
              src_.nonNegative(node["min_dihedral_degrees"], "mesh.min_dihedral_degrees");
        if (node["close_holes"]) s.close_holes = src_.boolean(node["close_holes"], "mesh.close_holes");
        if (node["decimate_vertices"])
          s.decimate_vertices =
              int(src_.integer(node["decimate_vertices"], "mesh.decimate_vertices", 4, 100000000));
        break;
      case FemMeshType::kTetgenFiles:
        src_.allowKeys(node, {"type", "node", "ele"}, "mesh");
        s.node_file = resolvePath(base_dir_, src_.string(src_.require(node, "node", "mesh"), "mesh.node"));
        s.ele_file = resolvePath(base_dir_, src_.string(src_.require(node, "ele", "mesh"), "mesh.ele"));
        break;
    }
  }

  PolyhedralMesh buildMesh(const YAML::Node& node) {
    try {
      return buildFemMesh(scene_.source);
    } catch (const std::exception& e) {
      src_.fail(node, std::string("mesh: ") + e.what());
    }
  }

  /// placement: {translation, rotation: {axis, degrees}, velocity, angular_velocity}; the rotation turns the
  /// mesh about its volume centroid, then it is translated; velocities are those of a rigid motion about the
  /// placed centroid.
  struct Placement {
    Vec3 translation = Vec3::Zero(), velocity = Vec3::Zero(), angular = Vec3::Zero();
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  };

  /// placement's keys and values, checked before the mesh is built (building can take long: a file with a
  /// bad key fails at once).
  Placement readPlacement(const YAML::Node& node) {
    Placement p;
    Vec3& translation = p.translation;
    Vec3& velocity = p.velocity;
    Vec3& angular = p.angular;
    Eigen::Matrix3d& rotation = p.rotation;
    if (node) {
      src_.allowKeys(node, {"translation", "rotation", "velocity", "angular_velocity"}, "placement");
      if (node["translation"]) translation = src_.vec3(node["translation"], "placement.translation");
      if (const YAML::Node r = node["rotation"]) {
        src_.allowKeys(r, {"axis", "degrees"}, "placement.rotation");
        const YAML::Node axis_node = src_.require(r, "axis", "placement.rotation");
        const Vec3 axis = src_.vec3(axis_node, "placement.rotation.axis");
        if (!(axis.norm() > 0)) src_.fail(axis_node, "placement.rotation.axis must be non-zero");
        const double degrees =
            src_.number(src_.require(r, "degrees", "placement.rotation"), "placement.rotation.degrees");
        rotation = Eigen::AngleAxisd(degrees * M_PI / 180.0, axis.normalized()).toRotationMatrix();
      }
      if (node["velocity"]) velocity = src_.vec3(node["velocity"], "placement.velocity");
      if (node["angular_velocity"])
        angular = src_.vec3(node["angular_velocity"], "placement.angular_velocity");
    }
    return p;
  }

  void place(const Placement& p, PolyhedralMesh mesh, const YAML::Node& mesh_node) {
    const Vec3 &translation = p.translation, &velocity = p.velocity, &angular = p.angular;
    const Eigen::Matrix3d& rotation = p.rotation;
    Vec3 centroid = Vec3::Zero();
    for (const ConvexPolyhedron& e : mesh.elements()) centroid += e.volume() * e.centroid();
    centroid /= mesh.volume();
    std::vector<Vec3> nodes(mesh.numNodes());
    for (int i = 0; i < mesh.numNodes(); ++i)
      nodes[i] = rotation * (mesh.node(i) - centroid) + centroid + translation;
    std::vector<PolyhedralMesh::ElementFaces> elements(mesh.numElements());
    for (int e = 0; e < mesh.numElements(); ++e) elements[e] = mesh.elementFaces(e);
    try {
      // The same face triangulations (given ones, e.g. mesh.face_diagonals, stay).
      scene_.mesh =
          std::make_shared<const PolyhedralMesh>(nodes, std::move(elements), mesh.elementFaceTriangles());
    } catch (const std::exception& e) {
      src_.fail(mesh_node, std::string("mesh after placement: ") + e.what());
    }
    const Vec3 placed_centroid = centroid + translation;
    scene_.initial_velocities.resize(nodes.size());
    for (size_t i = 0; i < nodes.size(); ++i)
      scene_.initial_velocities[i] = velocity + angular.cross(nodes[i] - placed_centroid);
  }

  const Source& src_;
  FemScene& scene_;
  std::string base_dir_;
};

}  // namespace

FemScene parseFemScene(const std::string& yaml_text, const std::string& source_name,
                       const std::string& base_dir) {
  const Source src{source_name};
  const YAML::Node root =
      src.parseMap(yaml_text, "expected a map of scene keys (mesh, material, dynamics, frames, ...)");
  FemScene scene;
  scene.path = source_name;
  scene.name = std::filesystem::path(source_name).stem().string();
  SceneReader(src, &scene, base_dir).read(root);
  return scene;
}

FemScene loadFemScene(const std::string& path) {
  return parseFemScene(YamlReader::readFile(path, &raiseFemSceneError), path,
                       std::filesystem::path(path).parent_path().string());
}

}  // namespace rc
