// FEM speed/accuracy benchmark (thesis 9.1.3-9.1.4): (a) static cantilever tip deflection against
// Timoshenko beam theory for several per-element integration schemes on hexahedral, tetrahedral and
// random-plane polyhedral meshes at three resolutions, with the time per stiffness assembly; (b) free-free
// bending vibration of a beam under linearised implicit Euler (WarpedDynamics): oscillation period and
// amplitude decay per period against the analytic Euler-Bernoulli first bending frequency and the discrete
// model's own first bending frequency, for several time steps, with the wall time per simulated second.
// Prints markdown tables (medians of several runs, one thread for the assembly); `--csv FILE` also writes
// every row as CSV (scripts/plot_fem_tradeoff.py draws it); `--quick`: fewer runs and resolutions.
//
// The element integration of the library has a fixed sample set: one vertex sample per node and one face
// sample per boundary triangle ((9.17)-(9.19), ElementQuadratureOptions exposes only the sample positions,
// the exact gradient correction and the tetrahedron shortcut). The other sample counts below are built here
// on the public ElementQuadrature type: 1 sample (centroid), n vertex samples only, and 1 or 4 Gauss points
// in each pyramid (boundary triangle, centroid); all with the same exact gradient correction (patch test).
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "relaxed_connectivity/fem/element_stiffness.h"
#include "relaxed_connectivity/fem/linear_elasticity.h"
#include "relaxed_connectivity/fem/mean_value_coordinates.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"
#include "relaxed_connectivity/fem/warped_dynamics.h"

