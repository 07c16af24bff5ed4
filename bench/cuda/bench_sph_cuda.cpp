// Throughput of the SPH GPU path: 3D dam break in a tank (fluid only) and with elastic cubes (fluid +
// elastic), at about 1e5, 1e6 and 1e7 fluid particles. Rates count the particles that move (fluid and solid);
// the static wall (boundary) particles are counted in the table but not in "moving part-steps/s" (the column
// "all part-steps/s" divides by every particle, walls included, as the first version of this bench did).
// On a CUDA device: SphGpuSolver (median over repetitions, CUDA events, steps taken one after the other) and
// the time split of its passes, then the "same window" rows: every solver starts from the initial state,
// takes
// --warmup untimed steps and times the next --window steps, repeated from scratch --reps times, so that GPU
// rows and CPU rows (this bench with --cpu, on any machine) time the same states at the same particle count.
// With --cpu (or without a device): the same-window rows of the host driver of the GPU code
// (SphGpuHostSolver<float>, the GPU's precision) and of the CPU solver (SphFluidSolver + SphElasticSolid,
// double), on the smaller sizes.
//   bench_sph_cuda [--cpu] [--sizes 1e5,1e6,1e7] [--reps 5] [--warmup 10] [--window 20]
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "relaxed_connectivity/sph/gpu/sph_gpu_host_solver.h"
#include "relaxed_connectivity/sph/gpu/sph_gpu_scene.h"
#include "relaxed_connectivity/sph/gpu/sph_gpu_setup.h"
#include "relaxed_connectivity/sph/gpu/sph_gpu_solver.h"
#include "relaxed_connectivity/sph/sph_elastic_solid.h"

namespace {

using namespace rc;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// Dam break in a 1 x 0.6 x 0.5 m tank with about `fluid` particles in the 0.4 x 0.5 x 0.5 m column; with
/// `elastic`, twelve 0.15 m cubes beside it.
SphGpuScene benchScene(double fluid, bool elastic) {
  SphGpuTankScene s;
  s.dx = std::cbrt(0.1 / fluid);
  s.num_blocks = elastic ? 12 : 0;
  return makeSphGpuTankScene(s);
}

void printHeader() {
  std::printf("%-24s %-14s %10s %10s %10s %10s %6s %11s %15s %13s\n", "solver", "scene", "particles", "fluid",
              "solid", "boundary", "nbrs", "ms/step", "moving p-st/s", "all p-st/s");
}

void printRow(const char* solver, const char* scene, const SphGpuScene& s, double neighbors,
              double seconds_per_step) {
  const double all = double(s.particles.size()), moving = double(s.fluid_particles + s.solid_particles);
  std::printf("%-24s %-14s %10zu %10zu %10zu %10zu %6.1f %11.3f %15.3e %13.3e\n", solver, scene,
              s.particles.size(), s.fluid_particles, s.solid_particles, s.boundary_particles, neighbors,
              1e3 * seconds_per_step, moving / seconds_per_step, all / seconds_per_step);
}

/// Same-window protocol: from the initial state, `warmup` untimed steps, then `window` timed ones.
struct Window {
  int warmup = 10, steps = 20;
};

void printWindowHeader(const Window& w, int reps) {
  std::printf(
      "\nSame window: each repetition starts from the initial state, takes %d untimed steps and times steps "
      "%d-%d; median of %d repetitions.\n",
      w.warmup, w.warmup + 1, w.warmup + w.steps, reps);
  printHeader();
}

void benchGpu(const std::vector<double>& sizes, int reps) {
  printHeader();
  std::vector<std::string> splits;
  struct Mode {
    bool masks, previous_passes;
    const char* name;
  };
  const Mode modes[] = {{true, false, "GPU, neighbour masks"},
                        {false, false, "GPU, cell scans"},
                        {true, true, "GPU, previous passes"}};
  for (double size : sizes)
    for (bool elastic : {false, true}) {
      const SphGpuScene scene = benchScene(size, elastic);
      const char* name = elastic ? "fluid+elastic" : "fluid";
      SphGpuSolver gpu(makeSphGpuSystem<float>(scene.config, scene.planes, scene.solids, scene.particles));
      const int steps = std::max(10, int(2e7 / double(scene.particles.size())));
      // The largest size also without neighbour masks and with the pass sequence of the first version (the
      // default first).
      for (int l = 0; l < (size == sizes.back() ? 3 : 1); ++l) {
        gpu.setNeighborMasks(modes[l].masks);
        gpu.setPreviousPasses(modes[l].previous_passes);
        gpu.step(10);  // warm-up
        std::vector<double> per_step;
        for (int r = 0; r < reps; ++r) per_step.push_back(1e-3 * gpu.timedStep(steps) / steps);
        printRow(modes[l].name, name, scene, gpu.neighborsPerParticle(), median(per_step));
        std::fflush(stdout);
      }
      gpu.setNeighborMasks(true);
      gpu.setPreviousPasses(false);
      std::fflush(stdout);
      gpu.setProfiling(true);
      gpu.resetPassTimes();
      gpu.step(10);
      const SphGpuPassTimes& t = gpu.passTimes();
      char line[256];
      std::snprintf(
          line, sizeof(line),
          "%-14s %10zu  sort %.3f  density %.3f  force %.3f  elastic %.3f  integrate %.3f  (ms/step)", name,
          scene.particles.size(), 1e3 * t.sort / t.steps, 1e3 * t.density / t.steps, 1e3 * t.force / t.steps,
          1e3 * t.elastic / t.steps, 1e3 * t.integrate / t.steps);
      splits.push_back(line);
    }
  std::printf(
      "\nGPU pass split (CUDA events, 10 profiled steps; the kick-drift is fused into the sort pass "
      "(reorder) and the force pass (next cell keys), the elastic acceleration and final kick into the force "
      "pass):\n");
  for (const std::string& s : splits) std::printf("%s\n", s.c_str());
}

void benchGpuWindow(const std::vector<double>& sizes, int reps, const Window& w) {
  printWindowHeader(w, reps);
  for (double size : sizes)
    for (bool elastic : {false, true}) {
      const SphGpuScene scene = benchScene(size, elastic);
      std::vector<double> per_step;
      double neighbors = 0.0;
      for (int r = 0; r < reps; ++r) {
        SphGpuSolver gpu(makeSphGpuSystem<float>(scene.config, scene.planes, scene.solids, scene.particles));
        gpu.step(w.warmup);
        per_step.push_back(1e-3 * gpu.timedStep(w.steps) / w.steps);
        neighbors = gpu.neighborsPerParticle();
      }
      printRow("GPU, neighbour masks", elastic ? "fluid+elastic" : "fluid", scene, neighbors,
               median(per_step));
      std::fflush(stdout);
    }
}

template <class Solver, class Make, class Neighbors>
double windowSecondsPerStep(const Window& w, int reps, Make make, Neighbors neighbors, double* nbrs) {
  std::vector<double> per_step;
  for (int r = 0; r < reps; ++r) {
    std::unique_ptr<Solver> solver = make();
    for (int k = 0; k < w.warmup; ++k) solver->step();
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 0; k < w.steps; ++k) solver->step();
    per_step.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() /
                       w.steps);
    *nbrs = neighbors(*solver);
  }
  return median(per_step);
}

