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

void SceneReader::readBlockTemperature(const YAML::Node& node, const std::string& where, size_t first) {
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

void SceneReader::readThermal(const YAML::Node& node) {
  if (node && !enabled("temperature"))
    src_.fail(node, "temperature: needs 'temperature' in the scene's 'enable' list");
  if (!enabled("temperature")) return;
  if (!node) src_.fail(enable_nodes_.at("temperature"), "enable: 'temperature' needs a 'temperature' block");
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

void SceneReader::readPhaseTransition(const YAML::Node& node) {
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
      src_.fail(held_nodes_[i]["phase"], "temperature.held[" + std::to_string(i) +
                                             "].phase: " + std::to_string(p) + " is not the freezing phase");
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

Cylinder SceneReader::readCylinder(const YAML::Node& node, const std::string& where) const {
  if (dimension_ != 3) src_.fail(node, where + ": a cylinder needs a 3D scene (in 2D use a box)");
  Cylinder c;
  c.from = src_.vec(src_.require(node, "from", where), where + ".from", dimension_, false);
  c.to = src_.vec(src_.require(node, "to", where), where + ".to", dimension_, false);
  if (!((c.to - c.from).norm() > 0)) src_.fail(node["to"], where + ": 'from' and 'to' must differ");
  c.radius = src_.positive(src_.require(node, "radius", where), where + ".radius");
  return c;
}

void SceneReader::readSources(const YAML::Node& node) {
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

}  // namespace rc::sph_scene_reading
