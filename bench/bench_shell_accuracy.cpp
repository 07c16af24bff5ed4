// Thin-shell speed/accuracy (thesis 7.2): bending energy of a flat sheet bent isometrically onto a cylinder
// of radius 0.6 (K_b/2 |S - S0|_F^2 = K_b / (4 r^2) per area over the interior nodes) and of a unit sphere
// inflated by 1.25 (K_b (1/1.25 - 1)^2 per area), against node spacing and fiber count. The fiber-count knob
// is ShellNodeOptions::neighbor_count k: buildShellFibers makes one fiber per neighbour and its most opposite
// neighbour and drops duplicates, so a node gets about k/2 fibers (shell_fibers.h has no separate knob).
// Per setting: nodes, fibers per node, relative bending-energy error, time per force evaluation
// (ShellEnergy::evaluate with gradient, median and fastest of several runs) and the stable Verlet step at
// rest (ShellEnergy::stableStep, K_s = K_b = rho = 1). Prints a markdown table; `--csv FILE` also writes a
// CSV for scripts/plot_shell_tradeoff.py. `--quick`: fewer settings. `--threads N` (default 1: on a shared
// 2-core machine a parallel evaluation of a few ms waits for descheduled threads and times out at 30-40 ms).
// Usage: bench_shell_accuracy [--csv FILE] [--quick] [--runs N] [--threads N]
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "relaxed_connectivity/shell/shell_energy.h"
#include "relaxed_connectivity/shell/shell_fibers.h"
#include "relaxed_connectivity/shell/shell_nodes.h"

namespace {

using namespace rc;
using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Jittered grid on [-size/2, size/2]^2, z = 0, normal +z (as test/shell/shell_test_support.h).
SurfelCloud sheetCloud(double size, size_t per_side) {
  SurfelCloud cloud;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const double step = size / per_side;
  for (size_t a = 0; a < per_side; ++a) {
    for (size_t b = 0; b < per_side; ++b) {
      cloud.positions.emplace_back(-0.5 * size + (a + 0.5 + jitter(rng)) * step,
                                   -0.5 * size + (b + 0.5 + jitter(rng)) * step, 0.0);
      cloud.normals.push_back(Vec3::UnitZ());
    }
  }
  return cloud;
}

// Fibonacci sampling of the unit sphere, outward normals.
SurfelCloud sphereCloud(size_t count) {
  SurfelCloud cloud;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count;
    const double s = std::sqrt(1.0 - z * z);
    const Vec3 n(s * std::cos(golden * i), s * std::sin(golden * i), z);
    cloud.positions.push_back(n);
    cloud.normals.push_back(n);
  }
  return cloud;
}

struct Row {
  std::string shape;
  double spacing = 0.0;  ///< requested node spacing
  size_t neighbors = 0, nodes = 0, fibers = 0;
  double bending = 0.0, analytic = 0.0, ms_per_eval = 0.0, ms_fastest = 0.0, stable_dt = 0.0,
         anisotropy = 0.0;
  std::string failure;
  double relError() const { return bending / analytic - 1.0; }
};

