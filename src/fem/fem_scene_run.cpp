#include "relaxed_connectivity/fem/fem_scene_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "relaxed_connectivity/fem/fem_modal.h"
#include "relaxed_connectivity/fem/fem_static.h"
#include "relaxed_connectivity/io/pvd_io.h"

namespace rc {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
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

std::string vec3Json(const Vec3& v) {
  return "[" + formatNumber(v.x()) + "," + formatNumber(v.y()) + "," + formatNumber(v.z()) + "]";
}

/// ,"analysis":"static","max_displacement":..,"held_reactions":[[..],..],"load_displacements":[[..],..]
std::string staticJson(const FemRunStats& s) {
  std::string j = ",\"analysis\":\"static\",\"max_displacement\":" + formatNumber(s.max_displacement) +
                  ",\"held_reactions\":[";
  for (size_t k = 0; k < s.held_reactions.size(); ++k) j += (k ? "," : "") + vec3Json(s.held_reactions[k]);
  j += "],\"load_displacements\":[";
  for (size_t k = 0; k < s.load_displacements.size(); ++k)
    j += (k ? "," : "") + vec3Json(s.load_displacements[k]);
  return j + "]";
}

/// ,"analysis":"modal","frequencies":[..]
std::string modalJson(const FemRunStats& s) {
  std::string j = ",\"analysis\":\"modal\",\"frequencies\":[";
  for (size_t k = 0; k < s.frequencies.size(); ++k) j += (k ? "," : "") + formatNumber(s.frequencies[k]);
  return j + "]";
}

/// The frames of a one-solve analysis (frame k: the node positions frames[k]) as VTU / OBJ files with a PVD
/// index (time = frame number), as the scene's output asks.
void writeSolveFrames(const FemScene& scene, const FemRunOptions& options,
                      const std::vector<Eigen::VectorXd>& frames, FemRunStats& stats) {
  if (options.out_dir.empty() || scene.output.every <= 0 || !(scene.output.vtu || scene.output.obj)) return;
  const Clock::time_point start = Clock::now();
  const std::filesystem::path dir(options.out_dir);
  std::filesystem::create_directories(dir);
  const Eigen::VectorXd velocities = Eigen::VectorXd::Zero(3 * scene.mesh->numNodes());
  std::vector<PvdEntry> pvd;
  for (size_t frame = 0; frame < frames.size(); ++frame) {
    const std::vector<FemBodyState> states = {{scene.mesh.get(), &frames[frame], &velocities}};
    char number[32];
    std::snprintf(number, sizeof(number), "%04zu", frame);
    if (scene.output.vtu) {
      const std::string file = scene.name + "_" + number + ".vtu";
      writeFemVtu((dir / file).string(), states, scene.output.encoding);
      stats.files.push_back((dir / file).string());
      pvd.push_back({file, double(frame)});
    }
    if (scene.output.obj) {
      const std::string file = (dir / (scene.name + "_surface_" + number + ".obj")).string();
      writeFemObj(file, states);
      stats.files.push_back(file);
    }
  }
  if (!pvd.empty()) {
    const std::string pvd_path = (dir / (scene.name + ".pvd")).string();
    writePvd(pvd_path, pvd);
    stats.files.push_back(pvd_path);
  }
  stats.times.output = secondsSince(start);
}

/// The statistics of a one-solve analysis before it runs: the scene, its single body and its frame count.
FemRunStats oneSolveStats(const FemScene& scene, int frame_count) {
  FemRunStats stats;
  stats.scene = scene.name;
  stats.frame_count = frame_count;
  stats.nodes_start = stats.nodes = scene.mesh->numNodes();
  stats.elements_start = stats.elements = scene.mesh->numElements();
  stats.bodies = 1;
  return stats;
}

/// *result = solve(); an exception becomes the run's error (then false).
template <class Result, class Solve>
bool tryToSolve(FemRunStats* stats, Result* result, Solve&& solve) {
  try {
    *result = solve();
    return true;
  } catch (const std::exception& e) {
    stats->error = e.what();
    return false;
  }
}

/// analysis: static: one solve, the rest state and the equilibrium as frames 0 and 1.
FemRunStats runFemStatic(const FemScene& scene, const FemRunOptions& options) {
  FemRunStats stats = oneSolveStats(scene, 1);
  stats.static_analysis = true;
  FemStaticResult result;
  if (!tryToSolve(&stats, &result, [&] { return solveFemStatic(scene); })) return stats;
  stats.frames = 1;
  stats.max_displacement = result.max_displacement;
  stats.held_reactions = result.held_reactions;
  stats.load_displacements = result.load_displacements;
  stats.times.solve = stats.wall_seconds = result.seconds;
  const int n = scene.mesh->numNodes();
  Eigen::VectorXd rest(3 * n);
  for (int i = 0; i < n; ++i) rest.segment<3>(3 * i) = scene.mesh->node(i);
  writeSolveFrames(scene, options, {rest, rest + result.displacements}, stats);
  return stats;
}

/// analysis: modal: the rest state (frame 0) and the mode shapes (frames 1..modes, each scaled to a tenth of
/// the mesh's diagonal).
FemRunStats runFemModal(const FemScene& scene, const FemRunOptions& options) {
  FemRunStats stats = oneSolveStats(scene, scene.modes);
  stats.modal_analysis = true;
  FemModalResult result;
  if (!tryToSolve(&stats, &result, [&] { return solveFemModal(scene); })) return stats;
  stats.frames = scene.modes;
  stats.frequencies.assign(result.frequencies.data(), result.frequencies.data() + result.frequencies.size());
  stats.times.solve = stats.wall_seconds = result.seconds;
  const int n = scene.mesh->numNodes();
  Eigen::VectorXd rest(3 * n);
  Vec3 lo = scene.mesh->node(0), hi = lo;
  for (int i = 0; i < n; ++i) {
    rest.segment<3>(3 * i) = scene.mesh->node(i);
    lo = lo.cwiseMin(scene.mesh->node(i));
    hi = hi.cwiseMax(scene.mesh->node(i));
  }
  const double amplitude = 0.1 * (hi - lo).norm();
  std::vector<Eigen::VectorXd> frames = {rest};
  for (int m = 0; m < scene.modes; ++m) {
    const Eigen::VectorXd mode = result.modes.col(m);
    double largest = 0;
    for (int i = 0; i < n; ++i) largest = std::max(largest, mode.segment<3>(3 * i).norm());
    frames.push_back(largest > 0 ? Eigen::VectorXd(rest + (amplitude / largest) * mode) : rest);
  }
  writeSolveFrames(scene, options, frames, stats);
  return stats;
}

}  // namespace

