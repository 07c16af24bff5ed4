#include "relaxed_connectivity/sph/sph_scene_run.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "relaxed_connectivity/io/obj_io.h"
#include "relaxed_connectivity/io/ply_io.h"
#include "relaxed_connectivity/io/pvd_io.h"
#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_fluid_source.h"
#include "relaxed_connectivity/sph/sph_output.h"
#include "relaxed_connectivity/sph/sph_probes.h"
#include "relaxed_connectivity/sph/sph_simulation.h"
#include "relaxed_connectivity/sph/sph_skinning.h"
#include "relaxed_connectivity/sph/sph_surface.h"

namespace rc {

namespace {

/// A frame is finished with SphFluidSolver::advance once the time left is within this many steps.
constexpr double kFinishWithinSteps = 4.0;

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct FluidMeasures {
  double mass = 0.0, potential = 0.0;
  Vec3 momentum = Vec3::Zero();
};

FluidMeasures measureFluid(const SphParticles& p, const Vec3& gravity) {
  FluidMeasures m;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.kinds[i] != SphParticleKind::kFluid) continue;
    m.mass += p.masses[i];
    m.momentum += p.masses[i] * p.velocities[i];
    m.potential -= p.masses[i] * gravity.dot(p.positions[i]);
  }
  return m;
}

/// Writes the particle files of one output frame.
class FrameWriter {
 public:
  FrameWriter(const SphScene& scene, const std::string& out_dir, SphRunStats* stats,
              const SphThermalModel* thermal)
      : scene_(scene), dir_(out_dir), stats_(*stats), thermal_(thermal) {
    active_ = !out_dir.empty() && scene.output.enabled();
    surface_ = !out_dir.empty() && scene.surface.enabled && (scene.surface.obj || scene.surface.ply);
    if (!out_dir.empty())
      for (const SphSceneSkin& skin : scene.skins) skins_.push_back(skin.skin);
    probes_ = !out_dir.empty() && scene.probes.enabled;
    if (active_ || surface_ || probes_ || !skins_.empty()) std::filesystem::create_directories(dir_);
    if (probes_) {
      probe_path_ = (dir_ / (scene.name + "_probes.csv")).string();
      probe_file_.open(probe_path_);
      if (!probe_file_) throw std::runtime_error(probe_path_ + ": cannot open for writing");
      writeSphProbeHeader(probe_file_, scene.probes.points.size());
      stats_.files.push_back(probe_path_);
    }
  }