namespace {

using rc::ConvexPolyhedron;
using rc::ElementQuadrature;
using rc::ElementQuadratureOptions;
using rc::LinearElasticModel;
using rc::PolyhedralMesh;
using rc::Vec3;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// ---------------------------------------------------------------------------------------------------------
// Integration schemes
// ---------------------------------------------------------------------------------------------------------

enum class Scheme { kCentroid, kVertex, kThesis, kThesisCentral, kPyramid1, kPyramid4 };

const char* schemeName(Scheme s) {
  switch (s) {
    case Scheme::kCentroid:
      return "centroid (1)";
    case Scheme::kVertex:
      return "vertex (n)";
    case Scheme::kThesis:
      return "thesis (n+T)";
    case Scheme::kThesisCentral:
      return "thesis 0.5/0.5 (n+T)";
    case Scheme::kPyramid1:
      return "pyramid 1-pt (T)";
    case Scheme::kPyramid4:
      return "pyramid 4-pt (4T)";
  }
  return "?";
}

// Samples with weights summing to V; MVC gradients there plus the exact gradient correction.
ElementQuadrature customQuadrature(const ConvexPolyhedron& element, Scheme scheme) {
  if (scheme == Scheme::kThesis) return rc::elementQuadrature(element);
  if (scheme == Scheme::kThesisCentral) {
    ElementQuadratureOptions options;
    options.vertex_sample_blend = 0.5;
    options.face_sample_blend = 0.5;
    return rc::elementQuadrature(element, options);
  }
  const int n = element.numNodes();
  const double volume = element.volume();
  const Vec3& c = element.centroid();
  ElementQuadrature q;
  q.volume = volume;
  q.node_volume_fractions = Eigen::VectorXd::Zero(n);
  for (const auto& tri : element.triangles()) {
    const Vec3 a = element.node(tri[0]), b = element.node(tri[1]), d = element.node(tri[2]);
    const double pyramid = (a - c).dot((b - c).cross(d - c)) / 6.0;  // (9.18)
    for (int v : tri) q.node_volume_fractions[v] += pyramid / (3.0 * volume);
    if (pyramid <= 1e-14 * volume) continue;
    if (scheme == Scheme::kPyramid1) {
      q.points.push_back((a + b + c + d) / 4.0);
      q.weights.push_back(pyramid);
    } else if (scheme == Scheme::kPyramid4) {
      const double alpha = 0.5854101966249685, beta = 0.1381966011250105;  // degree-2 rule
      const Vec3 corners[4] = {c, a, b, d};
      for (int k = 0; k < 4; ++k) {
        Vec3 p = Vec3::Zero();
        for (int j = 0; j < 4; ++j) p += (j == k ? alpha : beta) * corners[j];
        q.points.push_back(p);
        q.weights.push_back(pyramid / 4.0);
      }
    }
  }
  if (scheme == Scheme::kCentroid) {
    q.points.push_back(c);
    q.weights.push_back(volume);
  } else if (scheme == Scheme::kVertex) {
    for (int i = 0; i < n; ++i) {
      q.points.push_back(0.8 * element.node(i) + 0.2 * c);
      q.weights.push_back(q.node_volume_fractions[i] * volume);
    }
  }
  const rc::MeanValueCoordinates mvc(element);
  Eigen::VectorXd lambda;
  rc::NodeGradients sampled = rc::NodeGradients::Zero(n, 3);
  q.gradients.resize(q.points.size());
  for (size_t s = 0; s < q.points.size(); ++s) {
    mvc.evaluate(q.points[s], lambda, q.gradients[s]);
    sampled += q.weights[s] * q.gradients[s];
  }
  const rc::NodeGradients correction = (rc::exactIntegratedGradients(element) - sampled) / volume;
  for (rc::NodeGradients& g : q.gradients) g += correction;
  return q;
}

struct Assembly {
  Eigen::SparseMatrix<double> stiffness;
  double samples_per_element = 0.0;
};

// Quadrature, element stiffness and global assembly (one thread).
Assembly assemble(const PolyhedralMesh& mesh, Scheme scheme, const rc::Matrix6d& elasticity) {
  Assembly result;
  std::vector<Eigen::Triplet<double>> triplets;
  long samples = 0;
  for (int e = 0; e < mesh.numElements(); ++e) {
    const ConvexPolyhedron& element = mesh.element(e);
    const ElementQuadrature q = customQuadrature(element, scheme);
    samples += static_cast<long>(q.points.size());
    const Eigen::MatrixXd k = rc::elementStiffness(q, elasticity);
    const std::vector<int>& ids = element.globalNodeIds();
    for (int a = 0; a < element.numNodes(); ++a)
      for (int b = 0; b < element.numNodes(); ++b)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            triplets.emplace_back(3 * ids[a] + i, 3 * ids[b] + j, k(3 * a + i, 3 * b + j));
  }
  result.stiffness.resize(3 * mesh.numNodes(), 3 * mesh.numNodes());
  result.stiffness.setFromTriplets(triplets.begin(), triplets.end());
  result.samples_per_element = static_cast<double>(samples) / mesh.numElements();
  return result;
}

// K U = F with the dofs of `fixed` nodes at zero; NaN vector if the reduced matrix is singular.
Eigen::VectorXd solveClamped(const Eigen::SparseMatrix<double>& k, const Eigen::VectorXd& f,
                             const std::vector<char>& fixed) {
  const int n = static_cast<int>(fixed.size());
  std::vector<int> reduced(3 * n, -1);
  int free_dofs = 0;
  for (int i = 0; i < n; ++i)
    if (!fixed[i])
      for (int d = 0; d < 3; ++d) reduced[3 * i + d] = free_dofs++;
  std::vector<Eigen::Triplet<double>> triplets;
  for (int col = 0; col < k.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(k, col); it; ++it)
      if (reduced[it.row()] >= 0 && reduced[it.col()] >= 0)
        triplets.emplace_back(reduced[it.row()], reduced[it.col()], it.value());
  Eigen::SparseMatrix<double> a(free_dofs, free_dofs);
  a.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::VectorXd b(free_dofs);
  for (int d = 0; d < 3 * n; ++d)
    if (reduced[d] >= 0) b[reduced[d]] = f[d];
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * n);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(a);
  if (ldlt.info() != Eigen::Success) return Eigen::VectorXd::Constant(3 * n, NAN);
  const Eigen::VectorXd x = ldlt.solve(b);
  // Zero pivots of a singular reduced matrix (hourglass modes) show up as a large residual.
  if (!x.allFinite() || (a * x - b).norm() > 1e-6 * b.norm()) return Eigen::VectorXd::Constant(3 * n, NAN);
  for (int d = 0; d < 3 * n; ++d)
    if (reduced[d] >= 0) u[d] = x[reduced[d]];
  return u;
}

