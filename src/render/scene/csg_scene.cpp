#include "relaxed_connectivity/render/scene/csg_scene.h"
#include "relaxed_connectivity/io/yaml_reader.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "relaxed_connectivity/render/csg/patch_sampling.h"

namespace rc {

namespace {

constexpr double kDegree = M_PI / 180.0;
/// Surfels within this many radii of a texture square's border belong to both colour patches.
constexpr double kTextureOverlapRadii = 0.9;

[[noreturn]] void raiseSceneError(const std::string& message) {
  throw std::runtime_error(message);
}

/// Error context: the source name for "<file>:<line>:<column>: <problem>" and the scene's value types.
struct Source : YamlReader {
  explicit Source(std::string name) : YamlReader(std::move(name), &raiseSceneError) {}

  size_t count(const YAML::Node& node, const std::string& what) const {
    const double v = number(node, what);
    if (!(v >= 1) || v != std::floor(v) || v > 1e9) fail(node, what + " must be a positive integer");
    return size_t(v);
  }

  Vec3 direction(const YAML::Node& node, const std::string& what) const {
    const Vec3 v = vec3(node, what);
    if (!(v.norm() > 0)) fail(node, what + " must be non-zero");
    return v.normalized();
  }

  Rgba color(const YAML::Node& node, const std::string& what) const {
    if (!node.IsSequence() || (node.size() != 3 && node.size() != 4))
      fail(node, what + ": expected [r, g, b]");
    Rgba c = {0, 0, 0, 255};
    for (size_t k = 0; k < node.size(); ++k) {
      const double v = number(node[k], what);
      if (v < 0 || v > 255) fail(node[k], what + ": components must lie in [0, 255]");
      c[k] = uint8_t(std::lround(v));
    }
    return c;
  }

  Eigen::Matrix3d rotation(const YAML::Node& node, const std::string& what) const {
    if (!node) return Eigen::Matrix3d::Identity();
    allowKeys(node, {"axis", "angle"}, what);
    const Vec3 axis = direction(require(node, "axis", what), what + ".axis");
    const double angle = number(require(node, "angle", what), what + ".angle") * kDegree;
    return Eigen::AngleAxisd(angle, axis).matrix();
  }
};

bool validName(const std::string& name) {
  if (name.empty()) return false;
  for (char ch : name)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '.')) return false;
  return !std::isdigit(static_cast<unsigned char>(name[0]));
}

/// Surfels of one patch before assembly.
struct PatchSurfels {
  SurfelCloud cloud;
  SurfelRole role = SurfelRole::kSurface;
  Rgba color = {200, 200, 200, 255};
  double spacing = 0;  ///< mean spacing (for texture borders)
};

PatchSampling readSampling(const Source& src, const YAML::Node& patch, const std::string& where,
                           double radius_scale) {
  PatchSampling sampling;
  sampling.radius_scale = radius_scale;
  if (patch["samples"]) sampling.samples = src.count(patch["samples"], where + ".samples");
  if (patch["spacing"]) sampling.spacing = src.positive(patch["spacing"], where + ".spacing");
  if (sampling.samples == 0 && sampling.spacing == 0)
    src.fail(patch, where + ": needs 'samples' or 'spacing'");
  return sampling;
}

PatchMotion readMotion(const Source& src, const YAML::Node& node, const std::string& where) {
  PatchMotion motion;
  if (!node) return motion;
  src.allowKeys(node, {"velocity", "angular_velocity", "axis", "pivot"}, where);
  if (node["velocity"]) motion.velocity = src.vec3(node["velocity"], where + ".velocity");
  if (node["angular_velocity"])
    motion.angular_velocity = src.number(node["angular_velocity"], where + ".angular_velocity") * kDegree;
  if (node["axis"]) motion.axis = src.direction(node["axis"], where + ".axis");
  if (node["pivot"]) motion.pivot = src.vec3(node["pivot"], where + ".pivot");
  return motion;
}

