// SPH with elastic solids and temperature (thesis 8.2, Table 8.1). (a) Time per particle per step, median of
// several steps, for three scenes built as scene files (appendix F.2 conventions: rho = 1, Gamma = 1, K = 20,
// xi = 0.1, zeta = 0.01, h = 2 d) at ~10k, ~100k and ~1M particles, 1 and 2 threads, timed over the first
// steps from the start ("lattice": a block at rest on its lattice, ~26-29 neighbours):
//   fluid          a fluid block in a tank of planes,
//   fluid+elastic  the same block with an elastic cube (goal-position model) dropped into it,
//   elastic+temp   an elastic cube on a floor heated to 100 degrees (enable: [temperature]; the thermal model
//                  is stepped and timed after every solver step).
// (a, flowing) The fluid rows in steady state: config/sph/dam_break_3d.yaml scaled to ~10k / 100k / 1M moving
// particles (walls of static boundary particles, not counted in the rate; both counts printed), run once from
// the start to t* = t sqrt(2 g / a) = 4 (the front has hit the far wall and runs up it; a = column width) on
// 2 threads with a coarse step (cfl 0.8; `--warm-cfl C`, `--warm-threads T`, `--tstar 4,8`: more states),
// then each thread count restarts from that saved state and times single steps (`--flow-steps N`): neighbours
// per moving particle, dt and its limit, us per moving particle-step, x threads, the state reached (front,
// run-up, energies, pairing). `--flowing`: only these rows; `--no-flowing`: without them; `--plane-walls`: a
// tank of planes instead (every particle moves); `--state-dir DIR`: warm states saved to / reused from DIR
// (the 1M warm-up is ~2330 steps of 1.3M particles); `--trace`: the state every 0.5 t* of the warm-up (its
// steps then end on those marks: the states differ from a run without it in the last bits).
// (b) The scenes of Table 8.1 (Fig. 8.4 melting bunny 9871 particles 17 s/frame, Fig. 8.5 freezing rod
// 1606-7000 particles 18.2 s/frame, Fig. 8.8 nine dice 2214 particles 18.7 s/frame; Pentium 4, 3 GHz) with
// the shipped scene files run through runSphScene (the Fig. 8.4 and 8.5 scenes over all their frames):
// seconds per frame, steps per frame, dt and its limit, and the speed-up over the thesis. `--quick`: 10k only
// and one frame per scene; `--no-1m`: skip the 1M rows;
// `--dice N`: only the Fig. 8.8 rows, N frames each (`--only TEXT`, repeatable: only the rows whose label
// contains TEXT; without --dice: only table (b), only those rows); `--sizes`: only table (a) (lattice and
// flowing rows); `--threads T`: table (a) with T threads only (default 1 and 2; 1M particles take ~2.5 GB and
// 3 steps per row).
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_object_penalty.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"
#include "relaxed_connectivity/sph/sph_thermal.h"

