// Per-frame time of the cutting scenes of thesis Figs. 9.9 (sliced block) and 9.10 (bunny, curved cuts),
// split into the phases of Table 9.1: bases (element integration and solver set-up after cuts; elements a
// cut left unchanged reuse their data), rotations (R_e, element forces, R_e K_e R_e^T), assembly (scatter
// into K_w, system matrix, right-hand side), solve and topology (cuts, state transfer). Each phase is given
// as median / mean over the timed frames of its time in that frame; "total" is the mean frame time. Fig. 9.9
// runs all its frames; Fig. 9.10 (28k tetrahedra) runs all 75 or its first `--bunny-frames` frames. The
// thesis numbers (Pentium 4, 3 GHz) are printed next to ours: seconds per frame, in parenthesis without the
// recomputation of basis functions, and node / element counts after all cuts. Last: elements integrated
// anew / reused after the cuts. Then the cost normalised by size: the mean node and element counts over the
// frames, microseconds per node and per element per frame, against the thesis' seconds per frame divided by
// its node and element counts (Table 9.1 gives them at the start and the end only; its bunny row lists 24,079
// nodes / 8,278 elements at the start, fewer elements than nodes, which no tetrahedral mesh has, so the
// columns are read both ways). Usage: bench_fem_scenes [--bunny-frames N] [--bunny-solver
// cholmod|cholmod_pcg|cg_ic|cg]
//        [--refactor-iterations N] [--tolerance T] [--contact-updates N] [--extension-iterations N]
//        [--dump-positions FILE] [--no-carry] [--blas-thread-control] [--skip-block] [--scene-dir DIR]
// (--bunny-solver replaces the bunny scene's solver; cg and cg_ic use tolerance 1e-6 unless --tolerance gives
// the CG relative residual; --contact-updates sets pcg_contact_updates (0: the preconditioner ignores contact
// changes, the old path) and --extension-iterations pcg_extension_iterations (0: the old path);
// --dump-positions writes the bunny's final node positions, "x y z" per line; --blas-thread-control gives
// factorisations all threads and shuts OpenBLAS's pool down after each (setCholmodBlasThreadControl; off by
// default) and --no-carry starts the bodies made by cuts afresh (FemSimulation::setCarryStateAcrossCuts; the
// old path).)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "relaxed_connectivity/fem/cholmod_solver.h"
#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/fem/fem_simulation.h"

namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct ThesisRow {
  const char* figure;
  int nodes_start, elements_start, nodes_end, elements_end;
  double seconds, seconds_without_bases;
  bool columns_doubtful;  // fewer elements than nodes in a tetrahedral start mesh: read both ways
};

struct SceneResult {
  std::string name;
  int frames = 0, nodes_start = 0, elements_start = 0, nodes = 0, elements = 0, bodies = 0;
  long iterations = 0, unconverged = 0, recomputed = 0, reused = 0;
  rc::FemSimulation::SolverCounts solver;
  double setup = 0.0, mean_frame = 0.0, mean_nodes = 0.0, mean_elements = 0.0;
  std::vector<double> bases, rotations, assembly, solve, topology, frame;
};

// Solver override for the bunny (--bunny-solver): the scene's solver when empty.
struct SolverOverride {
  std::string type;  // cholmod, cholmod_pcg, cg_ic, cg
  int refactor_iterations = 0;
  double tolerance = 0.0;         // CG relative residual; 0: the scene's (or 1e-6 for cg and cg_ic)
  int contact_updates = -1;       // pcg_contact_updates; -1: the scene's
  int extension_iterations = -1;  // pcg_extension_iterations; -1: the scene's
  std::string positions_file;     // --dump-positions: final node positions, one "x y z" line per node
  bool carry_state = true;        // --no-carry: bodies made by cuts start fresh (the old path)
};