/// One patch entry: solid + surfels.
void readPatch(const Source& src, const YAML::Node& node, size_t index, double radius_scale,
               CsgScenePatch* patch, PatchSurfels* surfels) {
  const std::string where = "patches[" + std::to_string(index) + "]";
  src.allowKeys(node,
                {"name", "shape", "center", "radius", "semi_axes", "half_extents", "rotation", "point",
                 "normal", "size", "up", "disk_radius", "samples", "spacing", "color", "motion"},
                where);
  patch->name = src.string(src.require(node, "name", where), where + ".name");
  if (!validName(patch->name))
    src.fail(node["name"], where + ": patch name '" + patch->name + "' must match [A-Za-z_.][A-Za-z0-9_.]*");
  const std::string at = "patch '" + patch->name + "'";
  if (node["color"]) patch->color = src.color(node["color"], at + ".color");
  patch->motion = readMotion(src, node["motion"], at + ".motion");
  patch->has_solid = true;
  const YAML::Node shape_node = src.require(node, "shape", at);
  const std::string shape = src.string(shape_node, at + ".shape");
  if (shape == "sphere") {
    const Vec3 center = src.vec3(src.require(node, "center", at), at + ".center");
    const double radius = src.positive(src.require(node, "radius", at), at + ".radius");
    patch->solid = AnalyticSolid::sphere(center, radius);
    surfels->cloud = sampleSphere(center, radius, readSampling(src, node, at, radius_scale));
  } else if (shape == "ellipsoid") {
    const Vec3 center = src.vec3(src.require(node, "center", at), at + ".center");
    const YAML::Node axes_node = src.require(node, "semi_axes", at);
    const Vec3 semi_axes = src.vec3(axes_node, at + ".semi_axes");
    if (!(semi_axes.minCoeff() > 0)) src.fail(axes_node, at + ".semi_axes must be positive");
    const Eigen::Matrix3d rotation = src.rotation(node["rotation"], at + ".rotation");
    patch->solid = AnalyticSolid::ellipsoid(center, semi_axes, rotation);
    surfels->cloud = sampleEllipsoid(center, semi_axes, rotation, readSampling(src, node, at, radius_scale));
  } else if (shape == "half_space") {
    const Vec3 point = src.vec3(src.require(node, "point", at), at + ".point");
    const Vec3 normal = src.direction(src.require(node, "normal", at), at + ".normal");
    patch->solid = AnalyticSolid::halfSpace(point, normal);
    if (node["disk_radius"]) {
      if (node["size"] || node["samples"] || node["spacing"])
        src.fail(node["disk_radius"], at + ": 'disk_radius' excludes 'size', 'samples' and 'spacing'");
      surfels->cloud = samplePlaneDisk(point, normal, src.positive(node["disk_radius"], at + ".disk_radius"));
    } else {
      const double size = src.positive(src.require(node, "size", at), at + ".size");
      const Vec3 up = node["up"] ? src.direction(node["up"], at + ".up") : anyOrthogonal(normal);
      surfels->cloud = samplePlaneSquare(point, normal, up, size, readSampling(src, node, at, radius_scale));
    }
  } else if (shape == "box_faces") {
    const Vec3 center = src.vec3(src.require(node, "center", at), at + ".center");
    const YAML::Node half_node = src.require(node, "half_extents", at);
    const Vec3 half = src.vec3(half_node, at + ".half_extents");
    if (!(half.minCoeff() > 0)) src.fail(half_node, at + ".half_extents must be positive");
    const Eigen::Matrix3d rotation = src.rotation(node["rotation"], at + ".rotation");
    patch->solid = AnalyticSolid::box(center, half, rotation);
    surfels->cloud = sampleBoxFaces(center, half, rotation, readSampling(src, node, at, radius_scale));
  } else {
    src.fail(shape_node, at + ": unknown shape '" + shape + "' (sphere, ellipsoid, half_space, box_faces)");
  }
  surfels->color = patch->color;
  const size_t n = surfels->cloud.size();
  double area = 0;
  for (double r : surfels->cloud.radii) area += r * r;
  surfels->spacing = std::sqrt(area / n) / radius_scale;  // about the covering radius
}