namespace {

using namespace rc;

const char* kSolverBlock =
    "solver:\n"
    "  smoothing_ratio: 2.0\n"
    "  rest_density: 1\n"
    "  stiffness: 20\n"
    "  gamma: 1\n"
    "  negative_pressure_scale: 0.01\n"
    "  xsph: 0.1\n"
    "  gravity: [0, -9.81, 0]\n";

std::string vec(double x, double y, double z) {
  char b[128];
  std::snprintf(b, sizeof b, "[%.6g, %.6g, %.6g]", x, y, z);
  return b;
}

enum class Kind { kFluid, kFluidElastic, kElasticThermal };

const char* kindName(Kind k) {
  return k == Kind::kFluid ? "fluid" : k == Kind::kFluidElastic ? "fluid + elastic" : "elastic + temperature";
}

/// Scene text with about `target` particles, spacing d = 0.02.
std::string sceneText(Kind kind, size_t target) {
  const double d = 0.02;
  std::string s = "name: bench\ndimension: 3\nspacing: 0.02\n";
  if (kind == Kind::kFluid) {
    // n x n/2 x n fluid block filling the bottom of a tank of n x 2n x n cells.
    const double n = std::round(std::cbrt(2.0 * double(target)));
    s += kSolverBlock;
    s += "fluid:\n  - {lo: " + vec(0, 0, 0) + ", hi: " + vec(n * d, 0.5 * n * d, n * d) + "}\n";
    s += "boundary:\n  box_planes:\n    - {lo: " + vec(0, 0, 0) + ", hi: " + vec(n * d, 2 * n * d, n * d) +
         "}\n";
  } else if (kind == Kind::kFluidElastic) {
    // Fluid n x n/2 x n plus a cube of side n/3 cells just above the surface (the fcc lattice holds ~1.4
    // particles per cubic cell): ~(0.5 + 0.052) n^3 particles.
    const double n = std::round(std::cbrt(double(target) / 0.552));
    const double a = n / 3.0;
    s += "enable: [elasticity]\n";
    s += kSolverBlock;
    s += "fluid:\n  - {lo: " + vec(0, 0, 0) + ", hi: " + vec(n * d, 0.5 * n * d, n * d) + "}\n";
    s += "solids:\n  - {lo: " + vec(a * d, (0.5 * n + 1) * d, a * d) +
         ", hi: " + vec(2 * a * d, (0.5 * n + 1 + a) * d, 2 * a * d) +
         ", model: goal_position, goal_stiffness: 8.0e5}\n";
    s += "boundary:\n  box_planes:\n    - {lo: " + vec(0, 0, 0) + ", hi: " + vec(n * d, 2 * n * d, n * d) +
         "}\n";
  } else {
    // An elastic cube of side a cells (~1.41 a^3 fcc particles) at 0 degrees on a floor heated to 100.
    const double a = std::round(std::cbrt(double(target) / 1.414));
    s += "enable: [elasticity, temperature]\n";
    s += kSolverBlock;
    s += "solids:\n  - {lo: " + vec(0, 0.5 * d, 0) + ", hi: " + vec(a * d, (a + 0.5) * d, a * d) +
         ", model: goal_position, goal_stiffness: 8.0e5, temperature: 0}\n";
    s += "boundary:\n  box_planes:\n    - {lo: " + vec(-a * d, 0, -a * d) +
         ", hi: " + vec(2 * a * d, 3 * a * d, 2 * a * d) + "}\n";
    s += "temperature:\n  conductivity: 0.002\n  heat_capacity: 1\n  initial: 0\n  heated_planes:\n"
         "    - {normal: [0, 1, 0], offset: 0, distance: 0.03, temperature: 100, transfer_rate: 20}\n";
  }
  s += "frames: {count: 1, time: 0.0333333333333}\n";
  return s;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct PerParticle {
  size_t particles = 0, solid_particles = 0;
  double us_per_particle = 0.0, neighbors = 0.0, thermal_share = 0.0, dt = 0.0;
  SphStepLimit limit = SphStepLimit::kMaxDt;
};

/// Median wall time per particle per step (solver step + thermal model step) after one warm-up step.
PerParticle timeScene(const SphScene& scene, int threads, int steps) {
  SphScene copy = scene;
  copy.config.num_threads = threads;
  copy.thermal.config.num_threads = threads;
  omp_set_num_threads(threads);  // the elastic force terms use omp_get_max_threads()
  SphFluidSolver solver = makeSphSolver(copy);
  std::shared_ptr<SphThermalModel> thermal = makeSphThermal(copy, solver);
  auto one = [&](double& thermal_seconds) {
    const auto t0 = std::chrono::steady_clock::now();
    const SphStepStats& st = solver.step();
    const auto t1 = std::chrono::steady_clock::now();
    if (thermal) thermal->step(solver, st.dt);
    const auto t2 = std::chrono::steady_clock::now();
    thermal_seconds = std::chrono::duration<double>(t2 - t1).count();
    return std::chrono::duration<double>(t2 - t0).count();
  };
  double th = 0.0;
  one(th);
  std::vector<double> t, tt;
  for (int s = 0; s < steps; ++s) {
    t.push_back(one(th));
    tt.push_back(th);
  }
  PerParticle r;
  r.particles = solver.particles().size();
  for (const SphSceneSolid& solid : scene.solids) r.solid_particles += solid.count;
  const double m = median(t);
  r.us_per_particle = 1e6 * m / double(r.particles);
  r.thermal_share = thermal ? median(tt) / m : 0.0;
  r.neighbors = solver.lastStats().neighbors_per_particle;
  r.dt = solver.lastStats().dt;
  r.limit = solver.lastStats().limit;
  return r;
}

void perParticleTable(bool quick, bool million, const std::vector<int>& thread_counts) {
  std::printf(
      "## (a) Time per particle per step (median; solver step + thermal step), d = 0.02, h = 2 d; lattice: "
      "the first steps of a block at rest on its lattice (steps 2 on, from the start)\n\n");
  std::printf(
      "| scene | state | particles | solid particles | threads | neighbours/particle | "
      "us / particle / step | x threads | thermal share | dt | dt limit |\n");
  std::printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
  std::vector<size_t> sizes = {10000};
  if (!quick) sizes.push_back(100000);
  if (million) sizes.push_back(1000000);
  for (Kind kind : {Kind::kFluid, Kind::kFluidElastic, Kind::kElasticThermal})
    for (size_t n : sizes) {
      const SphScene scene = parseSphScene(sceneText(kind, n), "bench");
      for (int threads : thread_counts) {
        const PerParticle r = timeScene(scene, threads, n >= 1000000 ? 3 : n >= 100000 ? 5 : 9);
        std::printf(
            "| %s | lattice (first steps of a block at rest on its lattice) | %zu | %zu | %d | %.1f | "
            "%.3f | %.3f | %.0f%% | %.2e | %s |\n",
            kindName(kind), r.particles, r.solid_particles, threads, r.neighbors, r.us_per_particle,
            r.us_per_particle * threads, 100.0 * r.thermal_share, r.dt, toString(r.limit));
        std::fflush(stdout);
      }
    }
}

// ---- (a, flowing) A 3D dam break after the impact --------------------------------------------------------

/// config/sph/dam_break_3d.yaml scaled to about `target` moving particles at the same spacing (dx = 0.01,
/// h = 2 dx): a column of a x 1.5a x 1.5a cells at the left of a tank of 3a x 2.5a x 1.5a cells, c = 10
/// sqrt(2 g H) for the column height H, poly6 pressure gradient, mu = 0.5, xi = 0.1, zeta = 0.01, cfl 0.4.
/// Walls: two layers of static boundary particles with the box planes as a backstop (as shipped), or
/// (`particle_walls` false) the box planes alone.
struct DamBreak {
  SphScene scene;
  int a = 0;                                                  ///< column width in cells
  double dx = 0.01, width = 0.0, height = 0.0, tank_x = 0.0;  ///< column width, height; tank length [m]
  size_t moving = 0, walls = 0;
  double potential0 = 0.0;  ///< sum m g y of the fluid at the start (y from the floor)
};

DamBreak makeDamBreak(size_t target, bool particle_walls) {
  DamBreak b;
  b.a = std::max(4, int(std::lround(std::cbrt(double(target) / 2.25))));
  const int a = b.a, a15 = int(std::lround(1.5 * a));
  const double dx = b.dx;
  b.width = a * dx;
  b.height = a15 * dx;
  b.tank_x = 3 * a * dx;
  const double sound = 10.0 * std::sqrt(2.0 * 9.81 * b.height);
  char solver[512];
  std::snprintf(solver, sizeof solver,
                "solver:\n  smoothing_ratio: 2.0\n  rest_density: 1000\n  speed_of_sound: %.9g\n  gamma: 1\n"
                "  negative_pressure_scale: 0.01\n  pressure_kernel: poly6\n  viscosity: 0.5\n  xsph: 0.1\n"
                "  gravity: [0, -9.81, 0]\n",
                sound);
  const std::string tank = "{lo: " + vec(0, 0, 0) + ", hi: " + vec(3 * a * dx, 2.5 * a * dx, a15 * dx);
  std::string s = "name: dam_break_flowing\ndimension: 3\nspacing: 0.01\n";
  s += solver;
  s += "fluid:\n  - {lo: " + vec(0, 0, 0) + ", hi: " + vec(a * dx, a15 * dx, a15 * dx) + "}\n";
  s += "boundary:\n";
  if (particle_walls) s += "  walls:\n    - " + tank + ", layers: 2}\n";
  s += "  box_planes:\n    - " + tank + "}\n";
  s += "frames: {count: 1, time: 0.02}\n";
  b.scene = parseSphScene(s, "dam_break_flowing");
  const SphParticles& p = b.scene.particles;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.kinds[i] == SphParticleKind::kFluid) {
      ++b.moving;
      b.potential0 += p.masses[i] * 9.81 * p.positions[i].y();
    } else {
      ++b.walls;
    }
  }
  return b;
}