  void maybeWrite(int frame, const SphFluidSolver& solver) {
    writeProbes(solver);
    maybeWriteSurface(frame, solver);
    maybeWriteSkins(frame, solver);
    if (!active_ || frame % scene_.output.every != 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    char stem[64];
    std::snprintf(stem, sizeof(stem), "_%04d", frame);
    const std::string base = scene_.name + stem;
    if (scene_.output.ply) {
      const std::string path = (dir_ / (base + ".ply")).string();
      writeSphPly(path, solver.particles(), temperatures(solver), dockedPoints(solver));
      stats_.files.push_back(path);
    }
    if (scene_.output.vtp) {
      const std::string path = (dir_ / (base + ".vtp")).string();
      writeSphVtp(path, solver.particles(), VtpEncoding::kAppendedRaw, temperatures(solver),
                  dockedPoints(solver));
      stats_.files.push_back(path);
      pvd_.push_back({base + ".vtp", solver.time()});
      const std::string pvd = (dir_ / (scene_.name + ".pvd")).string();
      writePvd(pvd, pvd_);  // rewritten each time: a stopped run stays viewable
      if (pvd_.size() == 1) stats_.files.push_back(pvd);
    }
    stats_.output_seconds += secondsSince(t0);
  }

 private:
  /// The thermal model's temperatures, grown to the particle count (nullptr without temperature).
  const std::vector<double>* temperatures(const SphFluidSolver& solver) {
    if (!thermal_) return nullptr;
    temperatures_ = thermal_->temperatures();
    temperatures_.resize(solver.particles().size(), thermal_->config().initial_temperature);
    return &temperatures_;
  }

  /// Docked lattice points per particle of the solids with fracture (nullptr if none has it).
  const std::vector<uint32_t>* dockedPoints(const SphFluidSolver& solver) {
    return sphDockedPoints(solver, docked_) ? &docked_ : nullptr;
  }

  /// One row of <name>_probes.csv.
  void writeProbes(const SphFluidSolver& solver) {
    if (!probes_) return;
    const auto t0 = std::chrono::steady_clock::now();
    const SphKernels kernels(solver.config().dimension, solver.config().smoothing_length);
    std::vector<SphPointSample> samples;
    for (const Vec3& point : scene_.probes.points)
      samples.push_back(sampleSphPoint(solver.particles(), kernels, point));
    writeSphProbeRow(probe_file_, solver.time(), measureSphBody(solver.particles()), samples);
    probe_file_.flush();
    if (!probe_file_) throw std::runtime_error(probe_path_ + ": write failed");
    stats_.output_seconds += secondsSince(t0);
  }

  /// Marching cubes surface of the frame (8.2.7): <name>_surface_NNNN.obj / .ply.
  void maybeWriteSurface(int frame, const SphFluidSolver& solver) {
    if (!surface_ || frame % scene_.surface.every != 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    char stem[64];
    std::snprintf(stem, sizeof(stem), "_surface_%04d", frame);
    const std::string base = scene_.name + stem;
    SphSurfaceConfig config = scene_.surface.config;
    config.num_threads = solver.config().num_threads;
    const TriangleMesh mesh = extractSphSurface(solver.particles(), config);
    if (scene_.surface.obj) {
      const std::string path = (dir_ / (base + ".obj")).string();
      writeObjMesh(path, mesh);
      stats_.files.push_back(path);
    }
    if (scene_.surface.ply) {
      const std::string path = (dir_ / (base + ".ply")).string();
      writePlyMesh(path, mesh);
      stats_.files.push_back(path);
    }
    stats_.output_seconds += secondsSince(t0);
  }

  /// Skinned surfaces of the frame (8.38): <name>_skin<k>_NNNN.obj / .ply for solid k.
  void maybeWriteSkins(int frame, const SphFluidSolver& solver) {
    for (size_t s = 0; s < skins_.size(); ++s) {
      const SphSceneSkin& entry = scene_.skins[s];
      if (frame % entry.every != 0) continue;
      const auto t0 = std::chrono::steady_clock::now();
      SphSkin& skin = skins_[s];
      const std::vector<Vec3>& positions = solver.particles().positions;
      if (entry.lattice_transforms)
        skin.deform(positions, latticeTransforms(solver, scene_.solids[entry.solid]));
      else
        skin.deform(positions);
      skin.deformMesh(entry.rest, skin_mesh_);
      char stem[64];
      std::snprintf(stem, sizeof(stem), "_skin%zu_%04d", entry.solid, frame);
      const std::string base = scene_.name + stem;
      if (entry.obj) {
        const std::string path = (dir_ / (base + ".obj")).string();
        writeObjMesh(path, skin_mesh_);
        stats_.files.push_back(path);
      }
      if (entry.ply) {
        const std::string path = (dir_ / (base + ".ply")).string();
        writePlyMesh(path, skin_mesh_);
        stats_.files.push_back(path);
      }
      stats_.output_seconds += secondsSince(t0);
    }
  }

  /// The lattice transforms A_i of the solver's SphElasticSolid of `solid`; before its first evaluation
  /// the rest transforms (its orientation), which leave the skin at rest.
  const std::vector<Eigen::Matrix3d>& latticeTransforms(const SphFluidSolver& solver,
                                                        const SphSceneSolid& solid) {
    const size_t n = solver.particles().size();
    for (const auto& term : solver.forceTerms()) {
      const auto* elastic = dynamic_cast<const SphElasticSolid*>(term.get());
      if (elastic && elastic->phase() == solid.phase && elastic->latticeTransforms().size() == n)
        return elastic->latticeTransforms();
    }
    rest_transforms_.assign(n, solid.orientation);
    return rest_transforms_;
  }

  const SphScene& scene_;
  bool probes_ = false;
  std::string probe_path_;
  std::ofstream probe_file_;
  std::filesystem::path dir_;
  SphRunStats& stats_;
  bool active_ = false, surface_ = false;
  std::vector<SphSkin> skins_;  // copies of the scene's bound skins (deform() keeps state)
  TriangleMesh skin_mesh_;
  std::vector<Eigen::Matrix3d> rest_transforms_;
  const SphThermalModel* thermal_;
  std::vector<double> temperatures_;
  std::vector<uint32_t> docked_;
  std::vector<PvdEntry> pvd_;
};

void appendNumber(std::string& out, const char* key, double v) {
  char buf[64];
  if (std::isfinite(v))
    std::snprintf(buf, sizeof(buf), "\"%s\":%.6g", key, v);
  else
    std::snprintf(buf, sizeof(buf), "\"%s\":null", key);
  if (out.size() > 1) out += ',';
  out += buf;
}

void appendString(std::string& out, const char* key, const std::string& s) {
  if (out.size() > 1) out += ',';
  out += '"';
  out += key;
  out += "\":\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (static_cast<unsigned char>(ch) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\u%04x", unsigned(ch));
      out += buf;
    } else {
      out += ch;
    }
  }
  out += '"';
}

