#include "relaxed_connectivity/sph/sph_scene_reader.h"

#include "relaxed_connectivity/io/cloud_io.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include <Eigen/Geometry>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/mesh/fast_winding_number.h"
#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_lattice.h"
#include "relaxed_connectivity/sph/sph_scene_builders.h"
#include "relaxed_connectivity/sph/sph_scene_reader_sections.h"

namespace rc::sph_scene_reading {
namespace {

std::string shortNumber(double v) {
  std::ostringstream s;
  s << std::setprecision(3) << v;
  return s.str();
}

}  // namespace

void SceneReader::read(const YAML::Node& root) {
  src_.allowKeys(root,
                 {"name", "dimension", "spacing", "enable", "solver", "fluid", "solids", "boundary", "moving",
                  "frames", "output", "temperature", "phase_transition", "collisions", "sources", "probes"},
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
  if (const YAML::Node probes = root["probes"]) {
    src_.allowKeys(probes, {"points"}, "probes");
    scene_.probes.enabled = true;
    if (const YAML::Node points = probes["points"]) {
      if (!points.IsSequence()) src_.fail(points, "probes.points: expected a list of points");
      for (size_t i = 0; i < points.size(); ++i)
        scene_.probes.points.push_back(
            src_.vec(points[i], "probes.points[" + std::to_string(i) + "]", dimension_, true));
    }
  }
  if (enabled("surface")) finishSurface();
  if (enabled("skin")) finishSkins();
}

void SceneReader::readEnable(const YAML::Node& node) {
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

bool SceneReader::enabled(const std::string& physics) const {
  return std::find(scene_.enabled_physics.begin(), scene_.enabled_physics.end(), physics) !=
         scene_.enabled_physics.end();
}

void SceneReader::planeGeometry(const YAML::Node& p, const std::string& where, Vec3* normal,
                                double* offset) const {
  const YAML::Node n = src_.require(p, "normal", where);
  *normal = src_.vec(n, where + ".normal", dimension_, true);
  if (!(normal->norm() > 0)) src_.fail(n, where + ".normal must be non-zero");
  normal->normalize();
  if (p["offset"] && p["point"]) src_.fail(p["point"], where + ": give offset or point, not both");
  if (p["offset"]) *offset = src_.number(p["offset"], where + ".offset");
  if (p["point"]) *offset = normal->dot(src_.vec(p["point"], where + ".point", dimension_, false));
}

void SceneReader::readSolver(const YAML::Node& node) {
  src_.allowKeys(node,
                 {"smoothing_length",
                  "smoothing_ratio",
                  "rest_density",
                  "stiffness",
                  "speed_of_sound",
                  "gamma",
                  "negative_pressure_scale",
                  "tensile_correction",
                  "pressure_kernel",
                  "boundary_pressure",
                  "density",
                  "density_reinit_interval",
                  "viscosity",
                  "xsph",
                  "gravity",
                  "cfl",
                  "fixed_dt",
                  "max_dt",
                  "instability_energy_growth",
                  "instability_window",
                  "instability_window_growth",
                  "max_compression",
                  "threads"},
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
  if (const YAML::Node t = field("tensile_correction", "tensile_correction")) {
    c.tensile_correction = src_.number(t, "solver.tensile_correction");
    field_nodes_["tensile_spacing"] = t;
    if (c.tensile_correction > 0) {  // f = W(r) / W(Delta p) with the scene's particle spacing
      if (spacing_ <= 0) src_.fail(t, "solver.tensile_correction needs the scene's 'spacing'");
      c.tensile_spacing = spacing_;
    }
  }
  const YAML::Node kernel = field("pressure_kernel", "pressure_kernel");
  if (kernel)
    c.pressure_kernel = src_.choice<SphPressureKernel>(
        kernel, "solver.pressure_kernel",
        {{"spiky", SphPressureKernel::kSpiky}, {"poly6", SphPressureKernel::kPoly6}});
  if (const YAML::Node d = field("density", "density"))
    c.density = src_.choice<SphDensityMethod>(
        d, "solver.density",
        {{"summation", SphDensityMethod::kSummation}, {"continuity", SphDensityMethod::kContinuity}});
  if (const YAML::Node r = field("density_reinit_interval", "density_reinit_interval"))
    c.density_reinit_interval = int(src_.integer(r, "solver.density_reinit_interval", 0, 1000000));
  if (kernel && c.pressure_kernel == SphPressureKernel::kSpiky)
    warn(kernel,
         c.density == SphDensityMethod::kSummation
             ? "solver.pressure_kernel spiky is not the gradient of the summation density's energy and "
               "pumps energy into the fluid (docs/sph_choices.md: +28 % in a 2D dam break in 0.25 s, "
               "+454 % in inviscid sloshing in 0.5 s); poly6, the default, conserves it"
             : "solver.pressure_kernel spiky with continuity densities gains energy at the adaptive step "
               "(docs/sph_choices.md: +7.7 % in a free 2D blob in 0.2 s, poly6 -1.1 %)");
  if (const YAML::Node b = field("boundary_pressure", "boundary_pressure"))
    c.boundary_pressure =
        src_.choice<SphBoundaryPressure>(b, "solver.boundary_pressure",
                                         {{"extrapolated", SphBoundaryPressure::kExtrapolated},
                                          {"summation", SphBoundaryPressure::kSummation}});
  if (field("viscosity", "viscosity")) c.viscosity = src_.number(node["viscosity"], "solver.viscosity");
  if (field("xsph", "xsph")) c.xsph = src_.number(node["xsph"], "solver.xsph");
  if (field("gravity", "gravity")) c.gravity = src_.vec(node["gravity"], "solver.gravity", dimension_, true);
  if (field("cfl", "cfl")) c.cfl = src_.number(node["cfl"], "solver.cfl");
  if (field("fixed_dt", "fixed_dt")) c.fixed_dt = src_.number(node["fixed_dt"], "solver.fixed_dt");
  if (field("max_dt", "max_dt")) c.max_dt = src_.number(node["max_dt"], "solver.max_dt");
  if (field("instability_energy_growth", "instability_energy_growth"))
    c.instability_energy_growth =
        src_.number(node["instability_energy_growth"], "solver.instability_energy_growth");
  if (field("instability_window", "instability_window"))
    c.instability_window =
        int(src_.integer(node["instability_window"], "solver.instability_window", 0, 1000000));
  if (field("instability_window_growth", "instability_window_growth"))
    c.instability_window_growth =
        src_.number(node["instability_window_growth"], "solver.instability_window_growth");
  if (field("max_compression", "max_compression"))
    c.max_compression = src_.nonNegative(node["max_compression"], "solver.max_compression");
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

void SceneReader::warn(const YAML::Node& node, const std::string& problem) {
  scene_.warnings.push_back(src_.at(node) + ": warning: " + problem);
}

double SceneReader::blockSpacing(const YAML::Node& node, const std::string& where) const {
  if (node["spacing"]) return src_.positive(node["spacing"], where + ".spacing");
  if (spacing_ <= 0) src_.fail(node, where + ": missing 'spacing' (and the scene has no default 'spacing')");
  return spacing_;
}

double SceneReader::massFor(double dx) {
  auto it = masses_.find(dx);
  if (it == masses_.end())
    it = masses_
             .emplace(dx, latticeParticleMass(SphKernels(dimension_, scene_.config.smoothing_length),
                                              scene_.config.rest_density, dx))
             .first;
  return it->second;
}

void SceneReader::reserveLattice(const YAML::Node& node, const std::string& where, const Vec3& lo,
                                 const Vec3& hi, double dx, int layers) {
  double n = 1;
  for (int k = 0; k < dimension_; ++k) n *= std::floor((hi[k] - lo[k]) / dx + 1e-9) + 2.0 * layers;
  planned_ += n;
  if (planned_ > kMaxParticles)
    src_.fail(node, where + ": the scene would exceed " + std::to_string(long(kMaxParticles)) +
                        " particles (spacing too small?)");
}

void SceneReader::addBox(const YAML::Node& node, const std::string& where, const Box& box, double dx,
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

void SceneReader::readFluid(const YAML::Node& node, const std::string& where) {
  src_.allowKeys(node,
                 {"shape", "lo", "hi", "center", "radius", "mesh", "scale", "translation", "spacing",
                  "velocity", "temperature"},
                 where);
  enum class Shape { kBox, kSphere, kMesh };
  const Shape shape =
      node["shape"]
          ? src_.choice<Shape>(node["shape"], where + ".shape",
                               {{"box", Shape::kBox}, {"sphere", Shape::kSphere}, {"mesh", Shape::kMesh}})
          : Shape::kBox;
  for (const char* key : {"mesh", "scale", "translation"})
    if (node[key] && shape != Shape::kMesh)
      src_.fail(node[key], where + "." + key + ": only with shape: mesh");
  const size_t first = scene_.particles.size();
  Vec3 centre;
  double dx = 0;  // read after the shape, whose errors come first
  // The cell-centred lattice points of the box centre +- half that `inside` keeps, as fluid particles.
  auto addInside = [&](const Vec3& half, const YAML::Node& at, const std::string& what, auto&& inside) {
    reserveLattice(node, where, centre - half, centre + half, dx, 0);
    SphParticles box;
    try {
      addLatticeBox(box, centre - half, centre + half, dx, massFor(dx), dimension_, SphParticleKind::kFluid);
    } catch (const std::invalid_argument& e) {
      src_.fail(node, where + ": " + e.what());
    }
    for (size_t i = 0; i < box.size(); ++i)
      if (inside(box.positions[i]))
        scene_.particles.add(box.positions[i], Vec3::Zero(), box.masses[i], SphParticleKind::kFluid);
    if (scene_.particles.size() == first)
      src_.fail(at, where + ": the " + what + " holds no lattice point of spacing " + std::to_string(dx));
  };
  if (shape == Shape::kBox) {
    for (const char* key : {"center", "radius"})
      if (node[key]) src_.fail(node[key], where + "." + key + ": only with shape: sphere");
    const Box box = readBox(src_, node, where, dimension_);
    dx = blockSpacing(node, where);
    addBox(node, where, box, dx, SphParticleKind::kFluid, Vec3::Zero());
    centre = 0.5 * (box.lo + box.hi);
  } else if (shape == Shape::kMesh) {  // the lattice points inside the closed mesh (winding number > 1/2)
    for (const char* key : {"lo", "hi", "center", "radius"})
      if (node[key])
        src_.fail(node[key], where + "." + key + ": not with shape: mesh (mesh, scale, translation)");
    Vec3 half;
    const TriangleMesh mesh = readSolidMesh(node, where, Eigen::Matrix3d::Identity(), &centre, &half);
    dx = blockSpacing(node, where);
    const FastWindingNumber winding(mesh);  // (the mesh is centred on the origin)
    addInside(half, node["mesh"], "mesh (too small for the spacing, or not closed?)",
              [&](const Vec3& x) { return std::abs(winding(x - centre)) > 0.5; });
  } else {  // the lattice points of the bounding box within the radius (a disc in 2D)
    for (const char* key : {"lo", "hi"})
      if (node[key]) src_.fail(node[key], where + "." + key + ": not with shape: sphere (center and radius)");
    centre = src_.vec(src_.require(node, "center", where), where + ".center", dimension_, true);
    const double radius = src_.positive(src_.require(node, "radius", where), where + ".radius");
    dx = blockSpacing(node, where);
    addInside(dimension_ == 3 ? Vec3::Constant(radius) : Vec3(radius, radius, 0), node, "sphere",
              [&](const Vec3& x) { return (x - centre).norm() <= radius; });
  }
  readVelocityField(node["velocity"], where + ".velocity", centre, first);
  readBlockTemperature(node, where, first);
  // Too few neighbours: in 3D, fluid below h = 2.5 dx pairs up under compression (the poly6 gradient vanishes
  // at r -> 0) and its pressures read low; in 2D, below h = 2 dx the kernel sums are too coarse.
  const double ratio = scene_.config.smoothing_length / dx;
  if (dimension_ == 3 && ratio < 2.5 - 1e-9)
    warn(node, where + ": h = " + shortNumber(ratio) + " x its spacing (about " +
                   std::to_string(long(std::lround(4.0 / 3.0 * M_PI * ratio * ratio * ratio - 1))) +
                   " neighbours): 3D fluid below h = 2.5 dx pairs up under compression and its hydrostatic "
                   "pressure reads 16 % low at 2-2.2 dx (docs/sph_choices.md); use smoothing_ratio >= 2.5");
  if (dimension_ == 2 && ratio < 2 - 1e-9)
    warn(node, where + ": h = " + shortNumber(ratio) + " x its spacing (about " +
                   std::to_string(long(std::lround(M_PI * ratio * ratio - 1))) +
                   " neighbours): too few for the kernel sums; Monaghan's elliptical drop is 3.7 % off at "
                   "h = 1.5 dx, 2.2 % at 2 dx, 0.5 % at 3 dx (docs/validation.md); use smoothing_ratio >= 2");
}

void SceneReader::readVelocityField(const YAML::Node& node, const std::string& where, const Vec3& centre,
                                    size_t first) {
  if (!node) return;
  Vec3 uniform = Vec3::Zero(), about = centre, rotation = Vec3::Zero();
  Eigen::Matrix3d gradient = Eigen::Matrix3d::Zero();
  if (node.IsSequence()) {
    uniform = src_.vec(node, where, dimension_, true);
  } else {
    src_.allowKeys(node, {"uniform", "gradient", "rotation", "about", "file"}, where);
    if (node["uniform"]) uniform = src_.vec(node["uniform"], where + ".uniform", dimension_, true);
    if (node["about"]) about = src_.vec(node["about"], where + ".about", dimension_, true);
    if (const YAML::Node g = node["gradient"]) {
      if (!g.IsSequence() || int(g.size()) != dimension_)
        src_.fail(g, where + ".gradient: expected " + std::to_string(dimension_) +
                         " rows (the matrix A of v = A x)");
      for (int r = 0; r < dimension_; ++r) {
        if (!g[r].IsSequence() || int(g[r].size()) != dimension_)
          src_.fail(g[r], where + ".gradient: expected rows of " + std::to_string(dimension_) + " numbers");
        for (int c = 0; c < dimension_; ++c) gradient(r, c) = src_.number(g[r][c], where + ".gradient");
      }
    }
    if (const YAML::Node w = node["rotation"]) {
      if (dimension_ == 2)
        rotation = Vec3(0, 0, src_.number(w, where + ".rotation (2D: the angular velocity about z)"));
      else
        rotation = src_.vec(w, where + ".rotation", 3, false);
    }
  }
  for (size_t i = first; i < scene_.particles.size(); ++i) {
    const Vec3 r = scene_.particles.positions[i] - about;
    scene_.particles.velocities[i] = uniform + gradient * r + rotation.cross(r);
  }
  if (node.IsMap() && node["file"]) {  // plus the velocity of the nearest sample of the file
    std::vector<Vec3> points, velocities;
    readVelocitySamples(node["file"], where + ".file", &points, &velocities);
    const KdTree tree(points);
    for (size_t i = first; i < scene_.particles.size(); ++i) {
      Neighbor nearest;
      tree.knn(scene_.particles.positions[i], 1, &nearest);
      scene_.particles.velocities[i] += velocities[nearest.index];
    }
  }
}

void SceneReader::readVelocitySamples(const YAML::Node& node, const std::string& what,
                                      std::vector<Vec3>* points, std::vector<Vec3>* velocities) const {
  const std::string file = src_.string(node, what);
  std::filesystem::path path(file);
  if (path.is_relative()) path = std::filesystem::path(src_.sourceName()).parent_path() / path;
  std::ifstream in(path);
  if (!in) src_.fail(node, what + ": cannot open '" + path.string() + "'");
  const int n = dimension_;  // per line: the point, then the velocity (n numbers each)
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    for (char& c : line)
      if (c == ',') c = ' ';
    std::istringstream fields(line);
    std::vector<double> values;
    for (std::string token; fields >> token;) {
      char* end = nullptr;
      const double v = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0' || !std::isfinite(v))
        src_.fail(node, what + ": " + path.string() + ":" + std::to_string(number) + ": '" + token +
                            "' is not a finite number");
      values.push_back(v);
    }
    if (values.empty()) continue;
    if (int(values.size()) != 2 * n)
      src_.fail(node, what + ": " + path.string() + ":" + std::to_string(number) + ": expected " +
                          std::to_string(2 * n) + " numbers (" + (n == 2 ? "x y vx vy" : "x y z vx vy vz") +
                          "), got " + std::to_string(values.size()));
    points->emplace_back(values[0], values[1], n == 3 ? values[2] : 0.0);
    velocities->emplace_back(values[size_t(n)], values[size_t(n) + 1], n == 3 ? values[5] : 0.0);
  }
  if (points->empty()) src_.fail(node, what + ": '" + path.string() + "' holds no samples");
}

void SceneReader::readMoving(const YAML::Node& node, const std::string& where) {
  src_.allowKeys(node, {"lo", "hi", "spacing", "velocity"}, where);
  const Box box = readBox(src_, node, where, dimension_);
  const double dx = blockSpacing(node, where);
  const Vec3 v = src_.vec(src_.require(node, "velocity", where), where + ".velocity", dimension_, true);
  addBox(node, where, box, dx, SphParticleKind::kMovingBoundary, v);
}

void SceneReader::readBoundary(const YAML::Node& node) {
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

void SceneReader::readFrames(const YAML::Node& node) {
  src_.allowKeys(node, {"count", "time"}, "frames");
  scene_.frame_count = int(src_.integer(src_.require(node, "count", "frames"), "frames.count", 1, 100000000));
  scene_.frame_time = src_.positive(src_.require(node, "time", "frames"), "frames.time");
}

}  // namespace rc::sph_scene_reading

namespace rc {

using sph_scene_reading::SceneReader;
using sph_scene_reading::Source;

const std::vector<std::string>& sphOptionalPhysics() {
  // elasticity (8.2), phase_transition (8.2.4), temperature (heat conduction driving 8.2.4), surface (8.2.7).
  // collisions: the penalty (8.37) between solids (8.2.6). skin: surfaces bound to solids (8.38).
  static const std::vector<std::string> names = {"elasticity",  "collisions", "phase_transition",
                                                 "temperature", "surface",    "skin"};
  return names;
}

SphScene parseSphScene(const std::string& yaml_text, const std::string& source_name) {
  const Source src{source_name};
  const YAML::Node root =
      src.parseMap(yaml_text, "expected a map of scene keys (dimension, solver, fluid, frames, ...)");
  SphScene scene;
  scene.path = source_name;
  scene.name = std::filesystem::path(source_name).stem().string();
  SceneReader(src, &scene).read(root);
  return scene;
}

SphScene loadSphScene(const std::string& path) {
  return parseSphScene(YamlReader::readFile(path, &sph_scene_reading::raiseSphSceneError), path);
}

}  // namespace rc
