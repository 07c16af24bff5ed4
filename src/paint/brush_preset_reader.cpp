#include "relaxed_connectivity/paint/brush_preset_reader.h"

#include <cmath>
#include <sstream>

#include "relaxed_connectivity/io/yaml_reader.h"
#include "relaxed_connectivity/paint/brush_skeleton.h"

namespace rc {

namespace {

[[noreturn]] void raiseBrushPresetError(const std::string& message) {
  throw BrushPresetError(message);
}

}  // namespace

BrushPreset parseBrushPreset(const std::string& yaml_text, const std::string& source_name) {
  const YamlReader src(source_name, raiseBrushPresetError);
  const YAML::Node root = src.parseMap(yaml_text, "a brush preset must be a map of settings");
  src.allowKeys(root,
                {"name",
                 "shape",
                 "bristle_length",
                 "radius",
                 "thickness",
                 "segments",
                 "chains",
                 "handle_ring",
                 "mass",
                 "spring_stiffness",
                 "damping",
                 "surfel_spacing",
                 "friction",
                 "penalty_stiffness",
                 "integrator",
                 "time_step",
                 "gravity",
                 "collision_neighbors",
                 "split_angle_deg",
                 "paint_colour",
                 "paint_volume"},
                "brush preset");
  BrushPreset p;
  if (root["name"]) p.name = src.string(root["name"], "name");
  if (root["shape"])
    p.shape = src.choice<BrushShape>(root["shape"], "shape",
                                     {{"round", BrushShape::kRound}, {"flat", BrushShape::kFlat}});
  const auto positive = [&](const char* key, double* value) {
    if (root[key]) *value = src.positive(root[key], key);
  };
  const auto non_negative = [&](const char* key, double* value) {
    if (root[key]) *value = src.nonNegative(root[key], key);
  };
  const auto integer = [&](const char* key, int* value, long lo, long hi) {
    if (root[key]) *value = int(src.integer(root[key], key, lo, hi));
  };
  positive("bristle_length", &p.bristle_length);
  positive("radius", &p.radius);
  positive("thickness", &p.thickness);
  integer("segments", &p.segments, 1, 16);
  integer("chains", &p.chains, 1, 32);
  integer("handle_ring", &p.handle_ring, 3, 32);
  positive("mass", &p.mass);
  positive("spring_stiffness", &p.spring_stiffness);
  non_negative("damping", &p.damping);
  positive("surfel_spacing", &p.surfel_spacing);
  non_negative("friction", &p.friction);
  non_negative("penalty_stiffness", &p.penalty_stiffness);
  if (root["integrator"])
    p.integrator = src.choice<BrushIntegrator>(
        root["integrator"], "integrator",
        {{"verlet", BrushIntegrator::kVerlet}, {"implicit_euler", BrushIntegrator::kImplicitEuler}});
  positive("time_step", &p.time_step);
  if (root["gravity"]) p.gravity = src.vec3(root["gravity"], "gravity");
  integer("collision_neighbors", &p.collision_neighbors, 2, 64);
  if (root["split_angle_deg"]) {
    p.split_angle_deg = src.number(root["split_angle_deg"], "split_angle_deg");
    if (!(p.split_angle_deg > 0 && p.split_angle_deg < 180))
      src.fail(root["split_angle_deg"],
               "split_angle_deg must lie in (0, 180), got " + std::to_string(p.split_angle_deg));
  }
  if (root["paint_colour"]) {
    p.paint_colour = src.vec3(root["paint_colour"], "paint_colour");
    if ((p.paint_colour.array() < 0).any() || (p.paint_colour.array() > 1).any())
      src.fail(root["paint_colour"], "paint_colour components must lie in [0, 1]");
  }
  non_negative("paint_volume", &p.paint_volume);
  // (found by fuzz_yaml_readers: 32 chains of 16 masses made the step-limit eigen-problem 1,536 x 1,536, over
  // a second to read a preset)
  constexpr int kMaxActiveMasses = 128;
  if (p.chains * p.segments > kMaxActiveMasses)
    src.fail(root["chains"] ? root["chains"] : root,
             "chains x segments = " + std::to_string(p.chains * p.segments) + " bristle masses, more than " +
                 std::to_string(kMaxActiveMasses));
  if (p.surfel_spacing > p.bristle_length)
    src.fail(root["surfel_spacing"] ? root["surfel_spacing"] : root,
             "surfel_spacing must not exceed bristle_length");
  // The explicit step limit of this skeleton (stability at the extreme: a stiff preset is refused, not run).
  const std::string step_problem = brushStepLimitProblem(p);
  if (!step_problem.empty()) src.fail(root["time_step"] ? root["time_step"] : root, step_problem);
  return p;
}

std::string brushStepLimitProblem(const BrushPreset& p) {
  if (p.integrator != BrushIntegrator::kVerlet) return "";
  const double limit = BrushSkeleton(p).stepLimit();
  if (p.time_step <= limit) return "";
  std::ostringstream why;
  why << "time_step " << p.time_step << " s exceeds the skeleton's explicit step limit " << limit
      << " s (spring_stiffness " << p.spring_stiffness << " N/m, mass " << p.mass
      << " kg): lower time_step or stiffness, raise mass, or use integrator: implicit_euler";
  return why.str();
}

BrushPreset readBrushPreset(const std::string& path) {
  return parseBrushPreset(YamlReader::readFile(path, raiseBrushPresetError), path);
}

}  // namespace rc