double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/// Martin & Moyce time t* = t sqrt(2 g / a) of a column of width a.
double damBreakTStar(const DamBreak& b, double t) {
  return t * std::sqrt(2.0 * 9.81 / b.width);
}

/// Neighbours per moving particle and the fraction of moving particles with a neighbour closer than dx / 2
/// (3D poly6 pairing), from the rows of the solver's last force computation.
void movingNeighbours(const SphFluidSolver& solver, double dx, double& per_moving, double& paired) {
  per_moving = paired = 0.0;
  if (!solver.neighborsCurrent()) return;
  const SphParticles& p = solver.particles();
  const std::vector<uint32_t>& order = solver.neighborGrid().order();
  size_t moving = 0, entries = 0, close = 0;
  for (size_t s = 0; s < order.size(); ++s) {
    const uint32_t i = order[s];
    if (p.kinds[i] != SphParticleKind::kFluid) continue;
    uint32_t count = 0;
    const uint32_t* row = solver.neighborRow(s, count);
    ++moving;
    entries += count;
    bool near = false;
    for (uint32_t e = 0; e < count && !near; ++e)
      near = (p.positions[order[row[e]]] - p.positions[i]).squaredNorm() < 0.25 * dx * dx;
    close += near;
  }
  per_moving = moving ? double(entries) / double(moving) : 0.0;
  paired = moving ? double(close) / double(moving) : 0.0;
}