CsgSceneCamera readCamera(const Source& src, const YAML::Node& node, size_t index) {
  const std::string where = "cameras[" + std::to_string(index) + "]";
  src.allowKeys(
      node,
      {"name", "projection", "width", "height", "fov", "view_width", "eye", "target", "up", "near", "far"},
      where);
  CsgSceneCamera out;
  out.name = node["name"] ? src.string(node["name"], where + ".name") : "cam" + std::to_string(index);
  const uint32_t width = uint32_t(src.count(src.require(node, "width", where), where + ".width"));
  const uint32_t height = uint32_t(src.count(src.require(node, "height", where), where + ".height"));
  const std::string projection =
      node["projection"] ? src.string(node["projection"], where + ".projection") : "perspective";
  if (projection == "perspective") {
    const YAML::Node fov_node = src.require(node, "fov", where);
    const double fov = src.positive(fov_node, where + ".fov");
    if (fov >= 180) src.fail(fov_node, where + ".fov must be below 180 degrees");
    out.camera = Camera::perspective(width, height, fov * kDegree);
  } else if (projection == "orthographic") {
    out.camera = Camera::orthographic(
        width, height, src.positive(src.require(node, "view_width", where), where + ".view_width"));
  } else {
    src.fail(node["projection"], where + ": projection must be 'perspective' or 'orthographic'");
  }
  const Vec3 eye = src.vec3(src.require(node, "eye", where), where + ".eye");
  const Vec3 target = src.vec3(src.require(node, "target", where), where + ".target");
  if ((eye - target).norm() == 0) src.fail(node["target"], where + ": eye and target coincide");
  const Vec3 up = node["up"] ? src.direction(node["up"], where + ".up") : Vec3::UnitZ();
  out.camera.lookAt(eye, target, up);
  if (node["near"]) out.camera.near_clip = src.number(node["near"], where + ".near");
  if (node["far"]) out.camera.far_clip = src.number(node["far"], where + ".far");
  try {
    out.camera.validate();
  } catch (const std::invalid_argument& e) {
    src.fail(node, where + ": " + e.what());
  }
  return out;
}

/// Splits the sphere patch's surfels into outside/inside parts and builds the border surfels (role 2).
void buildTextureSquare(const TextureSquare& square, double border_spacing, const PatchSurfels& sphere,
                        double sphere_radius, PatchSurfels* outside, PatchSurfels* inside,
                        PatchSurfels border[4]) {
  const Vec3 w = square.direction;
  const Vec3 u = (square.up - square.up.dot(w) * w).normalized(), v = w.cross(u);
  const double t = std::tan(square.half_angle);
  const Vec3 plane_normals[4] = {(u - t * w).normalized(), (-u - t * w).normalized(),
                                 (v - t * w).normalized(), (-v - t * w).normalized()};
  outside->role = inside->role = SurfelRole::kSurface;
  outside->color = sphere.color;
  inside->color = square.color;
  outside->spacing = inside->spacing = sphere.spacing;
  std::vector<size_t> out_ids, in_ids;
  for (size_t i = 0; i < sphere.cloud.size(); ++i) {
    double beyond = -1e300;  // > 0 outside the pyramid
    for (const Vec3& n : plane_normals)
      beyond = std::max(beyond, (sphere.cloud.positions[i] - square.center).dot(n));
    const double margin = kTextureOverlapRadii * sphere.cloud.radii[i];
    if (beyond > -margin) out_ids.push_back(i);
    if (beyond < margin) in_ids.push_back(i);
  }
  outside->cloud = sphere.cloud;
  outside->cloud.select(out_ids);
  inside->cloud = sphere.cloud;
  inside->cloud.select(in_ids);
  // Border: one patch per pyramid plane (so a corner is an exact intersection of two patches, 4.4), surfels
  // on the great-circle arc between the corners, extended by one spacing at both ends.
  const Vec3 sides[4][2] = {{u, v}, {-u, v}, {v, u}, {-v, u}};
  for (int k = 0; k < 4; ++k) {
    const Vec3 a = (w + t * sides[k][0] - t * sides[k][1]).normalized();
    const Vec3 b = (w + t * sides[k][0] + t * sides[k][1]).normalized();
    const double angle = std::acos(std::clamp(a.dot(b), -1.0, 1.0));
    const double step = border_spacing / sphere_radius;
    const int m = std::max(1, int(std::ceil(angle / step)));
    const Vec3 ortho = (b - a.dot(b) * a).normalized();
    border[k].role = SurfelRole::kTextureDiscontinuity;
    border[k].color = square.color;
    border[k].spacing = border_spacing;
    for (int j = -1; j <= m + 1; ++j) {
      const double phi = angle * j / m;
      const Vec3 dir = std::cos(phi) * a + std::sin(phi) * ortho;
      border[k].cloud.positions.push_back(square.center + sphere_radius * dir);
      border[k].cloud.normals.push_back(plane_normals[k]);
      border[k].cloud.radii.push_back(1.5 * std::max(border_spacing, angle * sphere_radius / m));
    }
  }
}

