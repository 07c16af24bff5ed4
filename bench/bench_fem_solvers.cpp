// Linear solvers of the implicit Euler step (thesis 9.1.4, (9.20)): time per WarpedDynamics::step() for
// warm-started PCG with a Jacobi (the default) or incomplete Cholesky preconditioner, Eigen's SimplicialLDLT
// and CHOLMOD's supernodal Cholesky (analysed once), on tetrahedral (6 per cube) and hexahedral cantilever
// grids 4:1:1 of about 1k, 10k and 50k nodes. A bending velocity field and gravity keep the element rotations
// changing. Median of 5 steps after one untimed step (which holds the direct solvers' analysis); to keep the
// run near 2-3 minutes on 2 cores, a solver whose untimed step took over 1.5 s is timed on 1 step (marked *),
// and one whose untimed step, extrapolated to the next grid (direct: dofs^2, PCG: dofs^1.5), would exceed
// 20 s is skipped there.
// Prints a markdown table; `--quick`: the 1k and 10k grids only.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "relaxed_connectivity/fem/cholmod_solver.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace {

using rc::LinearElasticModel;
using rc::PolyhedralMesh;
using rc::Vec3;
using rc::WarpedDynamics;
using rc::WarpedDynamicsOptions;
using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

struct SolverCase {
  const char* name;
  WarpedDynamicsOptions::Solver solver;
  WarpedDynamicsOptions::Preconditioner preconditioner;
  bool skipped = false;       // too slow on a smaller grid
  double last_first_s = 0.0;  // untimed step on the previous grid
  int last_dofs = 0;
};

struct Timing {
  double median_ms = 0.0, first_ms = 0.0, iterations = 0.0;
  bool ran = false;
  int runs = 0;
};

Timing timeSteps(const LinearElasticModel& model, const SolverCase& c, int runs) {  // runs: timed steps
  WarpedDynamicsOptions options;
  options.time_step = 0.01;
  options.gravity = Vec3(0, 0, -9.81);
  options.solver = c.solver;
  options.preconditioner = c.preconditioner;
  WarpedDynamics sim(model, options);
  // Bending: v_z = -(x / L)^2 (a cantilever tip swinging down), the root at rest.
  Eigen::VectorXd velocities = Eigen::VectorXd::Zero(sim.numDofs());
  for (int i = 0; i < sim.numNodes(); ++i) {
    const double s = model.mesh().node(i).x() / 4.0;
    velocities[3 * i + 2] = -2.0 * s * s;
  }
  sim.setVelocities(velocities);
  Timing timing;
  auto start = Clock::now();
  sim.step();
  timing.first_ms = 1e3 * seconds(start);
  if (timing.first_ms > 1500.0) runs = 1;
  std::vector<double> times;
  int iterations = 0;
  for (int r = 0; r < runs; ++r) {
    start = Clock::now();
    const rc::StepStatistics stats = sim.step();
    times.push_back(1e3 * seconds(start));
    iterations += stats.solver_iterations;
    if (!stats.converged) std::fprintf(stderr, "warning: %s did not converge\n", c.name);
  }
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  timing.median_ms = times[times.size() / 2];
  timing.iterations = double(iterations) / runs;
  timing.ran = true;
  timing.runs = runs;
  return timing;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int runs = 5;
  const double skip_predicted_s = 20.0;
  std::vector<int> sizes = {6, 13, 23};  // 4n x n x n cells: 1,225 / 10,388 / 53,568 nodes
  if (quick) sizes.pop_back();
  using Solver = WarpedDynamicsOptions::Solver;
  using Pre = WarpedDynamicsOptions::Preconditioner;
  std::vector<SolverCase> solvers = {{"PCG Jacobi", Solver::kConjugateGradient, Pre::kJacobi},
                                     {"PCG IC", Solver::kConjugateGradient, Pre::kIncompleteCholesky},
                                     {"SimplicialLDLT", Solver::kSimplicialLDLT, Pre::kJacobi}};
  if (rc::cholmodAvailable()) solvers.push_back({"CHOLMOD", Solver::kCholmod, Pre::kJacobi});

  std::printf(
      "Implicit Euler step of a 4 x 1 x 1 cantilever (E = 1e6, nu = 0.3, rho = 1000, dt = 0.01, warped), "
      "median of %d steps [ms]; (x) = time / PCG Jacobi; PCG: warm start, tolerance 1e-8, mean iterations in "
      "[]%s\n\n",
      runs, rc::cholmodAvailable() ? "" : "; this build lacks CHOLMOD");
  std::printf("| grid | nodes | elements | dofs | setup [s] |");
  for (const SolverCase& c : solvers) std::printf(" %s |", c.name);
  std::printf("\n|---|---:|---:|---:|---:|");
  for (size_t k = 0; k < solvers.size(); ++k) std::printf("---:|");
  std::printf("\n");
  const auto bench_start = Clock::now();
  for (const bool tetrahedral : {true, false}) {
    for (SolverCase& c : solvers) c.skipped = false, c.last_dofs = 0;
    for (const int n : sizes) {
      auto start = Clock::now();
      const Vec3 lo(0, 0, 0), hi(4, 1, 1);
      PolyhedralMesh mesh = tetrahedral ? PolyhedralMesh::tetrahedralGrid(lo, hi, 4 * n, n, n)
                                        : PolyhedralMesh::hexahedralGrid(lo, hi, 4 * n, n, n);
      const LinearElasticModel model(std::move(mesh), 1e6, 0.3, 1000.0);
      const double setup_s = seconds(start);
      std::printf("| %s %dx%dx%d | %d | %d | %d | %.1f |", tetrahedral ? "tet" : "hex", 4 * n, n, n,
                  model.mesh().numNodes(), model.mesh().numElements(), model.numDofs(), setup_s);
      double reference_ms = 0.0;
      for (SolverCase& c : solvers) {
        // Extrapolated untimed step: direct solvers ~ dofs^2 (3D fill), PCG ~ dofs^1.5 (iterations ~ h^-1).
        const double growth = c.last_dofs > 0 ? double(model.numDofs()) / c.last_dofs : 0.0;
        const double predicted_s =
            c.last_first_s * std::pow(growth, c.solver == Solver::kConjugateGradient ? 1.5 : 2.0);
        if (c.skipped || predicted_s > skip_predicted_s) {
          c.skipped = true;
          std::printf(" skipped (~%.0f s) |", predicted_s);
          continue;
        }
        const Timing t = timeSteps(model, c, runs);
        c.last_first_s = 1e-3 * t.first_ms;
        c.last_dofs = model.numDofs();
        if (reference_ms == 0.0) reference_ms = t.median_ms;
        const char* mark = t.runs < runs ? "*" : "";
        if (c.solver == Solver::kConjugateGradient)
          std::printf(" %.1f%s [%.0f] (%.2f) |", t.median_ms, mark, t.iterations, t.median_ms / reference_ms);
        else
          std::printf(" %.1f%s (%.2f) |", t.median_ms, mark, t.median_ms / reference_ms);
        std::fflush(stdout);
      }
      std::printf("\n");
    }
  }
  std::printf(
      "\nTotal %.0f s. * one timed step; skipped (~t): extrapolated untimed step. Direct solvers: the "
      "first (untimed) step also analyses the pattern.\n",
      seconds(bench_start));
  return 0;
}