/// One line of the flow's state: time, t*, front and run-up, energies, pairing, neighbours.
std::string flowState(const DamBreak& b, const SphFluidSolver& solver, double time) {
  const SphParticles& p = solver.particles();
  double front = 0.0, runup = 0.0, kinetic = 0.0, potential = 0.0, vmax = 0.0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.kinds[i] != SphParticleKind::kFluid) continue;
    const Vec3& x = p.positions[i];
    front = std::max(front, x.x());
    if (x.x() > b.tank_x - b.width) runup = std::max(runup, x.y());  // the last column width of the tank
    kinetic += 0.5 * p.masses[i] * p.velocities[i].squaredNorm();
    potential += p.masses[i] * 9.81 * x.y();
    vmax = std::max(vmax, p.velocities[i].norm());
  }
  double per_moving = 0.0, paired = 0.0;
  movingNeighbours(solver, b.dx, per_moving, paired);
  char line[512];
  std::snprintf(line, sizeof line,
                "t = %.3f s (t* = %.2f), front %.2f of the tank, run-up at the far wall %.2f H, kinetic %.3f "
                "and potential %.3f of the initial potential energy, max speed %.2f sqrt(2 g H), "
                "neighbours/moving particle %.1f, paired (a neighbour < dx/2) %.0f%%",
                time, damBreakTStar(b, time), front / b.tank_x, runup / b.height, kinetic / b.potential0,
                potential / b.potential0, vmax / std::sqrt(2.0 * 9.81 * b.height), per_moving,
                100.0 * paired);
  return line;
}

/// The warm state of a flowing run in a file (positions, velocities, densities; `key` names the scene and
/// time), so that a re-run can skip the warm-up. False if the file is missing or for another scene.
bool loadFlowState(const std::string& path, const std::string& key, SphParticles& p, double& time,
                   uint64_t& steps) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  char stored[256] = {0};
  uint64_t n = 0;
  bool ok = std::fread(stored, 1, sizeof stored, f) == sizeof stored && key == stored &&
            std::fread(&n, sizeof n, 1, f) == 1 && n == p.size() &&
            std::fread(&time, sizeof time, 1, f) == 1 && std::fread(&steps, sizeof steps, 1, f) == 1;
  ok = ok && std::fread(p.positions.data(), sizeof(Vec3), n, f) == n &&
       std::fread(p.velocities.data(), sizeof(Vec3), n, f) == n &&
       std::fread(p.densities.data(), sizeof(double), n, f) == n;
  std::fclose(f);
  return ok;
}

void saveFlowState(const std::string& path, const std::string& key, const SphParticles& p, double time,
                   uint64_t steps) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) {
    std::fprintf(stderr, "cannot write %s\n", path.c_str());
    return;
  }
  char stored[256] = {0};
  std::snprintf(stored, sizeof stored, "%s", key.c_str());
  const uint64_t n = p.size();
  std::fwrite(stored, 1, sizeof stored, f);
  std::fwrite(&n, sizeof n, 1, f);
  std::fwrite(&time, sizeof time, 1, f);
  std::fwrite(&steps, sizeof steps, 1, f);
  std::fwrite(p.positions.data(), sizeof(Vec3), n, f);
  std::fwrite(p.velocities.data(), sizeof(Vec3), n, f);
  std::fwrite(p.densities.data(), sizeof(double), n, f);
  std::fclose(f);
}

struct FlowOptions {
  bool particle_walls = true;
  std::vector<double> t_stars = {4.0};  ///< timed states in Martin & Moyce time t sqrt(2 g / a), ascending
  int warm_threads = 2;                 ///< the warm-up runs once, on this many threads
  /// The warm-up's cfl (> 0; else the scene's 0.4): 0.8 halves its steps; at 10k and 100k particles it
  /// reaches t* = 4 and 8 with the neighbour counts and pairing of the cfl 0.4 run (within 0.3 neighbours).
  double warm_cfl = 0.8;
  std::string state_dir;  ///< if set: warm states are read from / written to this directory
  bool trace = false;     ///< print the state every 0.5 t* of the warm-up
  int steps = 0;          ///< timed steps per row (0: 21 / 11 / 7 at 10k / 100k / 1M)
};