void appendVector(std::string& out, const char* key, const Vec3& v) {
  char buf[128];
  auto num = [](double x) {
    char b[32];
    if (std::isfinite(x))
      std::snprintf(b, sizeof(b), "%.6g", x);
    else
      std::snprintf(b, sizeof(b), "null");
    return std::string(b);
  };
  std::snprintf(buf, sizeof(buf), "\"%s\":[%s,%s,%s]", key, num(v.x()).c_str(), num(v.y()).c_str(),
                num(v.z()).c_str());
  if (out.size() > 1) out += ',';
  out += buf;
}

}  // namespace

SphRunStats runSphScene(const SphScene& scene, SphFluidSolver& solver, const SphRunOptions& options) {
  SphSimulation simulation(scene, solver, options.thermal);
  return runSphScene(simulation, options);
}

SphRunStats runSphScene(SphSimulation& simulation, const SphRunOptions& options) {
  SphRunStats stats;
  const SphScene& scene = simulation.scene();
  SphFluidSolver& solver = simulation.solver();
  // Temperature (8.2.4) and fluid sources after every solver step; sources also emit before the first.
  SphSimulation& stepper = simulation;
  const std::shared_ptr<SphThermalModel>& thermal = stepper.thermal();
  const std::vector<SphFluidSource>& sources = stepper.sources();
  stats.thermal = thermal != nullptr;
  if (thermal) stats.heat_start = thermal->totalHeat(solver.particles());
  std::function<void(const SphStepStats&)> after_step;
  if (stepper.active()) after_step = [&](const SphStepStats& st) { stepper.afterStep(st); };
  stats.scene = scene.name;
  stats.particles = solver.particles().size();
  stats.sources = sources.size();
  std::vector<const SphElasticSolid*> solids;
  for (const auto& term : solver.forceTerms())
    if (const auto* solid = dynamic_cast<const SphElasticSolid*>(term.get())) solids.push_back(solid);
  stats.solids = solids.size();
  for (size_t i = 0; i < solver.particles().size(); ++i) {
    if (solver.particles().kinds[i] != SphParticleKind::kFluid) continue;
    ++(solver.particles().phases[i] == 0 ? stats.fluid_particles : stats.solid_particles);
  }
  stats.frame_count = scene.frame_count;
  stats.threads = solver.config().num_threads > 0 ? solver.config().num_threads : omp_get_max_threads();
  stats.min_dt = std::numeric_limits<double>::infinity();
  const Vec3 gravity = solver.config().gravity;
  const FluidMeasures start = measureFluid(solver.particles(), gravity);
  stats.momentum_start = start.momentum;
  const uint64_t first_step = solver.stepCount();
  const double start_time = solver.time();
  if (!sources.empty()) stepper.emit(start_time);
  FrameWriter writer(scene, options.out_dir, &stats, thermal.get());
  writer.maybeWrite(0, solver);

  bool have_energy = false;
  double energy_first = 0.0;
  auto energyNow = [&](const SphStepStats& st) {
    return st.kinetic_energy + st.compression_energy + st.term_energy +
           measureFluid(solver.particles(), gravity).potential;
  };
  auto record = [&](const SphStepStats& st) {
    stats.max_density_error = std::max(stats.max_density_error, st.max_density_error);
    for (const SphElasticSolid* solid : solids)
      stats.max_strain = std::max(stats.max_strain, solid->stats().max_strain);
    if (!have_energy) {
      energy_first = energyNow(st);
      have_energy = true;
    }
    if (st.unstable && stats.instability.empty()) {  // only when the solver does not throw
      stats.instability = st.instability;
      stats.instability_step = st.step;
    }
  };

  auto step_started = std::chrono::steady_clock::now();
  double frame_seconds = 0.0;
  double last_dt = 0.0;
  SphStepLimit last_limit = SphStepLimit::kMaxDt;
  try {
    for (int frame = 1; frame <= scene.frame_count; ++frame) {
      // The end time as SphFluidSolver::advance(frame_time) computes it.
      const double frame_end = solver.time() + scene.frame_time;
      const uint64_t frame_first = solver.stepCount();
      frame_seconds = 0.0;
      while (solver.time() < frame_end) {
        const double remaining = frame_end - solver.time();
        if (last_dt > 0.0 && remaining <= kFinishWithinSteps * last_dt) {
          // advance() shortens the last step to end on frame_end; for time >= frame_end / 2 the difference
          // above is exact (Sterbenz), so advance() ends on the same frame_end.
          const uint64_t before = solver.stepCount();
          step_started = std::chrono::steady_clock::now();
          const SphStepStats& st = solver.advance(remaining, after_step);
          const double seconds = secondsSince(step_started);
          frame_seconds += seconds;
          const uint64_t steps = solver.stepCount() - before;
          if (steps > 0) stats.max_step_us = std::max(stats.max_step_us, 1e6 * seconds / double(steps));
          record(st);
          break;
        }
        step_started = std::chrono::steady_clock::now();
        const SphStepStats& st =
            solver.stepUntil(frame_end);  // (a first step longer than the frame ends on it)
        frame_seconds += st.seconds;
        if (after_step) {
          const auto thermal_started = std::chrono::steady_clock::now();
          after_step(st);
          frame_seconds += secondsSince(thermal_started);
        }
        stats.max_step_us = std::max(stats.max_step_us, 1e6 * st.seconds);
        stats.min_dt = std::min(stats.min_dt, st.dt);
        last_dt = st.dt;
        last_limit = st.limit;
        record(st);
      }
      stats.wall_seconds += frame_seconds;
      stats.frames = frame;
      writer.maybeWrite(frame, solver);
      if (options.on_frame) {
        SphFrameReport report;
        report.frame = frame;
        report.frame_count = scene.frame_count;
        report.steps = solver.stepCount() - first_step;
        report.frame_steps = solver.stepCount() - frame_first;
        report.time = solver.time();
        report.dt = last_dt;
        report.limit = last_limit;
        report.frame_seconds = frame_seconds;
        options.on_frame(report);
      }
      if (!stats.instability.empty()) break;
    }
  } catch (const SphInstabilityError& e) {
    stats.wall_seconds += frame_seconds + secondsSince(step_started);  // the frame so far and the failed step
    stats.instability = e.what();
    stats.instability_step = e.step();
  }

  stats.steps = solver.stepCount() - first_step;
  stats.simulated_time = solver.time() - start_time;
  if (stats.steps > 0) {
    stats.mean_dt = stats.simulated_time / double(stats.steps);
    stats.mean_step_us = 1e6 * stats.wall_seconds / double(stats.steps);
    const double mean_particles =
        sources.empty() ? double(stats.particles) : stepper.particleSteps() / double(stats.steps);
    stats.us_per_particle_step = stats.mean_step_us / std::max(mean_particles, 1.0);
  }
  if (!std::isfinite(stats.min_dt)) stats.min_dt = stats.mean_dt;
  const FluidMeasures end = measureFluid(solver.particles(), gravity);
  stats.particles_end = solver.particles().size();
  for (const SphFluidSource& source : sources) {
    stats.emitted += source.stats().emitted;
    stats.emitted_mass += source.stats().emitted_mass;
    stats.source_skipped += source.stats().skipped;
  }
  if (sources.empty()) {
    stats.mass_drift = start.mass > 0.0 ? (end.mass - start.mass) / start.mass : 0.0;
    stats.boundary_impulse = end.momentum - start.momentum - start.mass * gravity * stats.simulated_time;
  } else {
    const double base = start.mass > 0.0 ? start.mass : stats.emitted_mass;
    stats.mass_drift = base > 0.0 ? (end.mass - start.mass - stats.emitted_mass) / base : 0.0;
    // Gravity acted on each emitted particle from its emission on: g sum m (t_end - t).
    const double emitted_gravity_time = stats.emitted_mass * solver.time() - stepper.emittedMassTime();
    stats.boundary_impulse = end.momentum - start.momentum - stepper.emittedMomentum() -
                             gravity * (start.mass * stats.simulated_time + emitted_gravity_time);
  }
  stats.momentum_end = end.momentum;
  stats.energy_first = stats.energy_end = stats.energy_change = std::numeric_limits<double>::quiet_NaN();
  stats.elastic_energy = std::numeric_limits<double>::quiet_NaN();
  if (have_energy) {
    const SphStepStats& last = solver.lastStats();
    stats.energy_first = energy_first;
    stats.energy_end = last.kinetic_energy + last.compression_energy + last.term_energy + end.potential;
    stats.elastic_energy = last.term_energy;
    stats.energy_change =
        (stats.energy_end - stats.energy_first) / std::max(std::abs(stats.energy_first), 1e-300);
  }
  stats.melted = stepper.melted();
  stats.frozen = stepper.frozen();
  if (thermal) {
    stats.heat_end = thermal->totalHeat(solver.particles());
    stats.min_temperature = std::numeric_limits<double>::infinity();
    stats.max_temperature = -std::numeric_limits<double>::infinity();
    const SphParticles& p = solver.particles();
    for (size_t i = 0; i < p.size() && i < thermal->temperatures().size(); ++i) {
      if (p.kinds[i] != SphParticleKind::kFluid) continue;
      stats.min_temperature = std::min(stats.min_temperature, thermal->temperatures()[i]);
      stats.max_temperature = std::max(stats.max_temperature, thermal->temperatures()[i]);
    }
  }
  return stats;
}