// ---------------------------------------------------------------------------------------------------------
// (a) Static cantilever
// ---------------------------------------------------------------------------------------------------------

constexpr double kLength = 10.0, kHeight = 1.0, kYoungs = 1000.0, kForce = 0.01;

PolyhedralMesh cantileverMesh(const std::string& type, int n) {
  const Vec3 lo(0, 0, 0), hi(kLength, kHeight, kHeight);
  if (type == "hex") return PolyhedralMesh::hexahedralGrid(lo, hi, 10 * n, n, n);
  if (type == "tet") return PolyhedralMesh::tetrahedralGrid(lo, hi, 10 * n, n, n);
  return PolyhedralMesh::randomPlaneCut(lo, hi, 10 * n, n, n, 6 * n, 7, 0.003);
}

struct StaticRow {
  std::string mesh, scheme;
  int n = 0, dofs = 0, elements = 0;
  double samples = 0.0, tip = 0.0, error = 0.0, assembly_ms = 0.0, solve_ms = 0.0;
};

std::vector<StaticRow> cantilever(bool quick) {
  // Tip load F on the end face x = L (uniform traction), clamp x = 0, nu = 0. Reference: Timoshenko
  // F L^3 / (3 E I) + F L / (kappa G A), kappa = 5/6, G = E / 2 (Euler-Bernoulli alone: 0.6% less).
  const double inertia = std::pow(kHeight, 4) / 12.0, area = kHeight * kHeight;
  const double euler_bernoulli = kForce * std::pow(kLength, 3) / (3.0 * kYoungs * inertia);
  const double timoshenko = euler_bernoulli + kForce * kLength / (5.0 / 6.0 * 0.5 * kYoungs * area);
  const rc::Matrix6d elasticity = rc::isotropicElasticity(kYoungs, 0.0);
  const Scheme schemes[] = {Scheme::kCentroid,      Scheme::kVertex,   Scheme::kThesis,
                            Scheme::kThesisCentral, Scheme::kPyramid1, Scheme::kPyramid4};
  const std::vector<int> resolutions = quick ? std::vector<int>{1, 2} : std::vector<int>{1, 2, 4};
  const int runs = quick ? 1 : 3;
  std::printf(
      "(a) Cantilever %gx%gx%g, E = %g, nu = 0, tip load %g: Timoshenko tip deflection %.6f "
      "(Euler-Bernoulli %.6f); error = tip / Timoshenko - 1; assembly = quadrature + K_e + global K, "
      "one thread, median of %d runs\n\n",
      kLength, kHeight, kHeight, kYoungs, kForce, timoshenko, euler_bernoulli, runs);
  std::printf(
      "| mesh | n | elements | dofs | scheme | samples/element | tip error | assembly ms | solve ms |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  std::vector<StaticRow> rows;
  for (const std::string type : {"hex", "tet", "random"}) {
    for (int n : resolutions) {
      const PolyhedralMesh mesh = cantileverMesh(type, n);
      std::vector<char> fixed(mesh.numNodes(), 0);
      for (int i = 0; i < mesh.numNodes(); ++i) fixed[i] = std::abs(mesh.node(i).x()) < 1e-9;
      std::vector<PolyhedralMesh::Triangle> end_face;
      for (const auto& t : mesh.boundaryTriangles())
        if (std::abs(mesh.node(t[0]).x() - kLength) < 1e-9 &&
            std::abs(mesh.node(t[1]).x() - kLength) < 1e-9 && std::abs(mesh.node(t[2]).x() - kLength) < 1e-9)
          end_face.push_back(t);
      // Consistent loads A_T / 3 per vertex; the tip deflection is the area mean of u_y over the end face.
      Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * mesh.numNodes());
      double end_area = 0.0;
      for (const auto& t : end_face) {
        const double a =
            0.5 * (mesh.node(t[1]) - mesh.node(t[0])).cross(mesh.node(t[2]) - mesh.node(t[0])).norm();
        end_area += a;
        for (int v : t) f[3 * v + 1] -= kForce / area * a / 3.0;
      }
      for (Scheme scheme : schemes) {
        StaticRow row;
        row.mesh = type;
        row.scheme = schemeName(scheme);
        row.n = n;
        row.dofs = 3 * mesh.numNodes();
        row.elements = mesh.numElements();
        std::vector<double> assembly_times, solve_times;
        Eigen::VectorXd u;
        for (int r = 0; r < runs; ++r) {
          const auto start = Clock::now();
          const Assembly k = assemble(mesh, scheme, elasticity);
          assembly_times.push_back(1e3 * secondsSince(start));
          row.samples = k.samples_per_element;
          const auto solve_start = Clock::now();
          u = solveClamped(k.stiffness, f, fixed);
          solve_times.push_back(1e3 * secondsSince(solve_start));
        }
        double tip = 0.0;
        for (const auto& t : end_face) {
          const double a =
              0.5 * (mesh.node(t[1]) - mesh.node(t[0])).cross(mesh.node(t[2]) - mesh.node(t[0])).norm();
          for (int v : t) tip -= a / 3.0 * u[3 * v + 1];
        }
        row.tip = tip / end_area;
        row.error = row.tip / timoshenko - 1.0;
        row.assembly_ms = median(assembly_times);
        row.solve_ms = median(solve_times);
        if (std::isfinite(row.tip) && std::abs(row.error) > 1.0)  // a near-singular K: hourglass modes
          std::printf("| %s | %d | %d | %d | %s | %.1f | hourglass (%+.0f%%) | %.1f | %.1f |\n", type.c_str(),
                      n, row.elements, row.dofs, row.scheme.c_str(), row.samples, 100.0 * row.error,
                      row.assembly_ms, row.solve_ms);
        else if (std::isfinite(row.tip))
          std::printf("| %s | %d | %d | %d | %s | %.1f | %+.2f%% | %.1f | %.1f |\n", type.c_str(), n,
                      row.elements, row.dofs, row.scheme.c_str(), row.samples, 100.0 * row.error,
                      row.assembly_ms, row.solve_ms);
        else
          std::printf("| %s | %d | %d | %d | %s | %.1f | singular K | %.1f | - |\n", type.c_str(), n,
                      row.elements, row.dofs, row.scheme.c_str(), row.samples, row.assembly_ms);
        std::fflush(stdout);
        rows.push_back(row);
      }
    }
  }
  return rows;
}