SceneResult runScene(const std::string& path, int max_frames, const SolverOverride& solver = {}) {
  SceneResult r;
  const Clock::time_point setup_start = Clock::now();
  rc::FemScene scene = rc::loadFemScene(path);
  using Solver = rc::WarpedDynamicsOptions::Solver;
  using Preconditioner = rc::WarpedDynamicsOptions::Preconditioner;
  if (solver.type == "cholmod") {
    scene.dynamics.solver = Solver::kCholmod;
  } else if (solver.type == "cholmod_pcg") {
    scene.dynamics.solver = Solver::kCholmodPcg;
  } else if (solver.type == "cg_ic" || solver.type == "cg") {
    scene.dynamics.solver = Solver::kConjugateGradient;
    scene.dynamics.preconditioner =
        solver.type == "cg_ic" ? Preconditioner::kIncompleteCholesky : Preconditioner::kJacobi;
    scene.dynamics.cg_tolerance = 1e-6;
  } else if (!solver.type.empty()) {
    throw std::invalid_argument("unknown --bunny-solver '" + solver.type +
                                "' (known: cholmod, cholmod_pcg, cg_ic, cg)");
  }
  if (solver.refactor_iterations > 0) scene.dynamics.pcg_refactor_iterations = solver.refactor_iterations;
  if (solver.tolerance > 0.0) scene.dynamics.cg_tolerance = solver.tolerance;
  if (solver.contact_updates >= 0) scene.dynamics.pcg_contact_updates = solver.contact_updates;
  if (solver.extension_iterations >= 0) scene.dynamics.pcg_extension_iterations = solver.extension_iterations;
  rc::FemSimulation sim(scene);
  sim.setCarryStateAcrossCuts(solver.carry_state);
  r.setup = std::chrono::duration<double>(Clock::now() - setup_start).count();
  r.name = scene.name;
  r.nodes_start = sim.numNodes();
  r.elements_start = sim.numElements();
  const int frames = max_frames > 0 ? std::min(max_frames, scene.frame_count) : scene.frame_count;
  double total = 0.0;
  for (int f = 0; f < frames; ++f) {
    const rc::FemPhaseTimes before = sim.phaseTimes();
    const Clock::time_point start = Clock::now();
    for (int s = 0; s < scene.steps_per_frame; ++s) sim.step();
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    const rc::FemPhaseTimes& after = sim.phaseTimes();
    r.bases.push_back(after.integration - before.integration);
    r.rotations.push_back(after.rotations - before.rotations);
    r.assembly.push_back(after.assembly - before.assembly);
    r.solve.push_back(after.solve - before.solve);
    r.topology.push_back(after.topology - before.topology);
    r.frame.push_back(seconds);
    total += seconds;
    r.mean_nodes += sim.numNodes();
    r.mean_elements += sim.numElements();
  }
  if (frames > 0) r.mean_nodes /= frames, r.mean_elements /= frames;
  if (!solver.positions_file.empty()) {
    std::FILE* out = std::fopen(solver.positions_file.c_str(), "w");
    if (!out) throw std::runtime_error("cannot write " + solver.positions_file);
    for (const rc::FemBodyState& body : sim.bodyStates())
      for (Eigen::Index k = 0; k + 2 < body.positions->size(); k += 3)
        std::fprintf(out, "%.17g %.17g %.17g\n", (*body.positions)[k], (*body.positions)[k + 1],
                     (*body.positions)[k + 2]);
    std::fclose(out);
  }
  r.frames = frames;
  r.mean_frame = frames > 0 ? total / frames : 0.0;
  r.nodes = sim.numNodes();
  r.elements = sim.numElements();
  r.bodies = sim.numBodies();
  r.iterations = sim.solverIterations();
  r.unconverged = sim.unconvergedSolves();
  r.recomputed = sim.recomputedElements();
  r.reused = sim.reusedElements();
  r.solver = sim.solverCounts();
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  int bunny_frames = 0;
  SolverOverride bunny_solver;
  bool skip_block = false;
  std::string scene_dir =
      std::string(__FILE__).substr(0, std::string(__FILE__).rfind('/')) + "/../config/fem";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--bunny-frames") && i + 1 < argc) {
      bunny_frames = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--bunny-solver") && i + 1 < argc) {
      bunny_solver.type = argv[++i];
    } else if (!std::strcmp(argv[i], "--refactor-iterations") && i + 1 < argc) {
      bunny_solver.refactor_iterations = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--tolerance") && i + 1 < argc) {
      bunny_solver.tolerance = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--contact-updates") && i + 1 < argc) {
      bunny_solver.contact_updates = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--extension-iterations") && i + 1 < argc) {
      bunny_solver.extension_iterations = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--dump-positions") && i + 1 < argc) {
      bunny_solver.positions_file = argv[++i];
    } else if (!std::strcmp(argv[i], "--no-carry")) {
      bunny_solver.carry_state = false;
    } else if (!std::strcmp(argv[i], "--blas-thread-control")) {
      rc::setCholmodBlasThreadControl(true);
    } else if (!std::strcmp(argv[i], "--skip-block")) {
      skip_block = true;
    } else if (!std::strcmp(argv[i], "--scene-dir") && i + 1 < argc) {
      scene_dir = argv[++i];
    } else {
      std::fprintf(
          stderr,
          "usage: %s [--bunny-frames N] [--bunny-solver cholmod|cholmod_pcg|cg_ic|cg] "
          "[--refactor-iterations N] [--tolerance T] [--contact-updates N] [--extension-iterations N] "
          "[--dump-positions FILE] [--no-carry] [--blas-thread-control] [--skip-block] [--scene-dir "
          "DIR]\n",
          argv[0]);
      return 2;
    }
  }
  // Table 9.1: start and end node / element counts, seconds per frame (without basis recomputation).
  const ThesisRow thesis[] = {{"9.9", 64, 27, 1214, 60, 0.8, 0.04, false},
                              {"9.10", 24079, 8278, 46132, 44118, 6.08, 3.56, true}};
  const std::string files[] = {scene_dir + "/fig9_9_sliced_block.yaml", scene_dir + "/fig9_10_bunny.yaml"};
  const int max_frames[] = {0, bunny_frames};
  std::vector<SceneResult> results;
  std::vector<int> rows;
  for (int k = skip_block ? 1 : 0; k < 2; ++k) {
    if (k == 1 && !std::filesystem::exists(std::string(RC_SHARED_DATA_DIR) + "/bunny.ply")) {
      std::printf("Fig. 9.10 skipped: needs ../shared/data/bunny.ply (%s)\n\n", RC_SHARED_DATA_DIR);
      continue;
    }
    try {
      results.push_back(runScene(files[k], max_frames[k], k == 1 ? bunny_solver : SolverOverride()));
      rows.push_back(k);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s\n", files[k].c_str(), e.what());
      return 1;
    }
  }
  std::printf("Per-frame time, ms: median / mean over the frames per phase; total: mean frame time\n\n");
  std::printf(
      "| Fig. | frames | bases | rotations | assembly | solve | topology | total ms | thesis s/frame "
      "| setup s | nodes start -> end | elements start -> end | bodies | thesis nodes / elements end "
      "| solves or CG it. |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (size_t row = 0; row < results.size(); ++row) {
    const SceneResult& r = results[row];
    const int k = rows[row];
    auto phase = [](const std::vector<double>& v) {
      double sum = 0.0;
      for (double x : v) sum += x;
      char text[64];
      std::snprintf(text, sizeof text, "%.1f / %.1f", 1e3 * median(v),
                    v.empty() ? 0.0 : 1e3 * sum / v.size());
      return std::string(text);
    };
    std::printf(
        "| %s | %d | %s | %s | %s | %s | %s | %.1f | %.2f (%.2f) | %.2f | %d -> %d | %d -> %d | %d | %d / %d "
        "| %ld |\n",
        thesis[k].figure, r.frames, phase(r.bases).c_str(), phase(r.rotations).c_str(),
        phase(r.assembly).c_str(), phase(r.solve).c_str(), phase(r.topology).c_str(), 1e3 * r.mean_frame,
        thesis[k].seconds, thesis[k].seconds_without_bases, r.setup, r.nodes_start, r.nodes, r.elements_start,
        r.elements, r.bodies, thesis[k].nodes_end, thesis[k].elements_end, r.iterations);
  }
  std::printf(
      "\nCost by size: mean nodes / elements over the frames; us per node and per element per frame (mean "
      "frame time divided by the mean count). Thesis: its s/frame divided by the mean of its start and end "
      "counts as printed in Table 9.1, and for the bunny also with its node and element columns "
      "exchanged.\n\n");
  std::printf(
      "| Fig. | mean nodes | mean elements | us / node | us / element | thesis mean nodes / elements | "
      "thesis "
      "us / node | thesis us / element | x thesis per node | x thesis per element | same, columns swapped "
      "|\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (size_t row = 0; row < results.size(); ++row) {
    const SceneResult& r = results[row];
    const ThesisRow& t = thesis[rows[row]];
    if (r.mean_nodes <= 0.0 || r.mean_elements <= 0.0) continue;
    const double us_node = 1e6 * r.mean_frame / r.mean_nodes,
                 us_element = 1e6 * r.mean_frame / r.mean_elements;
    const double t_nodes = 0.5 * (t.nodes_start + t.nodes_end),
                 t_elements = 0.5 * (t.elements_start + t.elements_end);
    const double t_node = 1e6 * t.seconds / t_nodes, t_element = 1e6 * t.seconds / t_elements;
    // Swapped reading: the thesis' elements are our nodes' peers and vice versa.
    char swapped[64] = "-";
    if (t.columns_doubtful)
      std::snprintf(swapped, sizeof swapped, "%.1f / %.1f", 1e6 * t.seconds / t_elements / us_node,
                    1e6 * t.seconds / t_nodes / us_element);
    std::printf("| %s | %.0f | %.0f | %.2f | %.2f | %.0f / %.0f | %.1f | %.1f | %.1f | %.1f | %s |\n",
                t.figure, r.mean_nodes, r.mean_elements, us_node, us_element, t_nodes, t_elements, t_node,
                t_element, t_node / us_node, t_element / us_element, swapped);
  }
  std::printf("\nElements after cuts: integrated anew / reused from the cut body\n");
  for (const SceneResult& r : results) std::printf("%s: %ld / %ld\n", r.name.c_str(), r.recomputed, r.reused);
  std::printf(
      "\nCHOLMOD: analyses (ms) / factorisations (ms) over the run; bodies built (the first and by cuts)\n");
  for (const SceneResult& r : results)
    std::printf("%s: %ld (%.0f) / %ld (%.0f); %ld\n", r.name.c_str(), r.solver.analyses,
                1e3 * r.solver.analysis_seconds, r.solver.factorizations,
                1e3 * r.solver.factorization_seconds, r.solver.bodies_built);
  std::printf("\nUnconverged solves (CG short of its tolerance)\n");
  for (const SceneResult& r : results) std::printf("%s: %ld\n", r.name.c_str(), r.unconverged);
  return 0;
}