std::string sphRunStatsJson(const SphRunStats& s) {
  std::string out = "{";
  appendString(out, "scene", s.scene);
  appendNumber(out, "particles", double(s.particles));
  appendNumber(out, "fluid_particles", double(s.fluid_particles));
  appendNumber(out, "particles_end", double(s.particles_end));
  if (s.sources > 0) {
    appendNumber(out, "sources", double(s.sources));
    appendNumber(out, "emitted", double(s.emitted));
    appendNumber(out, "emitted_mass", s.emitted_mass);
    appendNumber(out, "source_skipped", double(s.source_skipped));
  }
  appendNumber(out, "frames", s.frames);
  appendNumber(out, "frame_count", s.frame_count);
  appendNumber(out, "steps", double(s.steps));
  appendNumber(out, "threads", s.threads);
  appendNumber(out, "simulated_time_s", s.simulated_time);
  appendNumber(out, "mean_dt_s", s.mean_dt);
  appendNumber(out, "min_dt_s", s.min_dt);
  appendNumber(out, "mean_step_us", s.mean_step_us);
  appendNumber(out, "max_step_us", s.max_step_us);
  appendNumber(out, "us_per_particle_step", s.us_per_particle_step);
  appendNumber(out, "wall_s", s.wall_seconds);
  appendNumber(out, "output_s", s.output_seconds);
  appendNumber(out, "mass_drift", s.mass_drift);
  appendVector(out, "momentum_start", s.momentum_start);
  appendVector(out, "momentum_end", s.momentum_end);
  appendVector(out, "boundary_impulse", s.boundary_impulse);
  appendNumber(out, "energy_first", s.energy_first);
  appendNumber(out, "energy_end", s.energy_end);
  appendNumber(out, "energy_change", s.energy_change);
  appendNumber(out, "max_density_error", s.max_density_error);
  if (s.solids > 0) {
    appendNumber(out, "solids", double(s.solids));
    appendNumber(out, "solid_particles", double(s.solid_particles));
    appendNumber(out, "elastic_energy", s.elastic_energy);
    appendNumber(out, "max_strain", s.max_strain);
  }
  if (s.thermal) {
    appendNumber(out, "heat_start", s.heat_start);
    appendNumber(out, "heat_end", s.heat_end);
    appendNumber(out, "min_temperature", s.min_temperature);
    appendNumber(out, "max_temperature", s.max_temperature);
    appendNumber(out, "melted", double(s.melted));
    appendNumber(out, "frozen", double(s.frozen));
  }
  appendNumber(out, "files", double(s.files.size()));
  appendString(out, "instability", s.instability.empty() ? "none" : s.instability);
  if (!s.instability.empty()) appendNumber(out, "instability_step", double(s.instability_step));
  out += "}";
  return out;
}

}  // namespace rc
