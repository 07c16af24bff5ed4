#include "fem/fem_scene.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include <Eigen/Geometry>

#include "fem/polygon_cut.h"
#include "fem/tetgen_mesh.h"
#include "io/obj_io.h"
#include "io/off_io.h"
#include "io/ply_io.h"
#include "io/pvd_io.h"
#include "io/yaml_reader.h"
#include "mesh/surface_closing.h"
#include "mesh/surface_decimation.h"

namespace rc {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

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
    src_.allowKeys(
        root, {"name", "mesh", "placement", "material", "dynamics", "ground", "frames", "cuts", "output"},
        "scene");
    if (root["name"]) scene_.name = src_.string(root["name"], "name");
    readMaterial(src_.require(root, "material", "scene"));
    readDynamics(src_.require(root, "dynamics", "scene"));
    if (root["ground"]) readGround(root["ground"]);
    readFrames(src_.require(root, "frames", "scene"));
    if (root["cuts"]) readCuts(root["cuts"]);
    if (root["output"]) readOutput(root["output"]);
    const YAML::Node mesh = src_.require(root, "mesh", "scene");
    readMesh(mesh);
    PolyhedralMesh built = buildMesh(mesh);
    place(root["placement"], std::move(built), mesh);
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
    if (const YAML::Node w = node["rotation_weights"]) {
      const std::string s = src_.string(w, "dynamics.rotation_weights");
      if (s == "lumped_masses")
        d.rotation_weights = WarpedDynamicsOptions::RotationWeights::kLumpedMasses;
      else if (s == "node_volume_fractions")
        d.rotation_weights = WarpedDynamicsOptions::RotationWeights::kNodeVolumeFractions;
      else
        src_.fail(w, "dynamics.rotation_weights: unknown '" + s +
                         "' (known: lumped_masses, node_volume_fractions)");
    }
    if (const YAML::Node s = node["solver"]) {
      src_.allowKeys(s,
                     {"type", "preconditioner", "tolerance", "max_iterations", "warm_start",
                      "refactor_iterations", "extension_iterations", "contact_updates"},
                     "dynamics.solver");
      if (const YAML::Node t = s["type"]) {
        const std::string type = src_.string(t, "dynamics.solver.type");
        if (type == "cg")
          d.solver = WarpedDynamicsOptions::Solver::kConjugateGradient;
        else if (type == "ldlt")
          d.solver = WarpedDynamicsOptions::Solver::kSimplicialLDLT;
        else if (type == "cholmod")
          d.solver = WarpedDynamicsOptions::Solver::kCholmod;
        else if (type == "cholmod_pcg")
          d.solver = WarpedDynamicsOptions::Solver::kCholmodPcg;
        else
          src_.fail(t,
                    "dynamics.solver.type: unknown '" + type + "' (known: cg, ldlt, cholmod, cholmod_pcg)");
      }
      if (const YAML::Node p = s["preconditioner"]) {
        const std::string name = src_.string(p, "dynamics.solver.preconditioner");
        if (name == "jacobi")
          d.preconditioner = WarpedDynamicsOptions::Preconditioner::kJacobi;
        else if (name == "incomplete_cholesky")
          d.preconditioner = WarpedDynamicsOptions::Preconditioner::kIncompleteCholesky;
        else
          src_.fail(p, "dynamics.solver.preconditioner: unknown '" + name +
                           "' (known: jacobi, incomplete_cholesky)");
      }
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
    if (const YAML::Node e = node["encoding"]) {
      const std::string s = src_.string(e, "output.encoding");
      if (s == "ascii")
        o.encoding = VtuEncoding::kAscii;
      else if (s == "appended")
        o.encoding = VtuEncoding::kAppendedRaw;
      else
        src_.fail(e, "output.encoding: unknown '" + s + "' (known: ascii, appended)");
    }
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
    const std::string type = src_.string(type_node, "mesh.type");
    if (type == "convex_hull") {
      src_.allowKeys(node, {"type", "points"}, "mesh");
      s.type = FemMeshType::kConvexHull;
      s.points = src_.points(src_.require(node, "points", "mesh"), "mesh.points", 4);
    } else if (type == "hex_grid" || type == "tet_grid") {
      src_.allowKeys(node, {"type", "lo", "hi", "cells", "split"}, "mesh");
      s.type = type == "hex_grid" ? FemMeshType::kHexGrid : FemMeshType::kTetGrid;
      readBox(node, s);
      if (const YAML::Node sp = node["split"]) {
        if (s.type != FemMeshType::kTetGrid) src_.fail(sp, "mesh.split: only for type tet_grid");
        const long n = src_.integer(sp, "mesh.split", 5, 6);
        s.split = n == 5 ? PolyhedralMesh::TetrahedronSplit::kFive : PolyhedralMesh::TetrahedronSplit::kSix;
      }
    } else if (type == "random_planes" || type == "random_splits") {
      src_.allowKeys(node, {"type", "lo", "hi", "cells", "planes", "seed", "min_relative_gap"}, "mesh");
      s.type = type == "random_planes" ? FemMeshType::kRandomPlanes : FemMeshType::kRandomSplits;
      readBox(node, s);
      s.planes = int(src_.integer(src_.require(node, "planes", "mesh"), "mesh.planes", 0, 100000));
      if (node["seed"]) s.seed = unsigned(src_.integer(node["seed"], "mesh.seed", 0, 4294967295L));
      if (node["min_relative_gap"]) {
        s.min_relative_gap = src_.nonNegative(node["min_relative_gap"], "mesh.min_relative_gap");
        if (!(s.min_relative_gap < 0.5))
          src_.fail(node["min_relative_gap"], "mesh.min_relative_gap must be < 0.5");
      }
    } else if (type == "tetgen_surface") {
      src_.allowKeys(node,
                     {"type", "surface", "size", "max_volume", "max_radius_edge_ratio",
                      "min_dihedral_degrees", "close_holes", "decimate_vertices"},
                     "mesh");
      s.type = FemMeshType::kTetgenSurface;
      s.surface = resolvePath(base_dir_, src_.string(src_.require(node, "surface", "mesh"), "mesh.surface"));
      if (node["size"]) s.size = src_.positive(node["size"], "mesh.size");
      if (node["max_volume"]) s.max_volume = src_.nonNegative(node["max_volume"], "mesh.max_volume");
      if (node["max_radius_edge_ratio"])
        s.max_radius_edge_ratio =
            src_.nonNegative(node["max_radius_edge_ratio"], "mesh.max_radius_edge_ratio");
      if (node["min_dihedral_degrees"])
        s.min_dihedral_degrees = src_.nonNegative(node["min_dihedral_degrees"], "mesh.min_dihedral_degrees");
      if (node["close_holes"]) s.close_holes = src_.boolean(node["close_holes"], "mesh.close_holes");
      if (node["decimate_vertices"])
        s.decimate_vertices =
            int(src_.integer(node["decimate_vertices"], "mesh.decimate_vertices", 4, 100000000));
    } else if (type == "tetgen_files") {
      src_.allowKeys(node, {"type", "node", "ele"}, "mesh");
      s.type = FemMeshType::kTetgenFiles;
      s.node_file = resolvePath(base_dir_, src_.string(src_.require(node, "node", "mesh"), "mesh.node"));
      s.ele_file = resolvePath(base_dir_, src_.string(src_.require(node, "ele", "mesh"), "mesh.ele"));
    } else {
      src_.fail(type_node, "mesh.type: unknown '" + type +
                               "' (known: convex_hull, hex_grid, tet_grid, random_planes, random_splits, "
                               "tetgen_surface, tetgen_files)");
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
  void place(const YAML::Node& node, PolyhedralMesh mesh, const YAML::Node& mesh_node) {
    Vec3 translation = Vec3::Zero(), velocity = Vec3::Zero(), angular = Vec3::Zero();
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
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
    Vec3 centroid = Vec3::Zero();
    for (const ConvexPolyhedron& e : mesh.elements()) centroid += e.volume() * e.centroid();
    centroid /= mesh.volume();
    std::vector<Vec3> nodes(mesh.numNodes());
    for (int i = 0; i < mesh.numNodes(); ++i)
      nodes[i] = rotation * (mesh.node(i) - centroid) + centroid + translation;
    std::vector<PolyhedralMesh::ElementFaces> elements(mesh.numElements());
    for (int e = 0; e < mesh.numElements(); ++e) elements[e] = mesh.elementFaces(e);
    try {
      scene_.mesh = std::make_shared<const PolyhedralMesh>(nodes, std::move(elements));
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

TriangleMesh readSurface(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".obj") return readObjMesh(path);
  if (ext == ".off") return readOffMesh(path);
  if (ext == ".ply") return readPlyMesh(path);
  throw std::invalid_argument(path + ": unknown surface format (expected .obj, .off or .ply)");
}

std::string formatNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out + "\"";
}

}  // namespace

PolyhedralMesh randomElementSplits(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz, int num_splits,
                                   unsigned seed, double min_relative_gap) {
  PolyhedralMesh mesh = PolyhedralMesh::hexahedralGrid(lo, hi, nx, ny, nz);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gaussian;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double gap = min_relative_gap * (hi - lo).norm();
  for (int split = 0; split < num_splits; ++split) {
    bool done = false;
    for (int attempt = 0; attempt < 1000 && !done; ++attempt) {
      // Element with probability proportional to its volume.
      double pick = uniform(rng) * mesh.volume();
      int e = 0;
      for (; e + 1 < mesh.numElements(); ++e) {
        pick -= mesh.element(e).volume();
        if (pick <= 0) break;
      }
      const ConvexPolyhedron& element = mesh.element(e);
      Vec3 normal(gaussian(rng), gaussian(rng), gaussian(rng));
      if (!(normal.norm() > 1e-6)) continue;
      normal.normalize();
      double min_d = INFINITY, max_d = -INFINITY;
      for (const Vec3& x : element.nodes()) {
        min_d = std::min(min_d, normal.dot(x - element.centroid()));
        max_d = std::max(max_d, normal.dot(x - element.centroid()));
      }
      const Vec3 point =
          element.centroid() + (0.3 * (2.0 * uniform(rng) - 1.0)) * std::min(-min_d, max_d) * normal;
      bool near = false;
      for (const Vec3& x : element.nodes()) near = near || std::abs(normal.dot(x - point)) < gap;
      if (near) continue;
      // A small triangle around the point selects the chosen element only.
      const double inside = -element.maxFacePlaneDistance(point);
      if (!(inside > 4.0 * element.tolerance())) continue;
      const Vec3 e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
      PlaneCutOptions options;
      const double r = 0.25 * inside;
      for (int k = 0; k < 3; ++k) {
        const double angle = 2.0 * M_PI * k / 3.0;
        options.region.push_back(point + r * (std::cos(angle) * e1 + std::sin(angle) * e2));
      }
      try {
        PlaneCutResult cut = cutMeshByPlane(mesh, {}, point, normal, options);
        if (cut.num_split_elements != 1) continue;
        mesh = std::move(cut.mesh);
        done = true;
      } catch (const std::exception&) {
        continue;  // an invalid result (e.g. a near-degenerate part): draw again
      }
    }
    if (!done)
      throw std::runtime_error("randomElementSplits: no admissible plane for split " + std::to_string(split) +
                               " in 1000 draws (lower min_relative_gap)");
  }
  return mesh;
}

PolyhedralMesh buildFemMesh(const FemMeshSource& s) {
  switch (s.type) {
    case FemMeshType::kConvexHull: {
      const ConvexPolyhedron hull = ConvexPolyhedron::convexHull(s.points);
      std::vector<PolyhedralMesh::ElementFaces> elements(1);
      for (const ConvexPolyhedron::Face& f : hull.faces()) elements[0].push_back(f);
      return PolyhedralMesh(hull.nodes(), std::move(elements));
    }
    case FemMeshType::kHexGrid:
      return PolyhedralMesh::hexahedralGrid(s.lo, s.hi, s.cells[0], s.cells[1], s.cells[2]);
    case FemMeshType::kTetGrid:
      return PolyhedralMesh::tetrahedralGrid(s.lo, s.hi, s.cells[0], s.cells[1], s.cells[2], s.split);
    case FemMeshType::kRandomPlanes:
      return PolyhedralMesh::randomPlaneCut(s.lo, s.hi, s.cells[0], s.cells[1], s.cells[2], s.planes, s.seed,
                                            s.min_relative_gap);
    case FemMeshType::kRandomSplits:
      return randomElementSplits(s.lo, s.hi, s.cells[0], s.cells[1], s.cells[2], s.planes, s.seed,
                                 s.min_relative_gap);
    case FemMeshType::kTetgenSurface: {
      TriangleMesh surface = readSurface(s.surface);
      if (s.close_holes) surface = closeSurfaceHoles(surface);
      if (s.decimate_vertices > 0) {
        DecimationOptions decimation;
        decimation.target_vertices = s.decimate_vertices;
        surface = decimateSurface(surface, decimation);
      }
      std::vector<Vec3>& x = surface.vertices.positions;
      if (s.size > 0 && !x.empty()) {  // centre the bounding box at the origin, scale its diagonal to size
        Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
        for (const Vec3& p : x) {
          lo = lo.cwiseMin(p);
          hi = hi.cwiseMax(p);
        }
        const double scale = s.size / (hi - lo).norm();
        for (Vec3& p : x) p = (p - 0.5 * (lo + hi)) * scale;
      }
      TetgenOptions options;
      options.max_volume = s.max_volume;
      options.max_radius_edge_ratio = s.max_radius_edge_ratio;
      options.min_dihedral_degrees = s.min_dihedral_degrees;
      return toPolyhedralMesh(tetrahedralizeSurface(surface, options));
    }
    case FemMeshType::kTetgenFiles:
      return toPolyhedralMesh(readTetgenMesh(s.node_file, s.ele_file));
  }
  throw std::invalid_argument("buildFemMesh: unknown mesh type");
}

FemScene parseFemScene(const std::string& yaml_text, const std::string& source_name,
                       const std::string& base_dir) {
  const Source src{source_name};
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw FemSceneError(source_name + ":" + std::to_string(e.mark.line + 1) + ":" +
                        std::to_string(e.mark.column + 1) + ": YAML syntax: " + e.msg);
  }
  if (!root.IsMap()) src.fail(root, "expected a map of scene keys (mesh, material, dynamics, frames, ...)");
  FemScene scene;
  scene.path = source_name;
  scene.name = std::filesystem::path(source_name).stem().string();
  SceneReader(src, &scene, base_dir).read(root);
  return scene;
}

FemScene loadFemScene(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FemSceneError(path + ": cannot open the scene file");
  std::stringstream text;
  text << in.rdbuf();
  return parseFemScene(text.str(), path, std::filesystem::path(path).parent_path().string());
}

std::vector<std::vector<Vec3>> bladeSweepPolygons(const Vec3& blade_start, const Vec3& blade_end,
                                                  const std::vector<Vec3>& path) {
  if (path.size() < 2)
    throw std::invalid_argument("blade sweep: the path needs at least 2 points, got " +
                                std::to_string(path.size()));
  const Vec3 blade = blade_end - blade_start;
  if (!(blade.norm() > 0.0) || !blade.allFinite())
    throw std::invalid_argument("blade sweep: the blade has zero length");
  std::vector<std::vector<Vec3>> polygons;
  for (size_t k = 0; k + 1 < path.size(); ++k) {
    const Vec3 step = path[k + 1] - path[k];
    if (!(blade.cross(step).norm() > 1e-9 * blade.norm() * step.norm()) || !(step.norm() > 0.0))
      throw std::invalid_argument("blade sweep: path step " + std::to_string(k) +
                                  " is zero or parallel to the blade");
    polygons.push_back(
        {blade_start + path[k], blade_end + path[k], blade_end + path[k + 1], blade_start + path[k + 1]});
  }
  return polygons;
}

std::vector<Vec3> interpolateCutValues(const PolyhedralMesh& mesh, const PlaneCutResult& cut,
                                       const std::vector<Vec3>& values) {
  if (static_cast<int>(values.size()) != mesh.numNodes())
    throw std::invalid_argument("interpolateCutValues: " + std::to_string(values.size()) + " values for " +
                                std::to_string(mesh.numNodes()) + " nodes");
  const PolyhedralMesh& out_mesh = cut.mesh;
  if (static_cast<int>(cut.node_stencils.size()) == out_mesh.numNodes()) {
    std::vector<Vec3> out(out_mesh.numNodes(), Vec3::Zero());
    for (int v = 0; v < out_mesh.numNodes(); ++v)
      for (const auto& [u, w] : cut.node_stencils[v]) out[v] += w * values[u];
    return out;
  }
  const int old_nodes = mesh.numNodes();
  std::vector<Vec3> out(out_mesh.numNodes());
  std::copy(values.begin(), values.end(), out.begin());
  if (out_mesh.numNodes() == old_nodes) return out;
  std::vector<int> element_of(out_mesh.numNodes() - old_nodes, -1);
  for (int e = 0; e < out_mesh.numElements(); ++e)
    for (int v : out_mesh.element(e).globalNodeIds())
      if (v >= old_nodes && element_of[v - old_nodes] < 0) element_of[v - old_nodes] = e;
  for (int v = old_nodes; v < out_mesh.numNodes(); ++v) {
    const int e = element_of[v - old_nodes];
    if (e < 0) throw std::logic_error("interpolateCutValues: new node " + std::to_string(v) + " is unused");
    const Vec3& x = out_mesh.node(v);
    double best = INFINITY, best_t = 0.0;
    int best_a = -1, best_b = -1;
    for (const PolyhedralMesh::Face& face : mesh.elementFaces(cut.parent_element[e]))
      for (size_t k = 0; k < face.size(); ++k) {
        const int a = face[k], b = face[(k + 1) % face.size()];
        const Vec3 ab = mesh.node(b) - mesh.node(a);
        const double t = std::clamp(ab.dot(x - mesh.node(a)) / ab.squaredNorm(), 0.0, 1.0);
        const double d = (mesh.node(a) + t * ab - x).squaredNorm();
        if (d < best) {
          best = d;
          best_t = t;
          best_a = a;
          best_b = b;
        }
      }
    out[v] = (1.0 - best_t) * values[best_a] + best_t * values[best_b];
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------------
// FemSimulation
// ---------------------------------------------------------------------------------------------------------

namespace {

// Whether some element of mesh may meet the convex polygon (box: the polygon's bounding box): its bounding
// box meets the polygon's (grown by band) and its nodes are not all farther than band on one side of the
// polygon's plane. Conservative: true for a degenerate polygon (the cut reports the problem).
bool polygonMayMeetElements(const PolyhedralMesh& mesh, const std::vector<Vec3>& polygon,
                            const std::pair<Vec3, Vec3>& box, double band) {
  Vec3 normal = Vec3::Zero();  // Newell
  for (size_t k = 0; k < polygon.size(); ++k) normal += polygon[k].cross(polygon[(k + 1) % polygon.size()]);
  if (!(normal.norm() > 0.0) || !normal.allFinite()) return true;
  normal.normalize();
  const double offset = normal.dot(polygon.front());
  const Vec3 lo = box.first - Vec3::Constant(band), hi = box.second + Vec3::Constant(band);
  for (const ConvexPolyhedron& element : mesh.elements()) {
    Vec3 element_lo = Vec3::Constant(INFINITY), element_hi = Vec3::Constant(-INFINITY);
    double below = INFINITY, above = -INFINITY;
    for (const Vec3& x : element.nodes()) {
      element_lo = element_lo.cwiseMin(x);
      element_hi = element_hi.cwiseMax(x);
      const double d = normal.dot(x) - offset;
      below = std::min(below, d);
      above = std::max(above, d);
    }
    if ((element_lo.array() > hi.array()).any() || (element_hi.array() < lo.array()).any()) continue;
    if (below <= band && above >= -band) return true;
  }
  return false;
}

// Order-independent key of a node set (sum and xor of the ids; equal sets have equal keys).
std::pair<long, int> nodeSetKey(const std::vector<int>& ids, const std::vector<int>* map = nullptr) {
  std::pair<long, int> key(0, 0);
  for (int id : ids) {
    const int v = map ? (*map)[id] : id;
    key.first += v;
    key.second ^= v;
  }
  return key;
}

// Elements of a mesh around each node (compressed rows) and the node set key of each element.
struct NodeElements {
  std::vector<int> offset, elements;
  std::vector<std::pair<long, int>> keys;
  explicit NodeElements(const PolyhedralMesh& mesh) : offset(mesh.numNodes() + 1, 0) {
    for (const ConvexPolyhedron& element : mesh.elements())
      for (int id : element.globalNodeIds()) ++offset[id + 1];
    for (int i = 0; i < mesh.numNodes(); ++i) offset[i + 1] += offset[i];
    elements.resize(offset.back());
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    keys.resize(mesh.numElements());
    for (int e = 0; e < mesh.numElements(); ++e) {
      for (int id : mesh.element(e).globalNodeIds()) elements[fill[id]++] = e;
      keys[e] = nodeSetKey(mesh.element(e).globalNodeIds());
    }
  }
};

// R_e for the elements of `mesh`, cut from `from` (old_node: per node of mesh its node in from's mesh, -1
// for nodes the cut created): the rotation of the old element with the same nodes (elements the cut left
// whole), else of an old element sharing a node (a warm start: R varies smoothly), else I.
std::vector<Eigen::Matrix3d> carriedRotations(const WarpedDynamics& from, const NodeElements& around,
                                              const PolyhedralMesh& mesh, const std::vector<int>& old_node) {
  const PolyhedralMesh& old_mesh = from.model().mesh();
  std::vector<Eigen::Matrix3d> rotations(mesh.numElements(), Eigen::Matrix3d::Identity());
  for (int e = 0; e < mesh.numElements(); ++e) {
    const auto& ids = mesh.element(e).globalNodeIds();
    int first = -1;
    bool all_old = true;
    for (int id : ids) {
      all_old = all_old && old_node[id] >= 0;
      if (first < 0) first = old_node[id];
    }
    if (first < 0) continue;
    int match = around.elements[around.offset[first]];  // some element around the node
    const std::pair<long, int> key = all_old ? nodeSetKey(ids, &old_node) : std::pair<long, int>(-1, 0);
    if (all_old)
      for (int k = around.offset[first]; k < around.offset[first + 1]; ++k) {
        if (around.keys[around.elements[k]] != key) continue;
        const auto& old_ids = old_mesh.element(around.elements[k]).globalNodeIds();
        if (old_ids.size() != ids.size()) continue;
        bool same = true;
        for (size_t a = 0; a < ids.size() && same; ++a)
          same = std::find(old_ids.begin(), old_ids.end(), old_node[ids[a]]) != old_ids.end();
        if (same) {
          match = around.elements[k];
          break;
        }
      }
    rotations[e] = from.rotations()[match];
  }
  return rotations;
}

// Per node of `from`: its dv (the CG warm start) as 3-vectors.
std::vector<Vec3> nodeVelocityIncrements(const WarpedDynamics& from) {
  std::vector<Vec3> dv(from.numNodes());
  for (int i = 0; i < from.numNodes(); ++i) dv[i] = from.previousVelocityIncrement().segment<3>(3 * i);
  return dv;
}

}  // namespace

FemSimulation::FemSimulation(const FemScene& scene) : scene_(scene) {
  if (!scene_.mesh) throw std::invalid_argument("FemSimulation: the scene has no mesh");
  bodies_.push_back(makeBody(*scene_.mesh, std::vector<Vec3>(scene_.mesh->numNodes(), Vec3::Zero()),
                             scene_.initial_velocities));
}

std::unique_ptr<WarpedDynamics> FemSimulation::makeBody(PolyhedralMesh mesh,
                                                        const std::vector<Vec3>& displacements,
                                                        const std::vector<Vec3>& velocities,
                                                        const LinearElasticModel* donor, FemCutReport* report,
                                                        CarriedState* carried) {
  const Clock::time_point start = Clock::now();
  const int n = mesh.numNodes();
  Eigen::VectorXd x(3 * n), v(3 * n);
  for (int i = 0; i < n; ++i) {
    x.segment<3>(3 * i) = mesh.node(i) + displacements[i];
    v.segment<3>(3 * i) = velocities[i];
  }
  LinearElasticModel model(std::move(mesh), scene_.youngs_modulus, scene_.poisson_ratio, scene_.density,
                           scene_.quadrature, donor);
  if (report) {
    report->recomputed_elements += model.numRecomputedElements();
    report->reused_elements += model.numReusedElements();
  }
  auto body = std::make_unique<WarpedDynamics>(std::move(model), scene_.dynamics);
  body->setPositions(x);
  body->setVelocities(v);
  ++retired_counts_.bodies_built;
  if (carried && carry_state_) {
    if (!carried->rotations.empty()) body->setRotations(carried->rotations);
    if (!carried->previous_dv.empty()) {
      Eigen::VectorXd dv(3 * n);
      for (int i = 0; i < n; ++i) dv.segment<3>(3 * i) = carried->previous_dv[i];
      body->setPreviousVelocityIncrement(dv);
    }
  }
  times_.integration += secondsSince(start);
  return body;
}

void FemSimulation::retireSolver(const CholmodSolver* solver) {
  if (!solver) return;
  retired_counts_.analyses += solver->numAnalyses();
  retired_counts_.factorizations += solver->numFactorizations();
  retired_counts_.analysis_seconds += solver->analysisSeconds();
  retired_counts_.factorization_seconds += solver->factorizationSeconds();
}

FemSimulation::SolverCounts FemSimulation::solverCounts() const {
  SolverCounts counts = retired_counts_;
  for (const auto& body : bodies_)
    if (const CholmodSolver* solver = body->cholmodSolver()) {
      counts.analyses += solver->numAnalyses();
      counts.factorizations += solver->numFactorizations();
      counts.analysis_seconds += solver->analysisSeconds();
      counts.factorization_seconds += solver->factorizationSeconds();
    }
  return counts;
}

std::vector<FemBodyState> FemSimulation::bodyStates() const {
  std::vector<FemBodyState> states;
  for (const auto& b : bodies_) states.push_back({&b->model().mesh(), &b->positions(), &b->velocities()});
  return states;
}

int FemSimulation::numNodes() const {
  int n = 0;
  for (const auto& b : bodies_) n += b->numNodes();
  return n;
}

int FemSimulation::numElements() const {
  int n = 0;
  for (const auto& b : bodies_) n += b->model().mesh().numElements();
  return n;
}

double FemSimulation::minGroundDistance() const {
  const GroundPlane& g = scene_.dynamics.ground;
  const Vec3 normal = g.enabled ? g.normal.normalized() : Vec3::UnitZ();
  const double offset = g.enabled ? g.offset : 0.0;
  double d = INFINITY;
  for (const auto& b : bodies_)
    for (int i = 0; i < b->numNodes(); ++i)
      d = std::min(d, normal.dot(b->positions().segment<3>(3 * i)) - offset);
  return d;
}

FemCutReport FemSimulation::applyPolygonCuts(const std::vector<std::vector<Vec3>>& polygons,
                                             double snap_relative_distance, const CutSliverOptions& slivers) {
  FemCutReport report;
  report.polygons = static_cast<int>(polygons.size());
  polygons_applied_ += report.polygons;
  std::vector<std::pair<Vec3, Vec3>> boxes;  // per polygon
  for (const auto& polygon : polygons) {
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (const Vec3& p : polygon) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    boxes.emplace_back(lo, hi);
  }
  PolygonCutOptions options;
  options.snap_relative_distance = snap_relative_distance;
  options.slivers = slivers;
  std::vector<std::unique_ptr<WarpedDynamics>> next;
  for (auto& body : bodies_) {
    Clock::time_point start = Clock::now();
    const PolyhedralMesh& mesh = body->model().mesh();
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (const Vec3& x : mesh.nodes()) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
    const double margin = 1e-9 * (hi - lo).norm();
    std::vector<int> hits;
    for (size_t k = 0; k < boxes.size(); ++k)
      if ((boxes[k].first.array() <= hi.array() + margin).all() &&
          (boxes[k].second.array() >= lo.array() - margin).all())
        hits.push_back(static_cast<int>(k));
    // Keep only polygons that an element may meet: an element whose box meets the polygon's and whose nodes
    // are not all (beyond a margin) on one side of its plane. Saves building a ProgressiveCutMesh when
    // the blade has not reached the body yet.
    const double band = std::max(10.0 * snap_relative_distance, 1e-6) * (hi - lo).norm();
    hits.erase(
        std::remove_if(hits.begin(), hits.end(),
                       [&](int k) { return !polygonMayMeetElements(mesh, polygons[k], boxes[k], band); }),
        hits.end());
    if (hits.empty()) {
      times_.topology += secondsSince(start);
      next.push_back(std::move(body));
      continue;
    }
    const int n = mesh.numNodes();
    std::vector<Vec3> u(n), v(n);
    for (int i = 0; i < n; ++i) {
      u[i] = body->positions().segment<3>(3 * i) - mesh.node(i);
      v[i] = body->velocities().segment<3>(3 * i);
    }
    ProgressiveCutMesh cut_mesh(mesh, u, options);
    PolygonCutStats total;
    for (int k : hits) {
      const PolygonCutStats s = cut_mesh.cut(polygons[k]);
      total.num_split_elements += s.num_split_elements;
      total.num_new_nodes += s.num_new_nodes + s.num_pocket_nodes;
      total.num_duplicated_nodes += s.num_duplicated_nodes;
      total.num_new_crack_faces += s.num_new_crack_faces;
      report.slivers_removed += s.slivers.num_removed;
      report.slivers_kept += s.slivers.num_rejected;
    }
    if (total.num_split_elements == 0 && total.num_new_nodes == 0 && total.num_new_crack_faces == 0) {
      times_.topology += secondsSince(start);
      next.push_back(std::move(body));
      continue;
    }
    ++report.bodies_cut;
    report.split_elements += total.num_split_elements;
    report.new_nodes += total.num_new_nodes;
    report.duplicated_nodes += total.num_duplicated_nodes;
    report.crack_faces += total.num_new_crack_faces;
    const std::vector<Vec3> cut_velocities = cut_mesh.interpolateNodeValues(v);
    int num_components = 0;
    cut_mesh.elementComponents(&num_components);
    if (num_components > 1) ++report.bodies_separated;
    const std::vector<Vec3> cut_dv = cut_mesh.interpolateNodeValues(nodeVelocityIncrements(*body));
    const NodeElements around(mesh);
    std::vector<PolyhedralMesh> meshes;
    std::vector<std::vector<Vec3>> side_u, side_v;
    std::vector<CarriedState> carried(num_components);
    for (int c = 0; c < num_components; ++c) {
      std::vector<int> ids;
      meshes.push_back(cut_mesh.componentMesh(c, &ids, &mesh));
      side_u.emplace_back();
      side_v.emplace_back();
      std::vector<int> old_node(ids.size());
      for (size_t k = 0; k < ids.size(); ++k) {
        const int id = ids[k];
        side_u.back().push_back(cut_mesh.displacements()[id]);
        side_v.back().push_back(cut_velocities[id]);
        carried[c].previous_dv.push_back(cut_dv[id]);
        int original = id;  // follow duplicates back to a node of the cut body (-1: created by the cut)
        while (original >= cut_mesh.numInitialNodes()) original = cut_mesh.duplicateOf()[original];
        old_node[k] = original;
      }
      carried[c].rotations = carriedRotations(*body, around, meshes.back(), old_node);
    }
    times_.topology += secondsSince(start);
    for (int c = 0; c < num_components; ++c)
      next.push_back(
          makeBody(std::move(meshes[c]), side_u[c], side_v[c], &body->model(), &report, &carried[c]));
    retireSolver(body->cholmodSolver());
  }
  bodies_ = std::move(next);
  recomputed_elements_ += report.recomputed_elements;
  reused_elements_ += report.reused_elements;
  slivers_removed_ += report.slivers_removed;
  slivers_kept_ += report.slivers_kept;
  return report;
}

FemCutReport FemSimulation::applyCut(const FemSceneCut& cut) {
  if (cut.isPolygonCut()) return applyPolygonCuts(cut.polygons, cut.snap_relative_distance, cut.slivers);
  FemCutReport report;
  std::vector<std::unique_ptr<WarpedDynamics>> next;
  PlaneCutOptions options;
  options.region = cut.region;
  options.snap_relative_distance = cut.snap_relative_distance;
  options.slivers = cut.slivers;
  for (auto& body : bodies_) {
    Clock::time_point start = Clock::now();
    const PolyhedralMesh& mesh = body->model().mesh();
    const int n = mesh.numNodes();
    std::vector<Vec3> u(n), v(n);
    for (int i = 0; i < n; ++i) {
      u[i] = body->positions().segment<3>(3 * i) - mesh.node(i);
      v[i] = body->velocities().segment<3>(3 * i);
    }
    // Bodies entirely on one side (the plane misses or only touches them) stay as they are.
    bool negative = false, positive = false;
    for (const Vec3& x : mesh.nodes()) {
      const double d = cut.normal.dot(x - cut.point);
      negative = negative || d < 0;
      positive = positive || d > 0;
    }
    if (!(negative && positive)) {
      times_.topology += secondsSince(start);
      next.push_back(std::move(body));
      continue;
    }
    PlaneCutResult result = cutMeshByPlane(mesh, u, cut.point, cut.normal, options);
    bool side_negative = false, side_positive = false, crossed_whole = false;
    for (int s : result.element_side) {
      side_negative = side_negative || s < 0;
      side_positive = side_positive || s > 0;
      crossed_whole = crossed_whole || s == 0;
    }
    if (result.num_split_elements == 0 &&
        !(side_negative && side_positive && cut.separate && !crossed_whole)) {
      times_.topology += secondsSince(start);  // snapped onto existing nodes only: nothing changes
      next.push_back(std::move(body));
      continue;
    }
    ++report.bodies_cut;
    report.split_elements += result.num_split_elements;
    report.new_nodes += result.num_new_nodes;
    report.slivers_removed += result.slivers.num_removed;
    report.slivers_kept += result.slivers.num_rejected;
    const std::vector<Vec3> cut_velocities = interpolateCutValues(mesh, result, v);
    const std::vector<Vec3> cut_dv = interpolateCutValues(mesh, result, nodeVelocityIncrements(*body));
    if (cut.separate && side_negative && side_positive && !crossed_whole) {
      const SeparatedMesh separated = separateAlongPlane(result);
      ++report.bodies_separated;
      report.duplicated_nodes += separated.numDuplicatedNodes();
      const int cut_nodes = result.mesh.numNodes();
      auto combined = [&](const std::vector<Vec3>& values, int id) {
        return id < cut_nodes ? values[id] : values[separated.duplicate_of[id - cut_nodes]];
      };
      std::vector<std::vector<Vec3>> side_u(2), side_v(2);
      std::vector<CarriedState> carried(2);
      for (int s = 0; s < 2; ++s) {
        for (int id : separated.side_node_ids[s]) {
          side_u[s].push_back(combined(result.displacements, id));
          side_v[s].push_back(combined(cut_velocities, id));
          carried[s].previous_dv.push_back(combined(cut_dv, id));
        }
        for (int e : separated.side_element_ids[s])
          carried[s].rotations.push_back(body->rotations()[result.parent_element[e]]);
      }
      times_.topology += secondsSince(start);
      for (int s = 0; s < 2; ++s)
        next.push_back(
            makeBody(separated.sides[s], side_u[s], side_v[s], &body->model(), &report, &carried[s]));
    } else {
      CarriedState carried;
      carried.previous_dv = cut_dv;
      for (int parent : result.parent_element) carried.rotations.push_back(body->rotations()[parent]);
      times_.topology += secondsSince(start);
      next.push_back(makeBody(std::move(result.mesh), result.displacements, cut_velocities, &body->model(),
                              &report, &carried));
    }
    retireSolver(body->cholmodSolver());
  }
  bodies_ = std::move(next);
  recomputed_elements_ += report.recomputed_elements;
  reused_elements_ += report.reused_elements;
  slivers_removed_ += report.slivers_removed;
  slivers_kept_ += report.slivers_kept;
  return report;
}

void FemSimulation::step() {
  const double dt = scene_.dynamics.time_step;
  const double now = time_ + 1e-9 * dt;
  // Polygons due now are applied together (one ProgressiveCutMesh per body and step).
  std::vector<std::vector<Vec3>> batch;
  double batch_snap = 0.0;
  CutSliverOptions batch_slivers;
  int batch_cut = -1;
  auto flush = [&]() {
    if (batch.empty()) return;
    try {
      applyPolygonCuts(batch, batch_snap, batch_slivers);
    } catch (const std::exception& e) {
      throw std::runtime_error("cut " + std::to_string(batch_cut) +
                               " (polygons due at t = " + formatNumber(time_) + "): " + e.what());
    }
    batch.clear();
  };
  while (next_cut_ < static_cast<int>(scene_.cuts.size())) {
    const FemSceneCut& cut = scene_.cuts[next_cut_];
    if (!cut.isPolygonCut()) {
      if (cut.time > now) break;
      flush();
      try {
        applyCut(cut);
      } catch (const std::exception& e) {
        throw std::runtime_error("cut " + std::to_string(next_cut_) + " (t = " + formatNumber(cut.time) +
                                 "): " + e.what());
      }
      ++next_cut_;
      continue;
    }
    if (!batch.empty() &&
        (batch_snap != cut.snap_relative_distance || batch_slivers.enabled != cut.slivers.enabled ||
         batch_slivers.relative_thickness != cut.slivers.relative_thickness))
      flush();
    while (next_polygon_ < static_cast<int>(cut.polygons.size()) && cut.polygonTime(next_polygon_) <= now) {
      if (batch.empty()) {
        batch_snap = cut.snap_relative_distance;
        batch_slivers = cut.slivers;
        batch_cut = next_cut_;
      }
      batch.push_back(cut.polygons[next_polygon_++]);
    }
    if (next_polygon_ < static_cast<int>(cut.polygons.size())) break;
    next_polygon_ = 0;
    ++next_cut_;
  }
  flush();
  const Clock::time_point start = Clock::now();
  int iterations = 0;
  for (auto& body : bodies_) {
    const StepStatistics stats = body->step();
    times_.rotations += 1e-3 * stats.warping_ms;
    times_.assembly += 1e-3 * stats.assembly_ms;
    times_.solve += 1e-3 * stats.solve_ms;
    iterations += stats.solver_iterations;
    if (!stats.converged) ++unconverged_;
    if (!body->positions().allFinite() || !body->velocities().allFinite())
      throw std::runtime_error("step " + std::to_string(steps_ + 1) + ": the state became non-finite");
  }
  times_.dynamics += secondsSince(start);
  solver_iterations_ += iterations;
  max_step_iterations_ = std::max(max_step_iterations_, iterations);
  ++steps_;
  time_ = steps_ * dt;
}

// ---------------------------------------------------------------------------------------------------------
// Running a scene
// ---------------------------------------------------------------------------------------------------------

FemRunStats runFemScene(const FemScene& scene, const FemRunOptions& options) {
  FemRunStats stats;
  stats.scene = scene.name;
  stats.frame_count = scene.frame_count;
  FemSimulation sim(scene);
  stats.nodes_start = sim.numNodes();
  stats.elements_start = sim.numElements();

  const bool write =
      !options.out_dir.empty() && scene.output.every > 0 && (scene.output.vtu || scene.output.obj);
  std::vector<PvdEntry> pvd;
  auto output = [&](int frame) {
    if (!write || frame % scene.output.every != 0) return;
    const Clock::time_point start = Clock::now();
    char number[16];
    std::snprintf(number, sizeof(number), "%04d", frame);
    const std::filesystem::path dir(options.out_dir);
    const std::vector<FemBodyState> states = sim.bodyStates();
    if (scene.output.vtu) {
      const std::string file = scene.name + "_" + number + ".vtu";
      writeFemVtu((dir / file).string(), states, scene.output.encoding);
      stats.files.push_back((dir / file).string());
      pvd.push_back({file, sim.time()});
      const std::string pvd_path = (dir / (scene.name + ".pvd")).string();
      writePvd(pvd_path, pvd);
      if (pvd.size() == 1) stats.files.push_back(pvd_path);
    }
    if (scene.output.obj) {
      const std::string file = (dir / (scene.name + "_surface_" + number + ".obj")).string();
      writeFemObj(file, states);
      stats.files.push_back(file);
    }
    sim.phaseTimes().output += secondsSince(start);
  };
  if (write) std::filesystem::create_directories(options.out_dir);
  output(0);

  for (int frame = 1; frame <= scene.frame_count; ++frame) {
    const Clock::time_point start = Clock::now();
    const long iterations_before = sim.solverIterations();
    try {
      for (int s = 0; s < scene.steps_per_frame; ++s) sim.step();
    } catch (const std::exception& e) {
      stats.error = e.what();
      break;
    }
    stats.frames = frame;
    if (options.on_frame) {
      FemFrameReport r;
      r.frame = frame;
      r.frame_count = scene.frame_count;
      r.time = sim.time();
      r.steps = sim.steps();
      r.nodes = sim.numNodes();
      r.elements = sim.numElements();
      r.bodies = sim.numBodies();
      r.cuts = sim.cutsApplied();
      r.frame_iterations = sim.solverIterations() - iterations_before;
      r.frame_seconds = secondsSince(start);
      options.on_frame(r);
    }
    output(frame);
  }

  stats.nodes = sim.numNodes();
  stats.elements = sim.numElements();
  stats.bodies = sim.numBodies();
  stats.cuts = sim.cutsApplied();
  for (int b = 0; b < sim.numBodies(); ++b) stats.crack_faces += sim.body(b).model().mesh().numCrackFaces();
  stats.slivers_removed = sim.sliversRemoved();
  stats.slivers_kept = sim.sliversKept();
  stats.steps = sim.steps();
  stats.simulated_time = sim.time();
  stats.times = sim.phaseTimes();
  stats.wall_seconds = stats.times.integration + stats.times.dynamics + stats.times.topology;
  stats.solver_iterations = sim.solverIterations();
  stats.max_step_iterations = sim.maxStepIterations();
  stats.unconverged_solves = sim.unconvergedSolves();
  stats.min_ground_distance = sim.minGroundDistance();
  for (int b = 0; b < sim.numBodies(); ++b) stats.kinetic_energy += sim.body(b).kineticEnergy();
  return stats;
}

std::string femRunStatsJson(const FemRunStats& s) {
  std::ostringstream j;
  const double ms_per_frame = s.frames > 0 ? 1e3 * s.wall_seconds / s.frames : NAN;
  auto perFrame = [&](double seconds) { return s.frames > 0 ? 1e3 * seconds / s.frames : NAN; };
  j << "{\"scene\":" << jsonString(s.scene) << ",\"nodes_start\":" << s.nodes_start
    << ",\"elements_start\":" << s.elements_start << ",\"nodes\":" << s.nodes
    << ",\"elements\":" << s.elements << ",\"bodies\":" << s.bodies << ",\"cuts\":" << s.cuts
    << ",\"crack_faces\":" << s.crack_faces << ",\"slivers_removed\":" << s.slivers_removed
    << ",\"slivers_kept\":" << s.slivers_kept << ",\"frames\":" << s.frames
    << ",\"frame_count\":" << s.frame_count << ",\"steps\":" << s.steps
    << ",\"simulated_time\":" << formatNumber(s.simulated_time)
    << ",\"ms\":{\"integration\":" << formatNumber(1e3 * s.times.integration)
    << ",\"bases\":" << formatNumber(1e3 * s.times.integration)
    << ",\"rotations\":" << formatNumber(1e3 * s.times.rotations)
    << ",\"assembly\":" << formatNumber(1e3 * s.times.assembly)
    << ",\"solve\":" << formatNumber(1e3 * s.times.solve)
    << ",\"dynamics\":" << formatNumber(1e3 * s.times.dynamics)
    << ",\"topology\":" << formatNumber(1e3 * s.times.topology)
    << ",\"output\":" << formatNumber(1e3 * s.times.output)
    << ",\"total\":" << formatNumber(1e3 * s.wall_seconds)
    << "},\"ms_per_frame\":" << formatNumber(ms_per_frame)
    << ",\"ms_per_frame_phases\":{\"bases\":" << formatNumber(perFrame(s.times.integration))
    << ",\"rotations\":" << formatNumber(perFrame(s.times.rotations))
    << ",\"assembly\":" << formatNumber(perFrame(s.times.assembly))
    << ",\"solve\":" << formatNumber(perFrame(s.times.solve)) << ",\"other_dynamics\":"
    << formatNumber(perFrame(s.times.dynamics - s.times.rotations - s.times.assembly - s.times.solve))
    << ",\"topology\":" << formatNumber(perFrame(s.times.topology)) << "}"
    << ",\"ms_per_step\":" << formatNumber(s.steps > 0 ? 1e3 * s.times.dynamics / double(s.steps) : NAN)
    << ",\"solver_iterations\":" << s.solver_iterations
    << ",\"max_step_iterations\":" << s.max_step_iterations
    << ",\"unconverged_solves\":" << s.unconverged_solves
    << ",\"min_ground_distance\":" << formatNumber(s.min_ground_distance)
    << ",\"kinetic_energy\":" << formatNumber(s.kinetic_energy)
    << ",\"error\":" << (s.error.empty() ? std::string("null") : jsonString(s.error))
    << ",\"files\":" << s.files.size() << "}";
  return j.str();
}

}  // namespace rc
