// CPU cost of one SPH scene file (default: the Fig. 8.4 melting bunny, thesis Table 8.1): the scene is set up
// once, then its frames are run through runSphScene and timed both by the wall clock and by the process CPU
// time (user + system of all threads), which a loaded machine inflates far less than the wall time. Prints
// one JSON line per repetition with both per particle and step, the energy at the end, the melted count and
// an FNV-1a hash of the final positions and velocities (equal hashes: bitwise equal results). Usage:
// bench_sph_cpu [scene.yaml] [--frames N] [--threads T] [--reps R]
#include <time.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"

namespace {

double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

uint64_t fnv1a(const void* data, size_t bytes, uint64_t hash) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t k = 0; k < bytes; ++k) hash = (hash ^ p[k]) * 0x100000001B3ull;
  return hash;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path = "config/sph/fig8_4_melting_bunny.yaml";
  int frames = 6, threads = -1, reps = 1;
  for (int a = 1; a < argc; ++a) {
    const bool more = a + 1 < argc;
    if (!std::strcmp(argv[a], "--frames") && more) {
      frames = std::atoi(argv[++a]);
    } else if (!std::strcmp(argv[a], "--threads") && more) {
      threads = std::atoi(argv[++a]);
    } else if (!std::strcmp(argv[a], "--reps") && more) {
      reps = std::atoi(argv[++a]);
    } else if (argv[a][0] != '-') {
      path = argv[a];
    } else {
      std::fprintf(stderr, "usage: bench_sph_cpu [scene.yaml] [--frames N] [--threads T] [--reps R]\n");
      return 2;
    }
  }
  try {
    rc::SphScene scene = rc::loadSphScene(path);
    scene.frame_count = frames;
    if (threads >= 0) scene.config.num_threads = threads;
    for (int rep = 0; rep < reps; ++rep) {
      rc::SphFluidSolver solver = rc::makeSphSolver(scene);
      const double cpu0 = processCpuSeconds();
      const auto wall0 = std::chrono::steady_clock::now();
      const rc::SphRunStats stats = rc::runSphScene(scene, solver, {});
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
      const double cpu = processCpuSeconds() - cpu0;
      const rc::SphParticles& p = solver.particles();
      uint64_t hash = 0xCBF29CE484222325ull;
      hash = fnv1a(p.positions.data(), p.positions.size() * sizeof(rc::Vec3), hash);
      hash = fnv1a(p.velocities.data(), p.velocities.size() * sizeof(rc::Vec3), hash);
      const double particle_steps = double(stats.steps) * double(stats.particles);
      std::printf(
          "{\"scene\":\"%s\",\"rep\":%d,\"threads\":%d,\"steps\":%llu,\"particles\":%zu,"
          "\"us_per_particle_step\":%.4f,\"wall_us_per_particle_step\":%.4f,\"cpu_us_per_particle_step\":%."
          "4f,"
          "\"energy_end\":%.6g,\"melted\":%llu,\"state_hash\":\"%016llx\"}\n",
          stats.scene.c_str(), rep, stats.threads, (unsigned long long)stats.steps, stats.particles,
          stats.us_per_particle_step, 1e6 * wall / particle_steps, 1e6 * cpu / particle_steps,
          stats.energy_end, (unsigned long long)stats.melted, (unsigned long long)hash);
      std::fflush(stdout);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_sph_cpu: %s: %s\n", path.c_str(), e.what());
    return 1;
  }
  return 0;
}