FemRunStats runFemScene(const FemScene& scene, const FemRunOptions& options) {
  if (scene.analysis == FemAnalysis::kStatic) return runFemStatic(scene, options);
  if (scene.analysis == FemAnalysis::kModal) return runFemModal(scene, options);
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
  // Probes: a CSV row at the start and after every frame.
  std::ofstream probes;
  const double probe_tolerance = femBoxTolerance(*scene.mesh);
  auto probe = [&] {
    if (!probes.is_open()) return;
    std::vector<const WarpedDynamics*> bodies;
    for (int b = 0; b < sim.numBodies(); ++b) bodies.push_back(&sim.body(b));
    std::vector<FemRegionMeasures> regions;
    for (const FemProbe& p : scene.probes) regions.push_back(measureFemRegion(bodies, p, probe_tolerance));
    writeFemProbeRow(probes, sim.time(), measureFemBodies(bodies), regions);
  };
  if (!scene.probes.empty() && !options.out_dir.empty()) {
    std::filesystem::create_directories(options.out_dir);
    const std::string path = (std::filesystem::path(options.out_dir) / (scene.name + "_probes.csv")).string();
    probes.open(path);
    if (!probes) throw std::runtime_error("runFemScene: cannot write " + path);
    writeFemProbeHeader(probes, scene.probes);
    stats.files.push_back(path);
  }
  probe();

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
    probe();
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
    << (s.static_analysis ? staticJson(s) : std::string())
    << (s.modal_analysis ? modalJson(s) : std::string())
    << ",\"error\":" << (s.error.empty() ? std::string("null") : jsonString(s.error))
    << ",\"files\":" << s.files.size() << "}";
  return j.str();
}

}  // namespace rc