/// Times `steps` single steps of the scene from `state` on `threads` threads (a fresh solver; its first 2
/// steps are not timed) and prints the row.
void timeFlowingWindow(const DamBreak& b, const SphParticles& state, double t_star, int threads, int steps) {
  SphScene scene = b.scene;
  scene.particles = state;
  scene.config.num_threads = threads;
  omp_set_num_threads(threads);
  SphFluidSolver solver = makeSphSolver(scene);
  for (int s = 0; s < 2; ++s) solver.step();
  std::vector<double> t, cpu;
  const double cpu0 = processCpuSeconds();
  const auto w0 = std::chrono::steady_clock::now();
  for (int s = 0; s < steps; ++s) {
    const double c0 = processCpuSeconds();
    const auto t0 = std::chrono::steady_clock::now();
    solver.step();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    cpu.push_back(processCpuSeconds() - c0);
  }
  // CPU time of the process over the window per wall time and thread: below 1 on one thread, the process was
  // not running all the time (a loaded machine); on two, OpenMP workers also spin at barriers. The CPU time
  // per step (median) is the cost on one thread when the machine is loaded (not on two: the spinning).
  const double cpu_share =
      (processCpuSeconds() - cpu0) /
      (threads * std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count());
  double per_moving = 0.0, paired = 0.0;
  movingNeighbours(solver, b.dx, per_moving, paired);
  const double us = 1e6 * median(t) / double(b.moving);
  const auto [lo, hi] = std::minmax_element(t.begin(), t.end());
  std::printf(
      "| dam break, flowing (t* = %.2f) | %zu | %zu | %d | %d | %.1f | %.1f | %.3f | %.3f-%.3f | %.3f | "
      "%.3f | %.2e | %s | %.2f | %.3f |\n",
      t_star, b.moving, b.walls, threads, steps, per_moving, solver.lastStats().neighbors_per_particle, us,
      1e6 * *lo / double(b.moving), 1e6 * *hi / double(b.moving), us * threads,
      1e6 * median(t) / double(b.moving + b.walls), solver.lastStats().dt, toString(solver.lastStats().limit),
      cpu_share, 1e6 * median(cpu) / double(b.moving));
  std::fflush(stdout);
}

/// Flowing rows: each size runs once from the start (FlowOptions::warm_threads threads) through the states
/// t*; at each, every thread count restarts from the saved state (timeFlowingWindow); the rate counts only
/// the moving (fluid) particles.
void flowingTable(bool quick, bool million, const std::vector<int>& thread_counts, const FlowOptions& o) {
  std::string t_list;
  for (double t : o.t_stars) t_list += (t_list.empty() ? "" : ", ") + std::to_string(t).substr(0, 4);
  std::printf(
      "\n## (a, flowing) 3D dam break after the impact: config/sph/dam_break_3d.yaml scaled (column "
      "a x 1.5a x 1.5a cells in a tank of 3a x 2.5a x 1.5a, dx = 0.01, h = 2 dx, c = 10 sqrt(2 g H), poly6, "
      "mu = 0.5, xi = 0.1, zeta = 0.01, cfl 0.4; walls: %s). Warm-up: once, on %d threads, at cfl %.2f, from "
      "the start to t* = t sqrt(2 g / a) = %s; at each, every thread count restarts from that saved state at "
      "cfl %.2f: 2 steps untimed, then median (min-max) of single steps. The rate counts moving (fluid) "
      "particles only; the wall particles' work (neighbour search, density) is in it.\n\n",
      o.particle_walls ? "2 layers of static boundary particles + box planes" : "box planes only",
      o.warm_threads, o.warm_cfl > 0.0 ? o.warm_cfl : SphFluidConfig{}.cfl, t_list.c_str(),
      SphFluidConfig{}.cfl);
  std::printf(
      "| scene | moving particles | wall particles | threads | timed steps | neighbours / moving particle | "
      "neighbours / particle (all) | us / moving particle / step | min-max | x threads | us / particle / "
      "step (all) | dt | dt limit | CPU / (wall x threads) | CPU us / moving particle / step |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---|---:|---:|\n");
  std::fflush(stdout);
  std::vector<size_t> sizes = {10000};
  if (!quick) sizes.push_back(100000);
  if (million) sizes.push_back(1000000);
  std::string states;
  for (size_t target : sizes) {
    const DamBreak b = makeDamBreak(target, o.particle_walls);
    const double t_unit = 1.0 / std::sqrt(2.0 * 9.81 / b.width);  // t = t* t_unit
    SphScene warm_scene = b.scene;
    warm_scene.config.num_threads = o.warm_threads;
    if (o.warm_cfl > 0.0) warm_scene.config.cfl = o.warm_cfl;
    omp_set_num_threads(o.warm_threads);
    auto warm = std::make_unique<SphFluidSolver>(makeSphSolver(warm_scene));
    double offset = 0.0, seconds = 0.0;  // simulated time of the warm solver's start; warm-up wall time
    uint64_t step_offset = 0;
    bool any_loaded = false;
    const int steps = o.steps > 0 ? o.steps : target >= 1000000 ? 7 : target >= 100000 ? 11 : 21;
    for (double t_star : o.t_stars) {
      const double t_end = t_star * t_unit;
      char key[256];
      std::snprintf(key, sizeof key, "dam_break_flowing a=%d walls=%d t*=%.6g n=%zu cfl=%.6g", b.a,
                    int(o.particle_walls), t_star, b.scene.particles.size(), warm_scene.config.cfl);
      std::string path;
      if (!o.state_dir.empty()) {
        char name[128];
        std::snprintf(name, sizeof name, "/dam_break_%d_%s_t%.2f_cfl%.2f.bin", b.a,
                      o.particle_walls ? "walls" : "planes", t_star, warm_scene.config.cfl);
        path = o.state_dir + name;
      }
      SphParticles loaded_state = b.scene.particles;
      double loaded_time = 0.0;
      uint64_t loaded_steps = 0;
      omp_set_num_threads(o.warm_threads);
      const bool loaded = !path.empty() && loadFlowState(path, key, loaded_state, loaded_time, loaded_steps);
      if (loaded) {
        warm_scene.particles = loaded_state;
        warm = std::make_unique<SphFluidSolver>(makeSphSolver(warm_scene));
        warm->computeForces();  // the neighbour rows of the loaded state
        offset = loaded_time;
        step_offset = loaded_steps;
        any_loaded = true;
      } else {
        const auto t0 = std::chrono::steady_clock::now();
        const double chunk = o.trace ? 0.5 * t_unit : t_end;
        while (offset + warm->time() < t_end - 1e-12) {
          warm->advance(std::min(chunk, t_end - offset - warm->time()));
          if (o.trace)
            std::printf("<!-- %zu: %s -->\n", b.moving, flowState(b, *warm, offset + warm->time()).c_str());
          std::fflush(stdout);
        }
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (!path.empty())
          saveFlowState(path, key, warm->particles(), offset + warm->time(), step_offset + warm->stepCount());
      }
      const double now = offset + warm->time();
      char line[1024];
      std::snprintf(line, sizeof line, "| %zu | %zu | %d x %d x %d | %.2f | %.3f | %.2f | %llu | %s | %s |\n",
                    b.moving, b.walls, b.a, int(std::lround(1.5 * b.a)), int(std::lround(1.5 * b.a)),
                    b.scene.config.soundSpeed(), now, t_star,
                    (unsigned long long)(step_offset + warm->stepCount()),
                    (loaded       ? std::string("loaded")
                     : any_loaded ? std::to_string(int(std::lround(seconds))) + " s after a loaded state"
                                  : std::to_string(int(std::lround(seconds))) + " s")
                        .c_str(),
                    flowState(b, *warm, now).c_str());
      states += line;
      std::printf("<!-- warm state: %s -->\n", line);
      std::fflush(stdout);
      for (int threads : thread_counts) timeFlowingWindow(b, warm->particles(), t_star, threads, steps);
    }
  }
  std::printf(
      "\nStates at the timed windows (run-up: the highest fluid particle within a column width of the far "
      "wall; warm-up wall time: from the start, on the warm-up threads):\n\n"
      "| moving particles | wall particles | column (cells) | c [m/s] | t [s] | t* | steps from the start | "
      "warm-up wall time | state |\n|---:|---:|---|---:|---:|---:|---:|---|---|\n%s",
      states.c_str());
  std::fflush(stdout);
}