// Median and fastest of at least `runs` evaluations, more until 0.25 s have passed (the fastest is the better
// estimate on a loaded machine, where a run of a few ms is often descheduled).
std::pair<double, double> timeEvaluation(const ShellEnergy& energy, const std::vector<Vec3>& x, int runs) {
  std::vector<Vec3> gradient;
  energy.evaluate(x, &gradient);  // warm-up
  std::vector<double> ms;
  const Clock::time_point start = Clock::now();
  while (int(ms.size()) < runs ||
         (std::chrono::duration<double>(Clock::now() - start).count() < 0.25 && ms.size() < 200)) {
    const Clock::time_point t0 = Clock::now();
    energy.evaluate(x, &gradient);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  return {median(ms), *std::min_element(ms.begin(), ms.end())};
}

Row measure(const std::string& shape, double h, size_t k, int runs) {
  Row row;
  row.shape = shape;
  row.spacing = h;
  row.neighbors = k;
  ShellMaterial material;
  material.stretch_stiffness = material.bending_stiffness = material.areal_density = 1.0;
  try {
    ShellNodeOptions options;
    options.spacing = h;
    options.neighbor_count = k;
    const bool cylinder = shape == "cylinder";
    const double size = 1.4, radius = 0.6, inflation = 1.25;
    // About 5 surfels per node spacing, so the clustering has room to place the nodes.
    const ShellNodes nodes =
        cylinder ? selectShellNodes(sheetCloud(size, std::max<size_t>(180, size_t(5.0 * size / h))), options)
                 : selectShellNodes(sphereCloud(std::max<size_t>(20000, size_t(6.0 * 4.0 * M_PI / (h * h)))),
                                    options);
    const ShellFibers fibers = buildShellFibers(nodes);
    const ShellEnergy energy(nodes, fibers, material);
    row.nodes = nodes.size();
    row.fibers = fibers.size();
    row.anisotropy = nodes.sampling.median;
    std::vector<Vec3> x;
    if (cylinder) {
      for (const Vec3& p : nodes.rest_positions)
        x.emplace_back(radius * std::sin(p.x() / radius), p.y(), radius * (1.0 - std::cos(p.x() / radius)));
      std::vector<double> bend;
      energy.nodeEnergies(x, nullptr, &bend);
      double area = 0.0;
      for (size_t i = 0; i < nodes.size(); ++i) {  // interior: 2.5 spacings from the open edges
        const Vec3& p = nodes.rest_positions[i];
        if (std::max(std::abs(p.x()), std::abs(p.y())) > 0.5 * size - 2.5 * nodes.spacing) continue;
        row.bending += bend[i];
        area += nodes.rest_areas[i];
      }
      row.analytic = 0.5 / (radius * radius) * area;
    } else {
      for (const Vec3& p : nodes.rest_positions) x.push_back(inflation * p);
      row.bending = energy.evaluate(x).bending;
      const double dk = 1.0 / inflation - 1.0;
      row.analytic = dk * dk * 4.0 * M_PI;  // K_b/2 (dk1^2 + dk2^2) A0
    }
    std::tie(row.ms_per_eval, row.ms_fastest) = timeEvaluation(energy, x, runs);
    row.stable_dt = energy.stableStep(nodes.rest_positions).combined;
  } catch (const std::exception& e) {
    row.failure = e.what();
  }
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  const char* csv_path = nullptr;
  bool quick = false;
  int runs = 15, threads = 1;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--csv") && a + 1 < argc) {
      csv_path = argv[++a];
    } else if (!std::strcmp(argv[a], "--quick")) {
      quick = true;
    } else if (!std::strcmp(argv[a], "--runs") && a + 1 < argc) {
      runs = std::max(1, std::atoi(argv[++a]));
    } else if (!std::strcmp(argv[a], "--threads") && a + 1 < argc) {
      threads = std::max(1, std::atoi(argv[++a]));
    } else {
      std::fprintf(stderr, "usage: %s [--csv FILE] [--quick] [--runs N] [--threads N]\n", argv[0]);
      return 2;
    }
  }
  omp_set_num_threads(threads);
  const std::vector<double> sheet_h = quick ? std::vector<double>{0.1, 0.05}
                                            : std::vector<double>{0.14, 0.1, 0.07, 0.05, 0.035, 0.025, 0.018};
  const std::vector<double> sphere_h =
      quick ? std::vector<double>{0.25, 0.13} : std::vector<double>{0.3, 0.2, 0.13, 0.09, 0.065, 0.045};
  const std::vector<size_t> ks = quick ? std::vector<size_t>{6, 8} : std::vector<size_t>{6, 8, 12, 16};
  std::vector<Row> rows;
  for (const char* shape : {"cylinder", "sphere"}) {
    for (size_t k : ks) {
      for (double h : std::string(shape) == "cylinder" ? sheet_h : sphere_h) {
        rows.push_back(measure(shape, h, k, runs));
        std::fprintf(stderr, "%s h %.3f k %zu done\n", shape, h, k);
      }
    }
  }
  std::printf(
      "Bending energy against the analytic value (cylinder r = 0.6 on a 1.4 x 1.4 sheet, interior nodes; "
      "unit sphere inflated by 1.25); time per force evaluation (energy + gradient, %d thread(s)), median "
      "and fastest "
      "of >= %d runs (more up to 0.25 s); "
      "stable step at rest for K_s = K_b = rho = 1; k = neighbours per node (fibers ~ k/2 per node)\n\n",
      threads, runs);
  std::printf(
      "| shape | h | k | nodes | fibers / node | sampling anisotropy (median) | bending / analytic | error "
      "%% "
      "| ms / force eval. median (fastest) | us / node (fastest) | stable dt |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    if (!r.failure.empty()) {
      std::printf("| %s | %.3f | %zu | - | - | - | failed: %s | | | | |\n", r.shape.c_str(), r.spacing,
                  r.neighbors, r.failure.c_str());
      continue;
    }
    std::printf("| %s | %.3f | %zu | %zu | %.2f | %.3f | %.4f | %+.2f | %.3f (%.3f) | %.3f | %.3e |\n",
                r.shape.c_str(), r.spacing, r.neighbors, r.nodes, double(r.fibers) / r.nodes, r.anisotropy,
                r.bending / r.analytic, 100.0 * r.relError(), r.ms_per_eval, r.ms_fastest,
                1e3 * r.ms_fastest / r.nodes, r.stable_dt);
  }
  if (!csv_path) return 0;
  FILE* f = std::fopen(csv_path, "w");
  if (!f) {
    std::fprintf(stderr, "cannot write %s\n", csv_path);
    return 1;
  }
  std::fprintf(f,
               "shape,spacing,neighbor_count,nodes,fibers,fibers_per_node,sampling_anisotropy,bending_ratio,"
               "rel_error,ms_per_eval,ms_per_eval_fastest,us_per_node_fastest,stable_dt\n");
  for (const Row& r : rows) {
    if (!r.failure.empty()) continue;
    std::fprintf(f, "%s,%.4f,%zu,%zu,%zu,%.4f,%.4f,%.6f,%.6f,%.5f,%.5f,%.5f,%.6e\n", r.shape.c_str(),
                 r.spacing, r.neighbors, r.nodes, r.fibers, double(r.fibers) / r.nodes, r.anisotropy,
                 r.bending / r.analytic, r.relError(), r.ms_per_eval, r.ms_fastest,
                 1e3 * r.ms_fastest / r.nodes, r.stable_dt);
  }
  std::fclose(f);
  std::printf("\nwrote %s\n", csv_path);
  return 0;
}
