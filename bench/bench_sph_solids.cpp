// SPH with elastic solids and temperature (thesis 8.2, Table 8.1). (a) Time per particle per step, median of
// several steps, for three scenes built as scene files (appendix F.2 conventions: rho = 1, Gamma = 1, K = 20,
// xi = 0.1, zeta = 0.01, h = 2 d) at ~10k, ~100k and ~1M particles, 1 and 2 threads:
//   fluid          a fluid block in a tank of planes,
//   fluid+elastic  the same block with an elastic cube (goal-position model) dropped into it,
//   elastic+temp   an elastic cube on a floor heated to 100 degrees (enable: [temperature]; the thermal model
//                  is stepped and timed after every solver step).
// (b) The scenes of Table 8.1 (Fig. 8.4 melting bunny 9871 particles 17 s/frame, Fig. 8.5 freezing rod
// 1606-7000 particles 18.2 s/frame, Fig. 8.8 nine dice 2214 particles 18.7 s/frame; Pentium 4, 3 GHz) with
// the shipped scene files run through runSphScene (the Fig. 8.4 and 8.5 scenes over all their frames):
// seconds per frame, steps per frame, dt and its limit, and the speed-up over the thesis. `--quick`: 10k only
// and one frame per scene; `--no-1m`: skip the 1M rows;
// `--dice N`: only the Fig. 8.8 rows, N frames each (`--only TEXT`, repeatable: only the rows whose label
// contains TEXT; without --dice: only table (b), only those rows); `--sizes`: only table (a); `--threads T`:
// table (a) with T threads only (default 1 and 2; 1M particles take ~2.5 GB and 3 steps per row).
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "sph/sph_elastic_solid.h"
#include "sph/sph_fluid_solver.h"
#include "sph/sph_object_penalty.h"
#include "sph/sph_scene_file.h"
#include "sph/sph_scene_run.h"
#include "sph/sph_thermal.h"

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
      "## (a) Time per particle per step (median; solver step + thermal step), d = 0.02, h = 2 d\n\n");
  std::printf(
      "| scene | particles | solid particles | threads | neighbours/particle | us / particle / step | "
      "x threads | thermal share | dt | dt limit |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
  std::vector<size_t> sizes = {10000};
  if (!quick) sizes.push_back(100000);
  if (million) sizes.push_back(1000000);
  for (Kind kind : {Kind::kFluid, Kind::kFluidElastic, Kind::kElasticThermal})
    for (size_t n : sizes) {
      const SphScene scene = parseSphScene(sceneText(kind, n), "bench");
      for (int threads : thread_counts) {
        const PerParticle r = timeScene(scene, threads, n >= 1000000 ? 3 : n >= 100000 ? 5 : 9);
        std::printf("| %s | %zu | %zu | %d | %.1f | %.3f | %.3f | %.0f%% | %.2e | %s |\n", kindName(kind),
                    r.particles, r.solid_particles, threads, r.neighbors, r.us_per_particle,
                    r.us_per_particle * threads, 100.0 * r.thermal_share, r.dt, toString(r.limit));
        std::fflush(stdout);
      }
    }
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
  bool quick = false, million = true, sizes_only = false;
  std::vector<int> thread_counts = {1, 2};
  int dice_frames = 0;
  std::vector<std::string> only;
  for (int a = 1; a < argc; ++a) {
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
  if (only.empty()) perParticleTable(quick, million, thread_counts);
  if (!sizes_only) thesisTable(quick, 0, only);
  return 0;
}
