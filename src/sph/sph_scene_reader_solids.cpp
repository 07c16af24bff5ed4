#include "relaxed_connectivity/sph/sph_scene_reader_sections.h"

#include "relaxed_connectivity/io/cloud_io.h"

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

#include "relaxed_connectivity/mesh/fast_winding_number.h"
#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_lattice.h"
#include "relaxed_connectivity/sph/sph_scene_builders.h"

namespace rc::sph_scene_reading {

void SceneReader::readElasticMaterial(const YAML::Node& node, const std::string& where,
                                      SphElasticConfig* elastic) {
  SphElasticConfig& e = *elastic;
  e.lattice_spacing = blockSpacing(node, where);
  if (!(e.lattice_spacing < scene_.config.smoothing_length))
    src_.fail(node, where + ": the lattice spacing must be below the smoothing length (no neighbours)");
  e.model = node["model"] ? src_.choice<SphElasticModel>(node["model"], where + ".model",
                                                         {{"strain", SphElasticModel::kStrain},
                                                          {"goal_position", SphElasticModel::kGoalPosition}})
                          : SphElasticModel::kGoalPosition;
  const char* strain_keys[] = {"youngs_modulus", "poisson_ratio", "hourglass_control"};
  const char* goal_keys[] = {"goal_stiffness", "deformation_allowance", "implicit_goal",
                             "implicit_step_factor", "implicit_tolerance"};
  if (e.model == SphElasticModel::kStrain) {
    for (const char* k : goal_keys)
      if (node[k]) src_.fail(node[k], where + "." + k + ": applies to model goal_position, not strain");
    optionalNumber(node, "youngs_modulus", where, &e.youngs_modulus, &Source::positive);
    optionalNumber(node, "poisson_ratio", where, &e.poisson_ratio, &Source::number);
    optionalNumber(node, "hourglass_control", where, &e.hourglass_control, &Source::nonNegative);
  } else {
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
  }
  try {
    e.validate();
  } catch (const std::invalid_argument& ex) {
    src_.fail(node, where + ": " + ex.what());
  }
}

void SceneReader::readFracturePlasticity(const YAML::Node& node, const std::string& where,
                                         SphElasticConfig* elastic) {
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

TriangleMesh SceneReader::readMeshFile(const YAML::Node& node, const std::string& what) const {
  const std::string file = src_.string(node, what);
  std::filesystem::path path(file);
  if (path.is_relative()) path = std::filesystem::path(src_.sourceName()).parent_path() / path;
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
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

TriangleMesh SceneReader::readSolidMesh(const YAML::Node& node, const std::string& where,
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

void SceneReader::readSolid(const YAML::Node& node, const std::string& where) {
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

void SceneReader::readSkin(const YAML::Node& node, const std::string& where, const std::string& shape,
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
  if (const YAML::Node t = node["transforms"])
    skin.lattice_transforms =
        src_.choice<bool>(t, where + ".transforms", {{"fitted", false}, {"lattice", true}});
  if (const YAML::Node o = node["orphans"])
    pending.orphans = src_.choice<SphSkinOrphanPolicy>(
        o, where + ".orphans",
        {{"error", SphSkinOrphanPolicy::kThrow}, {"nearest", SphSkinOrphanPolicy::kNearestParticle}});
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

void SceneReader::finishSkins() {
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

void SceneReader::readCollisions(const YAML::Node& node) {
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

}  // namespace rc::sph_scene_reading