SurfelCloud assemble(const std::vector<PatchSurfels>& parts, std::vector<CsgScenePatch>* patches) {
  bool any_axes = false;
  size_t total = 0;
  for (const PatchSurfels& p : parts) {
    any_axes = any_axes || p.cloud.hasAxes();
    total += p.cloud.size();
  }
  SurfelCloud cloud;
  cloud.positions.reserve(total);
  Attribute& patch_id = cloud.attributes.add(kPatchIdAttribute, ScalarType::kInt32, 1, 0);
  patch_id.resize(total);
  Attribute& role = cloud.attributes.add(kSurfelRoleAttribute, ScalarType::kInt32, 1, 0);
  role.resize(total);
  Attribute* patch_column = cloud.attributes.find(kPatchIdAttribute);
  Attribute* role_column = cloud.attributes.find(kSurfelRoleAttribute);
  for (size_t k = 0; k < parts.size(); ++k) {
    const SurfelCloud& c = parts[k].cloud;
    (*patches)[k].first_surfel = cloud.positions.size();
    (*patches)[k].surfel_count = c.size();
    for (size_t i = 0; i < c.size(); ++i) {
      const size_t j = cloud.positions.size();
      cloud.positions.push_back(c.positions[i]);
      cloud.normals.push_back(c.normals[i]);
      cloud.radii.push_back(c.radii[i]);
      cloud.colors.push_back(parts[k].color);
      if (any_axes) {
        if (c.hasAxes()) {
          cloud.axes1.push_back(c.axes1[i]);
          cloud.axes2.push_back(c.axes2[i]);
        } else {
          const Vec3 t1 = anyOrthogonal(c.normals[i]);
          cloud.axes1.push_back(c.radii[i] * t1);
          cloud.axes2.push_back(c.radii[i] * c.normals[i].cross(t1));
        }
      }
      patch_column->set(j, double(k));
      role_column->set(j, double(surfelRoleValue(parts[k].role)));
    }
  }
  cloud.validate();
  return cloud;
}

}  // namespace

Eigen::Isometry3d PatchMotion::at(double t) const {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() = Eigen::AngleAxisd(angular_velocity * t, axis.normalized()).matrix();
  m.translation() = pivot - m.linear() * pivot + velocity * t;
  return m;
}

bool TextureSquare::contains(const Vec3& x) const {
  const Vec3 w = direction;
  const Vec3 u = (up - up.dot(w) * w).normalized(), v = w.cross(u);
  const Vec3 d = x - center;
  const double t = std::tan(half_angle), along = d.dot(w);
  return std::abs(d.dot(u)) <= t * along && std::abs(d.dot(v)) <= t * along;
}

std::map<std::string, int> CsgScene::patchIds() const {
  std::map<std::string, int> ids;
  for (size_t i = 0; i < patches.size(); ++i) ids[patches[i].name] = int(i);
  return ids;
}

CsgTree CsgScene::csgTree() const {
  return CsgTree::parse(csg_expression, patchIds());
}

bool CsgScene::isDynamic() const {
  return std::any_of(patches.begin(), patches.end(), [](const CsgScenePatch& p) { return p.motion.moves(); });
}

void CsgScene::moveTo(double t, SurfelCloud* out) const {
  if (out->size() != surfels.size())
    throw std::invalid_argument("CsgScene::moveTo: `out` is not a copy of the scene");
  for (const CsgScenePatch& patch : patches) {
    if (!patch.motion.moves()) continue;
    const Eigen::Isometry3d m = patch.motion.at(t);
    const Eigen::Matrix3d r = m.linear();
    for (size_t i = patch.first_surfel; i < patch.first_surfel + patch.surfel_count; ++i) {
      out->positions[i] = m * surfels.positions[i];
      out->normals[i] = r * surfels.normals[i];
      if (surfels.hasAxes()) {
        out->axes1[i] = r * surfels.axes1[i];
        out->axes2[i] = r * surfels.axes2[i];
      }
    }
  }
}

SurfelCloud CsgScene::atTime(double t) const {
  SurfelCloud moved = surfels;
  moveTo(t, &moved);
  return moved;
}

std::vector<AnalyticSolid> CsgScene::solidsAt(double t) const {
  std::vector<AnalyticSolid> solids;
  solids.reserve(patches.size());
  for (const CsgScenePatch& patch : patches)
    solids.push_back(patch.motion.moves() ? patch.solid.transformed(patch.motion.at(t)) : patch.solid);
  return solids;
}