void benchCpu(const std::vector<double>& sizes, int reps, const Window& w) {
  std::printf("CPU: %d OpenMP threads\n", omp_get_max_threads());
  printWindowHeader(w, reps);
  for (double size : sizes)
    for (bool elastic : {false, true}) {
      const SphGpuScene scene = benchScene(size, elastic);
      const char* name = elastic ? "fluid+elastic" : "fluid";
      double nbrs = 0.0;
      const double host = windowSecondsPerStep<SphGpuHostSolver<float>>(
          w, reps,
          [&] {
            return std::make_unique<SphGpuHostSolver<float>>(
                makeSphGpuSystem<float>(scene.config, scene.planes, scene.solids, scene.particles));
          },
          [](const SphGpuHostSolver<float>& s) { return s.neighborsPerParticle(); }, &nbrs);
      printRow("SphGpuHostSolver<float>", name, scene, nbrs, host);
      std::fflush(stdout);
      const SphKernels kernels(3, scene.config.smoothing_length);
      const double cpu = windowSecondsPerStep<SphFluidSolver>(
          w, reps,
          [&] {
            auto solver = std::make_unique<SphFluidSolver>(scene.config, scene.particles);
            for (const SphPlane& plane : scene.planes) solver->addPlane(plane);
            for (const SphGpuSolidSpec& s : scene.solids)
              solver->addForceTerm(
                  std::make_shared<SphElasticSolid>(s.config, kernels, s.phase, s.orientation));
            return solver;
          },
          [](const SphFluidSolver& s) { return s.lastStats().neighbors_per_particle; }, &nbrs);
      printRow("SphFluidSolver (double)", name, scene, nbrs, cpu);
      std::fflush(stdout);
    }
}

}  // namespace

int main(int argc, char** argv) {
  bool cpu = false;
  std::vector<double> sizes;
  int reps = 5;
  Window window;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--cpu")) {
      cpu = true;
    } else if (!std::strcmp(argv[i], "--sizes") && i + 1 < argc) {
      for (char* t = std::strtok(argv[++i], ","); t; t = std::strtok(nullptr, ","))
        sizes.push_back(std::atof(t));
    } else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) {
      reps = std::max(1, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--warmup") && i + 1 < argc) {
      window.warmup = std::max(0, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--window") && i + 1 < argc) {
      window.steps = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "usage: %s [--cpu] [--sizes 1e5,1e6,1e7] [--reps 5] [--warmup 10] [--window 20]\n",
                   argv[0]);
      return 2;
    }
  }
  std::string device;
  const bool gpu = !cpu && SphGpuSolver::deviceAvailable(&device);
  if (sizes.empty()) sizes = gpu ? std::vector<double>{1e5, 1e6, 1e7} : std::vector<double>{3e4, 1e5};
  if (gpu) {
    std::printf("device: %s\n", device.c_str());
    benchGpu(sizes, reps);
    benchGpuWindow(sizes, reps, window);
  } else {
    if (!cpu) std::printf("no CUDA device (%s): CPU solvers only\n", device.c_str());
    benchCpu(sizes, std::min(reps, 3), window);
  }
  return 0;
}