struct ThesisScene {
  const char* figure;
  const char* thesis_particles;
  double thesis_seconds_per_frame;
  std::string label;
  SphScene scene;
  int threads = 2;
  int frames = 0;  ///< 0: the table's default
};

/// The scene with the locally implicit goal springs and collision penalty (SphElasticConfig::implicit_goal,
/// SphObjectPenaltyConfig::implicit): the step is no longer limited by K_e and K_c.
/// `global`: the globally implicit goal springs (SphElasticConfig::global_implicit_goal) instead.
SphScene implicitSprings(SphScene scene, double step_factor = 0.0, bool global = false) {
  for (SphSceneSolid& solid : scene.solids) {
    solid.elastic.implicit_goal = true;
    solid.elastic.global_implicit_goal = global;
    solid.elastic.implicit_step_factor = step_factor;
  }
  scene.collisions.config.implicit = true;
  return scene;
}

/// The scene with the explicit goal forces (8.31) and collision penalty (8.37): dt at their Verlet limits.
SphScene explicitSprings(SphScene scene) {
  for (SphSceneSolid& solid : scene.solids) {
    solid.elastic.implicit_goal = false;
    solid.elastic.global_implicit_goal = false;
    solid.elastic.implicit_step_factor = 0.0;
  }
  scene.collisions.config.implicit = false;
  return scene;
}

std::string configPath(const char* name) {
  const std::string here = __FILE__;
  return here.substr(0, here.rfind("/bench/")) + "/config/sph/" + name;
}