AnalyticCsgCaster CsgScene::analyticCaster(double t) const {
  const CsgTree tree = csgTree();
  for (int p : tree.patches())
    if (!patches[p].has_solid)
      throw std::invalid_argument("CsgScene '" + name + "': patch '" + patches[p].name +
                                  "' has no analytic solid (a texture border); use analyticGeometryCaster()");
  return AnalyticCsgCaster(solidsAt(t), tree);
}

AnalyticCsgCaster CsgScene::analyticGeometryCaster(double t) const {
  return AnalyticCsgCaster(solidsAt(t), CsgTree::parse(geometry_expression, patchIds()));
}

CsgScene parseCsgScene(const std::string& yaml_text, const std::string& source_name) {
  const Source src{source_name};
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw std::runtime_error(source_name + ":" + std::to_string(e.mark.line + 1) + ":" +
                             std::to_string(e.mark.column + 1) + ": YAML syntax error: " + e.msg);
  }
  if (!root.IsMap()) src.fail(root, "a scene file must be a YAML map");
  src.allowKeys(root, {"name", "radius_scale", "patches", "csg", "texture_squares", "cameras"}, "scene");

  CsgScene scene;
  scene.path = source_name;
  std::string stem = source_name.substr(source_name.find_last_of('/') + 1);
  stem = stem.substr(0, stem.find_last_of('.'));
  scene.name = root["name"] ? src.string(root["name"], "name") : stem;
  const double radius_scale = root["radius_scale"] ? src.positive(root["radius_scale"], "radius_scale") : 1.5;

  const YAML::Node patch_list = src.require(root, "patches", "scene");
  if (!patch_list.IsSequence() || patch_list.size() == 0)
    src.fail(patch_list, "'patches' must be a non-empty list");
  std::vector<PatchSurfels> parts(patch_list.size());
  scene.patches.resize(patch_list.size());
  std::map<std::string, int> ids;
  for (size_t i = 0; i < patch_list.size(); ++i) {
    try {
      readPatch(src, patch_list[i], i, radius_scale, &scene.patches[i], &parts[i]);
    } catch (const std::invalid_argument& e) {
      src.fail(patch_list[i], e.what());
    }
    if (!ids.emplace(scene.patches[i].name, int(i)).second)
      src.fail(patch_list[i]["name"], "duplicate patch name '" + scene.patches[i].name + "'");
  }

  const YAML::Node csg_node = src.require(root, "csg", "scene");
  scene.geometry_expression = src.string(csg_node, "csg");
  scene.csg_expression = scene.geometry_expression;

  if (const YAML::Node squares = root["texture_squares"]) {
    if (!squares.IsSequence()) src.fail(squares, "'texture_squares' must be a list");
    for (size_t i = 0; i < squares.size(); ++i) {
      const YAML::Node node = squares[i];
      const std::string where = "texture_squares[" + std::to_string(i) + "]";
      src.allowKeys(node, {"name", "patch", "direction", "up", "half_angle", "color", "spacing"}, where);
      TextureSquare square;
      square.name = src.string(src.require(node, "name", where), where + ".name");
      if (!validName(square.name) || ids.count(square.name))
        src.fail(node["name"], where + ": name '" + square.name + "' is invalid or already used");
      const std::string patch_name = src.string(src.require(node, "patch", where), where + ".patch");
      const auto found = ids.find(patch_name);
      if (found == ids.end()) src.fail(node["patch"], where + ": unknown patch '" + patch_name + "'");
      const CsgScenePatch& sphere = scene.patches[found->second];
      if (sphere.solid.kind != AnalyticSolid::Kind::kSphere || sphere.motion.moves())
        src.fail(node["patch"], where + ": patch '" + patch_name + "' must be a static sphere");
      square.sphere_patch = found->second;
      square.center = sphere.solid.center;
      square.direction = src.direction(src.require(node, "direction", where), where + ".direction");
      square.up = src.direction(src.require(node, "up", where), where + ".up");
      if (std::abs(square.up.dot(square.direction)) > 0.99)
        src.fail(node["up"], where + ": 'up' must not be parallel to 'direction'");
      const YAML::Node angle_node = src.require(node, "half_angle", where);
      square.half_angle = src.positive(angle_node, where + ".half_angle") * kDegree;
      if (square.half_angle >= 60 * kDegree)
        src.fail(angle_node, where + ".half_angle must be below 60 degrees");
      if (node["color"]) square.color = src.color(node["color"], where + ".color");
      const double spacing = node["spacing"] ? src.positive(node["spacing"], where + ".spacing")
                                             : parts[square.sphere_patch].spacing;
      PatchSurfels outside, inside, border[4];
      buildTextureSquare(square, spacing, parts[square.sphere_patch], sphere.solid.radius, &outside, &inside,
                         border);
      parts[square.sphere_patch] = outside;
      CsgScenePatch inside_patch = sphere;
      inside_patch.name = patch_name + "_" + square.name;
      inside_patch.color = square.color;
      std::vector<std::string> new_names = {inside_patch.name};
      // The border enters the tree twice (a patch may occur only once): sides <name>_a0..a3 and copies
      // _b0..b3.
      for (const char* copy : {"_a", "_b"})
        for (int k = 0; k < 4; ++k) new_names.push_back(square.name + copy + std::to_string(k));
      for (const std::string& n : new_names)
        if (ids.count(n)) src.fail(node["name"], where + ": patch name '" + n + "' exists");
      square.inside_patch = int(scene.patches.size());
      square.border_patch = square.inside_patch + 1;
      square.border_copy_patch = square.inside_patch + 5;
      for (size_t k = 0; k < new_names.size(); ++k) {
        CsgScenePatch patch = inside_patch;
        if (k > 0) {
          patch = CsgScenePatch();
          patch.name = new_names[k];
          patch.role = SurfelRole::kTextureDiscontinuity;
          patch.has_solid = false;
          patch.color = square.color;
        }
        ids[new_names[k]] = int(scene.patches.size());
        scene.patches.push_back(patch);
        parts.push_back(k == 0 ? inside : border[(k - 1) % 4]);
      }
      scene.texture_squares.push_back(square);
      // Replace the sphere's leaf: ((P_sq | !(a0 & a1 & a2 & a3)) & (P | (b0 & b1 & b2 & b3))).
      const CsgTree original = CsgTree::parse(scene.csg_expression, ids);
      if (original.leafOf(square.sphere_patch) < 0)
        src.fail(node["patch"], where + ": patch '" + patch_name + "' is not in the CSG expression");
      std::string replaced;
      const std::string& e = scene.csg_expression;
      for (size_t p = 0; p < e.size();) {
        const bool starts =
            e.compare(p, patch_name.size(), patch_name) == 0 &&
            (p == 0 || !(std::isalnum((unsigned char)e[p - 1]) || e[p - 1] == '_' || e[p - 1] == '.'));
        const size_t q = p + patch_name.size();
        const bool ends = q >= e.size() || !(std::isalnum((unsigned char)e[q]) || e[q] == '_' || e[q] == '.');
        if (starts && ends) {
          const std::string& a = square.name;
          replaced += "((" + inside_patch.name + " | !(" + a + "_a0 & " + a + "_a1 & " + a + "_a2 & " + a +
                      "_a3)) & (" + patch_name + " | (" + a + "_b0 & " + a + "_b1 & " + a + "_b2 & " + a +
                      "_b3)))";
          p = q;
        } else {
          replaced += e[p++];
        }
      }
      scene.csg_expression = replaced;
    }
  }

  CsgTree tree;
  try {
    tree = CsgTree::parse(scene.csg_expression, ids);
    (void)CsgTree::parse(scene.geometry_expression, ids);
  } catch (const std::invalid_argument& e) {
    src.fail(csg_node, std::string("csg: ") + e.what());
  }
  const std::vector<int> used = tree.patches();
  for (size_t i = 0; i < scene.patches.size(); ++i)
    if (!std::binary_search(used.begin(), used.end(), int(i)))
      src.fail(csg_node,
               "csg: patch '" + scene.patches[i].name + "' is not used in \"" + scene.csg_expression + "\"");

  const YAML::Node camera_list = src.require(root, "cameras", "scene");
  if (!camera_list.IsSequence() || camera_list.size() == 0)
    src.fail(camera_list, "'cameras' must be a non-empty list");
  for (size_t i = 0; i < camera_list.size(); ++i) scene.cameras.push_back(readCamera(src, camera_list[i], i));

  scene.surfels = assemble(parts, &scene.patches);
  return scene;
}

CsgScene loadCsgScene(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open scene file");
  std::stringstream text;
  text << in.rdbuf();
  return parseCsgScene(text.str(), path);
}

}  // namespace rc