// ---------------------------------------------------------------------------------------------------------
// (b) Free-free bending vibration under implicit Euler
// ---------------------------------------------------------------------------------------------------------

struct DynamicRow {
  std::string mesh;
  int dofs = 0;
  double dt = 0.0, period = 0.0, decay = 0.0, analytic_period = 0.0, discrete_period = 0.0;
  double predicted_period = 0.0, predicted_decay = 0.0, seconds_per_simulated_second = 0.0;
  double mean_iterations = 0.0;
};

std::vector<DynamicRow> vibration(bool quick) {
  // Beam L x H x W = 10 x 1 x 2 (y-bending is the softest mode: I = W H^3 / 12), E = 1000, nu = 0, rho = 1,
  // free-free. Euler-Bernoulli: omega_1 = (4.7300408 / L)^2 sqrt(E I / (rho A)).
  const double length = 10.0, height = 1.0, width = 2.0, youngs = 1000.0;
  const double inertia = width * std::pow(height, 3) / 12.0, area = width * height;
  const double omega_analytic = std::pow(4.7300408 / length, 2) * std::sqrt(youngs * inertia / area);
  const double analytic_period = 2.0 * M_PI / omega_analytic;
  const std::vector<double> steps = quick ? std::vector<double>{0.3, 0.1, 0.03, 0.01}
                                          : std::vector<double>{0.5, 0.3, 0.1, 0.03, 0.01, 0.003, 0.001};
  const int runs = quick ? 1 : 3;
  std::printf(
      "\n(b) Free-free beam %gx%gx%g, E = %g, nu = 0, rho = 1, started in its first discrete bending mode "
      "(end amplitude 1e-3 L), stiffness-warped implicit Euler (Jacobi CG, tol 1e-8), %.1f analytic periods. "
      "Euler-Bernoulli period %.4f s. Period from zero crossings of the end deflection, decay = amplitude "
      "ratio after one period; 'theory' = backward Euler on the discrete mode: T = 2 pi dt / atan(w dt), "
      "decay = (1 + w^2 dt^2)^(-T / (2 dt)). Median of %d runs.\n\n",
      length, height, width, youngs, 4.0, analytic_period, runs);
  std::printf(
      "| mesh | dofs | dt | steps/period | period | vs Euler-Bernoulli | vs discrete mode | theory period "
      "| decay/period | theory decay | CG it/step | s per simulated s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<DynamicRow> rows;
  for (const std::string type : {"hex", "random"}) {
    const Vec3 lo(0, 0, 0), hi(length, height, width);
    const PolyhedralMesh mesh = type == "hex"
                                    ? PolyhedralMesh::hexahedralGrid(lo, hi, 20, 2, 4)
                                    : PolyhedralMesh::randomPlaneCut(lo, hi, 10, 1, 2, 12, 5, 0.003);
    const LinearElasticModel model(mesh, youngs, 0.0, 1.0);
    // Discrete first bending mode: generalised eigenproblem K x = w^2 M x (lumped M), rigid modes skipped.
    const int dofs = model.numDofs();
    Eigen::VectorXd inv_sqrt_mass(dofs);
    for (int i = 0; i < mesh.numNodes(); ++i)
      inv_sqrt_mass.segment<3>(3 * i).setConstant(1.0 / std::sqrt(model.lumpedMasses()[i]));
    const Eigen::MatrixXd k_dense = Eigen::MatrixXd(model.stiffness());
    const Eigen::MatrixXd a = inv_sqrt_mass.asDiagonal() * k_dense * inv_sqrt_mass.asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a);
    const int mode = 6;  // after the six rigid modes
    const double omega_h = std::sqrt(eigen.eigenvalues()[mode]);
    Eigen::VectorXd shape = inv_sqrt_mass.cwiseProduct(eigen.eigenvectors().col(mode));
    std::vector<int> end_nodes;
    for (int i = 0; i < mesh.numNodes(); ++i)
      if (std::abs(mesh.node(i).x() - length) < 1e-9) end_nodes.push_back(i);
    auto endDeflection = [&](const Eigen::VectorXd& u) {
      double s = 0.0;
      for (int i : end_nodes) s += u[3 * i + 1];
      return s / end_nodes.size();
    };
    double y_energy = 0.0;
    for (int i = 0; i < mesh.numNodes(); ++i) y_energy += shape[3 * i + 1] * shape[3 * i + 1];
    if (y_energy < 0.5 * shape.squaredNorm())
      std::printf("warning: %s mode %d is not a y-bending mode\n", type.c_str(), mode);
    shape *= 1e-3 * length / endDeflection(shape);
    const double discrete_period = 2.0 * M_PI / omega_h;

    for (double dt : steps) {
      DynamicRow row;
      row.mesh = type;
      row.dofs = dofs;
      row.dt = dt;
      row.analytic_period = analytic_period;
      row.discrete_period = discrete_period;
      row.predicted_period = 2.0 * M_PI * dt / std::atan(omega_h * dt);
      row.predicted_decay = std::pow(1.0 + omega_h * omega_h * dt * dt, -row.predicted_period / (2.0 * dt));
      const int num_steps = static_cast<int>(std::ceil(4.0 * analytic_period / dt));
      std::vector<double> times;
      for (int r = 0; r < runs; ++r) {
        rc::WarpedDynamicsOptions options;
        options.time_step = dt;
        rc::WarpedDynamics sim(model, options);
        sim.setPositions(sim.restPositions() + shape);
        std::vector<double> signal{endDeflection(shape)};
        long iterations = 0;
        const auto start = Clock::now();
        for (int s = 0; s < num_steps; ++s) {
          iterations += sim.step().solver_iterations;
          signal.push_back(endDeflection(sim.positions() - sim.restPositions()));
        }
        times.push_back(secondsSince(start) / (num_steps * dt));
        row.mean_iterations = static_cast<double>(iterations) / num_steps;
        // Zero crossings (linear interpolation); period = twice the spacing of the first two, decay = the
        // interpolated value one period after the start relative to the initial value.
        std::vector<double> crossings;
        for (size_t s = 0; s + 1 < signal.size(); ++s)
          if ((signal[s] > 0) != (signal[s + 1] > 0))
            crossings.push_back(dt * (s + signal[s] / (signal[s] - signal[s + 1])));
        row.period = crossings.size() >= 3 ? crossings[2] - crossings[0] : NAN;
        if (std::isfinite(row.period)) {
          const double at = row.period / dt;
          const size_t s = static_cast<size_t>(at);
          const double frac = at - s;
          row.decay =
              s + 1 < signal.size() ? ((1 - frac) * signal[s] + frac * signal[s + 1]) / signal[0] : NAN;
        } else {
          row.decay = NAN;
        }
      }
      row.seconds_per_simulated_second = median(times);
      std::printf("| %s | %d | %g | %.1f | %.4f | %+.2f%% | %+.2f%% | %.4f | %.4f | %.4f | %.1f | %.3f |\n",
                  type.c_str(), dofs, dt, analytic_period / dt, row.period,
                  100.0 * (row.period / analytic_period - 1.0), 100.0 * (row.period / discrete_period - 1.0),
                  row.predicted_period, row.decay, row.predicted_decay, row.mean_iterations,
                  row.seconds_per_simulated_second);
      std::fflush(stdout);
      rows.push_back(row);
    }
    std::printf("| %s | %d | discrete mode | | %.4f | %+.2f%% | | | | | | |\n", type.c_str(), dofs,
                discrete_period, 100.0 * (discrete_period / analytic_period - 1.0));
  }
  return rows;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  const char* csv_path = nullptr;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--quick")) {
      quick = true;
    } else if (!std::strcmp(argv[a], "--csv") && a + 1 < argc) {
      csv_path = argv[++a];
    } else {
      std::fprintf(stderr, "usage: %s [--quick] [--csv FILE]\n", argv[0]);
      return 2;
    }
  }
  const std::vector<StaticRow> statics = cantilever(quick);
  const std::vector<DynamicRow> dynamics = vibration(quick);
  if (!csv_path) return 0;
  FILE* f = std::fopen(csv_path, "w");
  if (!f) {
    std::fprintf(stderr, "cannot write %s\n", csv_path);
    return 1;
  }
  std::fprintf(f,
               "part,mesh,n,scheme,elements,dofs,samples_per_element,tip_deflection,rel_error,assembly_ms,"
               "solve_ms,dt,period,analytic_period,discrete_period,predicted_period,decay_per_period,"
               "predicted_decay,mean_cg_iterations,seconds_per_simulated_second\n");
  for (const StaticRow& r : statics)
    std::fprintf(f, "static,%s,%d,%s,%d,%d,%.3f,%.9g,%.6g,%.4f,%.4f,,,,,,,,,\n", r.mesh.c_str(), r.n,
                 r.scheme.c_str(), r.elements, r.dofs, r.samples, r.tip, r.error, r.assembly_ms, r.solve_ms);
  for (const DynamicRow& r : dynamics)
    std::fprintf(f, "dynamic,%s,,implicit Euler,,%d,,,,,,%g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.2f,%.5g\n",
                 r.mesh.c_str(), r.dofs, r.dt, r.period, r.analytic_period, r.discrete_period,
                 r.predicted_period, r.decay, r.predicted_decay, r.mean_iterations,
                 r.seconds_per_simulated_second);
  std::fclose(f);
  std::printf("\nwrote %s\n", csv_path);
  return 0;
}