/// dice_only > 0: only the Fig. 8.8 rows, with that many frames for the implicit ones; `only` (if not
/// empty): only the rows whose label contains one of them.
void thesisTable(bool quick, int dice_only = 0, const std::vector<std::string>& only = {}) {
  std::vector<ThesisScene> scenes;
  const SphScene dice = loadSphScene(configPath("dice_3d.yaml"));
  scenes.push_back({"8.8", "2214", 18.7, "dice_3d.yaml, implicit springs", implicitSprings(dice), 1});
  scenes.push_back({"8.8", "2214", 18.7, "dice_3d.yaml, implicit springs", implicitSprings(dice), 2});
  scenes.push_back({"8.8", "2214", 18.7, "dice_3d.yaml, implicit springs, dt <= 10 x explicit limit",
                    implicitSprings(dice, 10.0), 1});
  scenes.push_back({"8.8", "2214", 18.7, "dice_3d.yaml, implicit springs, dt <= 4 x explicit limit",
                    implicitSprings(dice, 4.0), 1});
  scenes.push_back(
      {"8.8", "2214", 18.7, "dice_3d.yaml, explicit springs (8.31), (8.37)", explicitSprings(dice), 1, 1});
  for (double factor : {10.0, 20.0, 30.0, 0.0}) {
    const std::string cap = factor > 0.0 ? ", dt <= " + std::to_string(int(factor)) + " x explicit limit" +
                                               (factor == 30.0 ? " (as shipped)" : "")
                                         : ", no cap";
    scenes.push_back({"8.8", "2214", 18.7, "dice_3d.yaml, global implicit springs" + cap,
                      implicitSprings(dice, factor, true), 1});
  }
  scenes.push_back({"8.8", "2214", 18.7,
                    "dice_3d.yaml, global implicit springs, dt <= 30 x explicit limit (as shipped)",
                    implicitSprings(dice, 30.0, true), 2});
  SphScene uncoupled = implicitSprings(dice, 30.0, true);
  uncoupled.collisions.config.couple_global_implicit = false;
  scenes.push_back(
      {"8.8", "2214", 18.7,
       "dice_3d.yaml, global implicit springs, dt <= 30 x explicit limit, contacts outside the solve",
       uncoupled, 1});
  if (dice_only > 0) {
    for (ThesisScene& t : scenes) t.frames = dice_only;
  } else {
    // The shipped Fig. 8.4 and 8.5 scenes, all their frames (the cost changes as the bunny melts and the
    // slime pours in); --quick: their first frame.
    const SphScene bunny = loadSphScene(configPath("fig8_4_melting_bunny.yaml"));
    const SphScene slime = loadSphScene(configPath("fig8_5_freezing_rod.yaml"));
    for (int threads : {1, 2}) {
      scenes.push_back({"8.4", "9871", 17.0, "fig8_4_melting_bunny.yaml (as shipped), all frames", bunny,
                        threads, quick ? 1 : bunny.frame_count});
      scenes.push_back({"8.5", "1606-7000", 18.2, "fig8_5_freezing_rod.yaml (as shipped), all frames", slime,
                        threads, quick ? 1 : slime.frame_count});
    }
    scenes.push_back({"8.4", "9871", 17.0, "fig8_4_melting_bunny.yaml, first 6 frames (all solid)", bunny, 2,
                      quick ? 1 : 6});
    scenes.push_back({"8.5", "1606-7000", 18.2, "freezing_rod_2d.yaml (as shipped, 2D)",
                      loadSphScene(configPath("freezing_rod_2d.yaml"))});
  }
  const int frames = dice_only > 0 ? dice_only : quick ? 1 : 2;
  std::printf(
      "\n## (b) Table 8.1 scenes (thesis: Pentium 4, 3 GHz), %d frame(s) from the start, no "
      "output\n\n",
      frames);
  std::printf(
      "| Fig. | thesis particles | thesis s/frame | our scene | threads | particles | frame time [s] | s / "
      "frame "
      "| steps / frame | mean dt | last dt limit | us / particle / step | s / (1/30 s) | speed-up vs thesis "
      "(per "
      "1/30 s) |\n");
  std::printf("|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|\n");
  for (ThesisScene& t : scenes) {
    if (!only.empty() && std::none_of(only.begin(), only.end(), [&](const std::string& o) {
          return t.label.find(o) != std::string::npos;
        }))
      continue;
    SphScene& scene = t.scene;
    scene.frame_count = t.frames > 0 ? t.frames : frames;
    scene.output = SphParticleOutput{};
    scene.surface.enabled = false;
    scene.skins.clear();
    scene.config.num_threads = t.threads;
    scene.thermal.config.num_threads = t.threads;
    omp_set_num_threads(t.threads);
    SphFluidSolver solver = makeSphSolver(scene);  // with the planes and gravity of the global springs
    SphStepLimit limit = SphStepLimit::kMaxDt;
    SphRunOptions options;
    double max_strain = 0.0, min_contact = std::numeric_limits<double>::infinity();
    double cg_iterations = 0.0, max_p99 = 0.0, max_mean = 0.0;
    int cg_samples = 0;
    std::vector<double> strains;
    options.on_frame = [&](const SphFrameReport& r) {
      limit = r.limit;
      strains.clear();
      for (const auto& term : solver.forceTerms()) {  // the state at the frame's end
        if (const auto* solid = dynamic_cast<const SphElasticSolid*>(term.get())) {
          max_strain = std::max(max_strain, solid->stats().max_strain);
          const SphParticles& p = solver.particles();
          for (size_t i = 0; i < p.size() && i < solid->strains().size(); ++i)
            if (p.phases[i] == solid->phase())  // largest |eigenvalue| of the strain (8.26)
              strains.push_back(
                  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(solid->strains()[i], Eigen::EigenvaluesOnly)
                      .eigenvalues()
                      .cwiseAbs()
                      .maxCoeff());
          if (solid->config().global_implicit_goal) {
            cg_iterations += solid->stats().implicit_iterations;
            ++cg_samples;
          }
        }
        if (const auto* penalty = dynamic_cast<const SphObjectPenalty*>(term.get()))
          if (penalty->stats().contact_pairs > 0)
            min_contact = std::min(min_contact, penalty->stats().min_distance);
      }
      if (!strains.empty()) {  // the 99th percentile and the mean over the solid particles
        std::sort(strains.begin(), strains.end());
        max_p99 = std::max(max_p99, strains[strains.size() * 99 / 100]);
        double sum = 0.0;
        for (double e : strains) sum += e;
        max_mean = std::max(max_mean, sum / double(strains.size()));
      }
    };
    const SphRunStats st = runSphScene(scene, solver, options);
    if (!st.instability.empty())
      std::printf("<!-- %s unstable: %s -->\n", scene.name.c_str(), st.instability.c_str());
    const double per_frame = st.wall_seconds / std::max(1, st.frames);
    const double per_30th = per_frame * (1.0 / 30.0) / scene.frame_time;
    std::printf("| %s | %s | %.1f | %s | %d | %zu | %.4f | %.3f | %.0f | %.2e | %s | %.2f | %.3f | %.0fx |\n",
                t.figure, t.thesis_particles, t.thesis_seconds_per_frame, t.label.c_str(), t.threads,
                st.particles, scene.frame_time, per_frame, double(st.steps) / std::max(1, st.frames),
                st.mean_dt, toString(limit), st.us_per_particle_step, per_30th,
                t.thesis_seconds_per_frame / per_30th);
    if (t.figure == std::string("8.8"))
      std::printf(
          "<!-- %s: max strain at frame ends %.4f (99th percentile %.4f, mean %.4f: largest over the frame "
          "ends), smallest distance between dice %.4f m (d %.3f), CG iterations per solve at frame ends %.1f "
          "-->\n",
          t.label.c_str(), max_strain, max_p99, max_mean, min_contact,
          scene.collisions.config.contact_distance, cg_samples > 0 ? cg_iterations / cg_samples : 0.0);
    std::fflush(stdout);
  }
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, million = true, sizes_only = false, lattice = true, flowing = true;
  std::vector<int> thread_counts = {1, 2};
  int dice_frames = 0;
  std::vector<std::string> only;
  FlowOptions flow;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--flowing")) lattice = false, sizes_only = true;
    if (!std::strcmp(argv[a], "--no-flowing")) flowing = false;
    if (!std::strcmp(argv[a], "--plane-walls")) flow.particle_walls = false;
    if (!std::strcmp(argv[a], "--tstar") && a + 1 < argc) {  // comma-separated, ascending
      flow.t_stars.clear();
      for (char* t = std::strtok(argv[++a], ","); t; t = std::strtok(nullptr, ","))
        flow.t_stars.push_back(std::max(0.0, std::atof(t)));
      std::sort(flow.t_stars.begin(), flow.t_stars.end());
    }
    if (!std::strcmp(argv[a], "--warm-threads") && a + 1 < argc)
      flow.warm_threads = std::max(1, std::atoi(argv[++a]));
    if (!std::strcmp(argv[a], "--state-dir") && a + 1 < argc) flow.state_dir = argv[++a];
    if (!std::strcmp(argv[a], "--warm-cfl") && a + 1 < argc)
      flow.warm_cfl = std::min(1.0, std::max(0.0, std::atof(argv[++a])));
    if (!std::strcmp(argv[a], "--trace")) flow.trace = true;
    if (!std::strcmp(argv[a], "--flow-steps") && a + 1 < argc) flow.steps = std::max(1, std::atoi(argv[++a]));
    if (!std::strcmp(argv[a], "--only") && a + 1 < argc) only.push_back(argv[++a]);
    if (!std::strcmp(argv[a], "--quick")) quick = true;
    if (!std::strcmp(argv[a], "--no-1m")) million = false;
    if (!std::strcmp(argv[a], "--dice") && a + 1 < argc) dice_frames = std::max(1, std::atoi(argv[++a]));
    if (!std::strcmp(argv[a], "--sizes")) sizes_only = true;
    if (!std::strcmp(argv[a], "--threads") && a + 1 < argc)
      thread_counts = {std::max(1, std::atoi(argv[++a]))};
  }
  if (dice_frames > 0) {  // the Fig. 8.8 rows only
    thesisTable(true, dice_frames, only);
    return 0;
  }
  if (quick) million = false;
  if (only.empty() && lattice) perParticleTable(quick, million, thread_counts);
  if (only.empty() && flowing) flowingTable(quick, million, thread_counts, flow);
  if (!sizes_only) thesisTable(quick, 0, only);
  return 0;
}
