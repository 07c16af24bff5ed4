// MLS projection benchmark against pcl::MovingLeastSquares on equal inputs: both sides get the same noisy
// positions rounded to float and nothing else (rc estimates its normals from them, inside its timed run).
// (a) every input point projected, noisy sphere and torus, same search radius, 1 and 2 threads;
// (a2) equal error: for PCL order 2 at several radii, the fastest rc configuration with no larger RMS error;
// (b) speed/accuracy of projectInputs over support radius, fit, weight and iteration cap (--csv PATH);
// (c) real data from RC_SHARED_DATA_DIR: the PCL milk-carton scan (no ground truth: roughness and drift) and
//     the Stanford bunny with added noise (distance to the original mesh).
// Times are medians of several runs. Usage: bench_mls [--quick] [--no-sweep] [--no-real] [--csv PATH]
#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/surface/analytic_shapes.h"
#include "relaxed_connectivity/surface/mls_surface.h"
#include "relaxed_connectivity/surface/normal_estimation.h"
#include "relaxed_connectivity/surface/radius_estimation.h"

#ifdef RC_HAVE_PCL
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/mls.h>
#endif

namespace {

using namespace rc;

struct Timing {
  double median = 0, min = 0, max = 0;
  double spreadPercent() const { return median > 0 ? 100.0 * (max - min) / median : 0.0; }
};

Timing timeRuns(int runs, const std::function<void()>& run) {
  std::vector<double> t;
  for (int i = 0; i < runs; ++i) {
    const auto a = std::chrono::steady_clock::now();
    run();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
  }
  std::sort(t.begin(), t.end());
  return {t[t.size() / 2], t.front(), t.back()};
}

/// The projected points of one method: only the valid ones, with the index of their input point.
struct Output {
  std::vector<Vec3> points;
  std::vector<uint32_t> source;
  double mean_iterations = 1;
  Timing time;
};

struct Stats {
  double rms = 0, max = 0;
};

Stats statsOf(const std::vector<double>& d) {
  Stats s;
  for (double v : d) s.rms += v * v, s.max = std::max(s.max, v);
  s.rms = d.empty() ? 0 : std::sqrt(s.rms / static_cast<double>(d.size()));
  return s;
}

Stats analyticError(const AnalyticSurface& shape, const std::vector<Vec3>& pts) {
  std::vector<double> d;
  d.reserve(pts.size());
  for (const Vec3& p : pts) d.push_back(std::abs(shape.signedDistance(p)));
  return statsOf(d);
}

/// |out_i - in_source(i)|: how far the smoother moved the points.
Stats drift(const std::vector<Vec3>& input, const Output& out) {
  std::vector<double> d;
  for (size_t i = 0; i < out.points.size(); ++i) d.push_back((out.points[i] - input[out.source[i]]).norm());
  return statsOf(d);
}

/// Roughness: RMS over the points of the residual of each point to the least-squares quadratic height field
/// (unweighted, in the PCA frame) of its kRoughnessK nearest points of the same cloud, itself included.
constexpr size_t kRoughnessK = 20;
double roughness(const std::vector<Vec3>& pts) {
  if (pts.size() < kRoughnessK) return 0;
  KdTree tree(pts);
  std::vector<Neighbor> rows;
  tree.knnBatch(pts, kRoughnessK, rows);
  double sum = 0;
#pragma omp parallel for reduction(+ : sum)
  for (long i = 0; i < static_cast<long>(pts.size()); ++i) {
    Vec3 mean = Vec3::Zero();
    for (size_t j = 0; j < kRoughnessK; ++j) mean += pts[rows[i * kRoughnessK + j].index];
    mean /= static_cast<double>(kRoughnessK);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (size_t j = 0; j < kRoughnessK; ++j) {
      const Vec3 d = pts[rows[i * kRoughnessK + j].index] - mean;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Vec3 n = eig.eigenvectors().col(0), t1 = eig.eigenvectors().col(2), t2 = eig.eigenvectors().col(1);
    Eigen::Matrix<double, kRoughnessK, 6> A;
    Eigen::Matrix<double, kRoughnessK, 1> b;
    for (size_t j = 0; j < kRoughnessK; ++j) {
      const Vec3 d = pts[rows[i * kRoughnessK + j].index] - mean;
      const double u = d.dot(t1), v = d.dot(t2);
      A.row(j) << 1, u, v, u * u, u * v, v * v;
      b(j) = d.dot(n);
    }
    const Eigen::Matrix<double, 6, 1> c = A.colPivHouseholderQr().solve(b);
    const Vec3 d = pts[i] - mean;
    const double u = d.dot(t1), v = d.dot(t2);
    const double r = d.dot(n) - (c(0) + c(1) * u + c(2) * v + c(3) * u * u + c(4) * u * v + c(5) * v * v);
    sum += r * r;
  }
  return std::sqrt(sum / static_cast<double>(pts.size()));
}

/// Distance to a triangle mesh: the closest point over the triangles around the kMeshK nearest vertices
/// (exact whenever the closest triangle touches one of them, as for points near a fine mesh).
class MeshDistance {
 public:
  static constexpr size_t kMeshK = 16;
  explicit MeshDistance(const TriangleMesh& mesh)
      : mesh_(mesh), tree_(mesh.vertices.positions), first_(mesh.vertices.size() + 1, 0) {
    for (const Triangle& t : mesh.triangles)
      for (uint32_t v : t) ++first_[v + 1];
    for (size_t v = 0; v + 1 < first_.size(); ++v) first_[v + 1] += first_[v];
    faces_.resize(first_.back());
    std::vector<uint32_t> fill(first_.begin(), first_.end() - 1);
    for (uint32_t f = 0; f < mesh.triangles.size(); ++f)
      for (uint32_t v : mesh.triangles[f]) faces_[fill[v]++] = f;
  }

  Stats errors(const std::vector<Vec3>& pts) const {
    std::vector<double> d(pts.size());
#pragma omp parallel for
    for (long i = 0; i < static_cast<long>(pts.size()); ++i) d[i] = distance(pts[i]);
    return statsOf(d);
  }

  double distance(const Vec3& p) const {
    Neighbor nb[kMeshK];
    const size_t k = tree_.knn(p, kMeshK, nb);
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < k; ++j)
      for (uint32_t f = first_[nb[j].index]; f < first_[nb[j].index + 1]; ++f) {
        const Triangle& t = mesh_.triangles[faces_[f]];
        const auto& P = mesh_.vertices.positions;
        best = std::min(best, (p - closestOnTriangle(p, P[t[0]], P[t[1]], P[t[2]])).squaredNorm());
      }
    return std::sqrt(best);
  }

 private:
  /// Ericson, Real-Time Collision Detection 5.1.5.
  static Vec3 closestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
      return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
  }

  const TriangleMesh& mesh_;
  KdTree tree_;
  std::vector<uint32_t> first_, faces_;  // CSR: the triangles of each vertex
};

// ---------------------------------------------------------------------------------------------------------------
/// kEstimated: MlsConfig::estimate_normals (covariance normals over the MLS support, oriented per
/// neighbourhood); kKnn: estimateNormals (PCA of the 16 nearest, MST orientation) first, in the timed run.
enum class Normals { kNone, kEstimated, kKnn, kExact };

struct RcMethod {
  std::string name;
  MlsFit fit;
  Normals normals;
  bool gaussian;  // PCL's weight exp(-d^2/r^2) clipped at r; else Wendland C2 with support r
  int max_iterations = 1;
  bool inputs = true;         // projectInputs, else projectBatch (a kd-tree query per point)
  int refinement_passes = 0;  // MlsConfig::normal_refinement_passes (estimated normals only)
};

MlsConfig configOf(const RcMethod& m, double radius, double tolerance, bool require_convergence) {
  MlsConfig config;
  config.fit = m.fit;
  if (m.normals == Normals::kKnn && m.fit != MlsFit::kSphere)
    throw std::invalid_argument("bench_mls: kNN normals are only used by the sphere fit");
  config.weight =
      m.gaussian ? WeightFunction::clippedGaussian(radius, 1.0) : WeightFunction::wendland(radius);
  config.estimate_normals = m.normals == Normals::kEstimated;
  config.normal_refinement_passes = m.refinement_passes;
  config.max_iterations = m.max_iterations;
  config.require_convergence = require_convergence;
  config.tolerance = tolerance;
  return config;
}

/// `cloud` carries the exact normals (used only by Normals::kExact, the oracle).
/// Default: converged projections only (tolerance 1e-6 r); the sweep passes 1e-10 and accepts capped ones.
Output runRc(const SurfelCloud& cloud, const RcMethod& m, double radius, int threads, int runs,
             double tolerance = 1e-6, bool require_convergence = true) {
  SurfelCloud input = cloud;
  if (m.normals != Normals::kExact) input.normals.clear();
  const MlsConfig config = configOf(m, radius, tolerance, require_convergence && m.max_iterations > 1);
  std::vector<MlsProjection> out;
  omp_set_num_threads(threads);
  Output o;
  SurfelCloud with_knn;
  o.time = timeRuns(runs, [&] {
    if (m.normals == Normals::kKnn) {
      with_knn.positions = input.positions;
      NormalEstimationConfig normals;
      normals.k = 16;
      normals.write_curvature = false;
      estimateNormals(with_knn, normals);
    }
    const SurfelCloud& source = m.normals == Normals::kKnn ? with_knn : input;
    MlsSurface surface(source, config);  // kd-tree / neighbour lists / estimated normals included
    if (m.inputs)
      surface.projectInputs(out);
    else
      surface.projectBatch(source.positions, out);
  });
  double iterations = 0;
  for (size_t i = 0; i < out.size(); ++i)
    if (out[i].valid) {
      o.points.push_back(out[i].point), o.source.push_back(static_cast<uint32_t>(i));
      iterations += out[i].iterations;
    }
  o.mean_iterations = o.points.empty() ? 0 : iterations / static_cast<double>(o.points.size());
  return o;
}

#ifdef RC_HAVE_PCL
Output runPcl(const std::vector<Vec3>& positions, double radius, int order, int threads, int runs) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr in(new pcl::PointCloud<pcl::PointXYZ>);
  for (const Vec3& p : positions)
    in->push_back(
        pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())));
  pcl::PointCloud<pcl::PointNormal> out;
  pcl::PointIndicesPtr corresponding;
  Output o;
  o.time = timeRuns(runs, [&] {
    pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointNormal> mls;
    mls.setInputCloud(in);
    mls.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
    mls.setSearchRadius(radius);  // also sets the Gaussian parameter to radius^2
    mls.setPolynomialOrder(order);
    mls.setComputeNormals(true);
    mls.setNumberOfThreads(threads);
    out.clear();
    mls.process(out);
    corresponding = mls.getCorrespondingIndices();
  });
  for (size_t i = 0; i < out.size(); ++i) {
    o.points.emplace_back(out[i].x, out[i].y, out[i].z);
    o.source.push_back(static_cast<uint32_t>(corresponding->indices[i]));
  }
  return o;
}
#endif

/// The shared input: positions rounded to float (what PCL's PointXYZ holds), so both sides see the same data.
void roundToFloat(std::vector<Vec3>& pts) {
  for (Vec3& p : pts) p = p.cast<float>().cast<double>();
}

const RcMethod kApssEstG{"rc apss est-normals G", MlsFit::kSphere, Normals::kEstimated, true};
const RcMethod kApssEstW{"rc apss est-normals W", MlsFit::kSphere, Normals::kEstimated, false};
const RcMethod kApssRefG{"rc apss refined-normals G", MlsFit::kSphere, Normals::kEstimated, true, 1, true, 1};
const RcMethod kApssRefW{
    "rc apss refined-normals W", MlsFit::kSphere, Normals::kEstimated, false, 1, true, 1};
const RcMethod kPlaneG{"rc plane G", MlsFit::kPlane, Normals::kNone, true};
const RcMethod kPlaneW{"rc plane W", MlsFit::kPlane, Normals::kNone, false};
const RcMethod kPolyG{"rc polynomial2 G", MlsFit::kPolynomial, Normals::kNone, true};
const RcMethod kPolyW{"rc polynomial2 W", MlsFit::kPolynomial, Normals::kNone, false};
const RcMethod kApssPtsW{"rc apss points W", MlsFit::kSphere, Normals::kNone, false};
const RcMethod kApssKnnG{"rc apss kNN-PCA+MST normals G", MlsFit::kSphere, Normals::kKnn, true};
const RcMethod kApssExactW{"oracle: rc apss exact-normals W", MlsFit::kSphere, Normals::kExact, false};
const RcMethod kApssExactG{"oracle: rc apss exact-normals G", MlsFit::kSphere, Normals::kExact, true};

RcMethod variant(RcMethod m, const char* suffix, int max_iterations, bool inputs) {
  m.name += suffix;
  m.max_iterations = max_iterations;
  m.inputs = inputs;
  return m;
}

/// A benchmark input: float positions (plus the sampler's exact normals for the oracle rows), the spacing h,
/// and the error of a set of points (distance to the true surface) where there is a ground truth.
struct Dataset {
  std::string name;
  SurfelCloud cloud;
  double h = 0;
  std::function<Stats(const std::vector<Vec3>&)> error;  // empty: no ground truth
};

/// Mesh vertices (Gaussian noise of noise_factor h added, h measured before) as a data set; error = distance
/// to the mesh when it has triangles. False when the file is absent.
bool loadReal(const std::string& name, const std::string& file, double noise_factor, Dataset* set,
              std::vector<std::shared_ptr<MeshDistance>>* keep) {
  if (!std::filesystem::exists(file)) {
    std::printf("# %s skipped: %s not found\n", name.c_str(), file.c_str());
    return false;
  }
  ReadOptions options;
  options.keep_invalid = false;
  auto mesh = std::make_shared<TriangleMesh>(readMesh(file, options));
  set->name = name;
  set->cloud.positions = mesh->vertices.positions;
  set->h = sampleSpacing(set->cloud.positions);
  if (noise_factor > 0) {
    std::mt19937_64 rng(23);
    std::normal_distribution<double> gauss(0.0, noise_factor * set->h);
    for (Vec3& p : set->cloud.positions) p += Vec3(gauss(rng), gauss(rng), gauss(rng));
  }
  roundToFloat(set->cloud.positions);
  if (!mesh->triangles.empty()) {
    auto truth = std::make_shared<MeshDistance>(*mesh);
    keep->push_back(truth);
    set->error = [truth, mesh](const std::vector<Vec3>& pts) { return truth->errors(pts); };
  }
  std::printf("# %s: %s, %zu points%s, h = %.4g%s\n", name.c_str(), file.c_str(), set->cloud.size(),
              mesh->triangles.empty() ? "" : " (mesh vertices)", set->h,
              noise_factor > 0 ? " (measured before the noise)" : "");
  return true;
}

void printHeader(size_t n) {
  const char* lines[] = {
      "# Inputs: the same noisy positions, rounded to float, for PCL and rc; no normals for either.",
      "#   PCL fits its plane per point. rc 'est-normals' rows estimate a normal per sample from the",
      "#   positions (weighted covariance normal (3.5) over the same support, MlsConfig::estimate_normals);",
      "#   'kNN-PCA+MST' rows run estimateNormals (16 nearest, MST orientation) first. Both are in the time.",
      "#   'oracle' rows get the sampler's exact normals, which PCL never sees: a reference, not a peer.",
      "# Weights: 'G' = PCL's own weight exp(-d^2/r^2) clipped at the search radius r (rc: clipped",
      "#   Gaussian (3.11), sigma = r, clip 1); 'W' = Wendland C2 (3.12), support r (rc's default, "
      "narrower).",
      "# PCL: MovingLeastSquares<PointXYZ, PointNormal>, search radius r (Gaussian parameter r^2), order 2",
      "#   (default) or 1, SIMPLE projection, normals on; its kd-tree is built in process().",
      "# rc: MlsSurface; neighbour lists / kd-tree in the time. 'it1': one step from each input, as PCL;",
      "#   'conv': iterated until a step moves < 1e-6 r (<= 20 iterations); 'inputs' = projectInputs,",
      "#   'project' = projectBatch (a kd-tree query per point).",
      "# Times: median of the runs; spread = (max - min) / median; x PCL2 / x PCL1 = speed over PCL order 2",
      "#   / 1 measured in the same run at the same radius and thread count.",
  };
  for (const char* line : lines) std::printf("%s\n", line);
  std::printf(
      "# Synthetic: %zu uniform random samples of a sphere (R = 1) and a torus (major radius R = 1,\n", n);
  std::printf("#   minor radius r = 0.4), spacing h = sqrt(area / n), Gaussian noise sigma = 0.15 h per\n");
  std::printf("#   coordinate; error = distance to the analytic surface.\n");
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, sweep = true, real = true;
  std::string csv_path;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick"))
      quick = true;
    else if (!std::strcmp(argv[i], "--no-sweep"))
      sweep = false;
    else if (!std::strcmp(argv[i], "--no-real"))
      real = false;
    else if (!std::strcmp(argv[i], "--csv") && i + 1 < argc)
      csv_path = argv[++i];
    else {
      std::fprintf(stderr, "usage: %s [--quick] [--no-sweep] [--no-real] [--csv PATH]\n", argv[0]);
      return 2;
    }
  }
  const size_t n = quick ? 10000 : 50000;
  const int runs = quick ? 3 : 5, front_runs = 3;
  const AnalyticSphere sphere(Vec3::Zero(), 1.0);
  const AnalyticTorus torus(Vec3::Zero(), 1.0, 0.4);
  printHeader(n);
#ifndef RC_HAVE_PCL
  std::printf("# PCL not found at build time: no PCL rows.\n");
#endif
  std::vector<Dataset> synthetic;
  for (const AnalyticSurface* shape :
       {static_cast<const AnalyticSurface*>(&sphere), static_cast<const AnalyticSurface*>(&torus)}) {
    Dataset set;
    set.name = shape == &sphere ? "sphere" : "torus";
    set.h = shape->spacing(n);
    set.cloud = shape->sample(n, {SamplingPattern::kUniformRandom, 0.15 * set.h, 17});
    roundToFloat(set.cloud.positions);
    set.error = [shape](const std::vector<Vec3>& pts) { return analyticError(*shape, pts); };
    synthetic.push_back(set);
  }
  // Real data: h measured from the 6th-neighbour radius, sqrt(pi / 6) r6 (= sqrt(area / n) for uniform
  // samples).
  std::vector<Dataset> scans;   // without ground truth
  std::vector<Dataset> meshes;  // noisy mesh vertices, error against the mesh
  std::vector<std::shared_ptr<MeshDistance>> keep;
  if (real) {
    const std::string dir = RC_SHARED_DATA_DIR;
    Dataset set;
    if (loadReal("milk scan", dir + "/pcl/milk.pcd", 0.0, &set, &keep)) scans.push_back(set);
    for (double noise : {0.15, 0.5}) {
      char name[32];
      std::snprintf(name, sizeof(name), "bunny %.2gh", noise);
      if (loadReal(name, dir + "/bunny.ply", noise, &(set = Dataset()), &keep)) meshes.push_back(set);
    }
  }

  // (a) ----------------------------------------------------------------------------------------------------
  std::printf("\n# (a) every input point projected, search radius r = 3 h for both\n");
  std::printf("%-7s %-44s %3s %10s %6s %10s %10s %7s %7s %7s %6s\n", "shape", "method", "thr", "points/s",
              "spread", "rms err", "max err", "invalid", "x PCL2", "x PCL1", "iters");
  const std::vector<RcMethod> table_a = {
      variant(kApssEstG, " inputs it1", 1, true),     variant(kApssEstG, " inputs conv", 20, true),
      variant(kApssEstG, " project conv", 20, false), variant(kApssEstW, " inputs it1", 1, true),
      variant(kApssKnnG, " inputs it1", 1, true),     variant(kPlaneG, " inputs it1", 1, true),
      variant(kPlaneW, " inputs it1", 1, true),       variant(kPlaneW, " inputs conv", 20, true),
      variant(kPolyG, " inputs it1", 1, true),        variant(kPolyW, " inputs it1", 1, true),
      variant(kApssPtsW, " inputs it1", 1, true),     variant(kApssPtsW, " inputs conv", 20, true),
      variant(kApssExactW, " inputs it1", 1, true),   variant(kApssExactG, " inputs it1", 1, true)};
  for (const Dataset& set : synthetic) {
    const char* name = set.name.c_str();
    const Stats input = set.error(set.cloud.positions);
    std::printf("%-7s %-44s %3s %10s %6s %10.3e %10.3e\n", name, "input (noisy)", "-", "-", "-", input.rms,
                input.max);
    for (int threads : {1, 2}) {
      double pcl_rate[3] = {0, 0, 0};  // by order, measured in this run
      auto print = [&](const std::string& method, const Output& o) {
        const double rate = static_cast<double>(n) / o.time.median;
        const Stats e = set.error(o.points);
        std::printf("%-7s %-44s %3d %10.0f %5.0f%% %10.3e %10.3e %7zu %7.2f %7.2f %6.2f\n", name,
                    method.c_str(), threads, rate, o.time.spreadPercent(), e.rms, e.max, n - o.points.size(),
                    pcl_rate[2] > 0 ? rate / pcl_rate[2] : 0.0, pcl_rate[1] > 0 ? rate / pcl_rate[1] : 0.0,
                    o.mean_iterations);
      };
#ifdef RC_HAVE_PCL
      const Output pcl2 = runPcl(set.cloud.positions, 3 * set.h, 2, threads, runs);
      const Output pcl1 = runPcl(set.cloud.positions, 3 * set.h, 1, threads, runs);
      pcl_rate[2] = static_cast<double>(n) / pcl2.time.median;
      pcl_rate[1] = static_cast<double>(n) / pcl1.time.median;
      print("pcl order 2 (default)", pcl2);
      print("pcl order 1", pcl1);
#endif
      for (const RcMethod& m : table_a) print(m.name, runRc(set.cloud, m, 3 * set.h, threads, runs));
    }
  }

  // (a2) ---------------------------------------------------------------------------------------------------
#ifdef RC_HAVE_PCL
  struct Candidate {
    RcMethod method;
    double factor;
  };
  std::vector<Candidate> candidates;
  for (double f : {2.0, 2.5, 3.0, 3.5, 4.0}) candidates.push_back({kApssEstG, f});
  for (double f : {3.0, 4.0, 5.0}) candidates.push_back({kApssEstW, f});
  for (double f : {2.0, 2.5, 3.0}) candidates.push_back({kPlaneG, f});
  for (double f : {3.0, 4.0, 5.0}) candidates.push_back({kPlaneW, f});
  for (double f : {3.0, 4.0}) candidates.push_back({kPolyG, f});
  const std::vector<double> pcl_factors = {2.5, 3.0, 3.5, 4.0, 5.0};
  std::printf(
      "\n# (a2) equal error: PCL order 2 at radius r_pcl; the fastest of the rc candidates (one step from "
      "each\n"
      "#      input, normals estimated where used) whose RMS error is not larger. %d runs each. Candidates:\n"
      "#      apss est-normals G at 2-4 h, apss est-normals W at 3-5 h, plane G at 2-3 h, plane W at 3-5 h,\n"
      "#      polynomial2 G at 3-4 h.\n",
      front_runs);
  std::printf("%-12s %3s %6s %10s %10s | %-22s %5s %10s %10s %7s\n", "data", "thr", "r_pcl", "PCL pts/s",
              "PCL rms", "fastest rc at <= rms", "r_rc", "points/s", "rms err", "x PCL");
  std::vector<const Dataset*> with_truth;
  for (const Dataset& set : synthetic) with_truth.push_back(&set);
  for (const Dataset& set : meshes) with_truth.push_back(&set);
  for (const Dataset* set : with_truth) {
    const double m = static_cast<double>(set->cloud.size());
    for (int threads : {1, 2}) {
      std::vector<std::pair<double, double>> rc;  // (rate, rms) per candidate
      for (const Candidate& c : candidates) {
        const Output o = runRc(set->cloud, c.method, c.factor * set->h, threads, front_runs);
        rc.push_back({m / o.time.median, set->error(o.points).rms});
      }
      for (double f : pcl_factors) {
        const Output p = runPcl(set->cloud.positions, f * set->h, 2, threads, front_runs);
        const double rate = m / p.time.median, rms = set->error(p.points).rms;
        size_t best = candidates.size();
        for (size_t c = 0; c < candidates.size(); ++c)
          if (rc[c].second <= rms && (best == candidates.size() || rc[c].first > rc[best].first)) best = c;
        std::printf("%-12s %3d %6.1f %10.0f %10.3e | ", set->name.c_str(), threads, f, rate, rms);
        if (best == candidates.size())
          std::printf("%-22s\n", "(none)");
        else
          std::printf("%-22s %5.1f %10.0f %10.3e %7.2f\n", candidates[best].method.name.c_str() + 3,
                      candidates[best].factor, rc[best].first, rc[best].second, rc[best].first / rate);
      }
    }
  }
#endif

  // (c) ----------------------------------------------------------------------------------------------------
  if (!scans.empty() || !meshes.empty()) {
    std::printf(
        "\n# (c) real data, radius r = 3 h for both, the same float positions. mesh err = distance to the\n"
        "#     original triangle mesh (closest of the triangles around the %zu nearest vertices); roughness "
        "=\n"
        "#     RMS residual of each point to the least-squares quadratic height field (PCA frame) of its "
        "%zu\n"
        "#     nearest points of the same cloud; drift = distance from each output point to its input "
        "point.\n",
        MeshDistance::kMeshK, kRoughnessK);
    std::printf("%-12s %-30s %3s %10s %6s %10s %10s %10s %10s %10s %7s %7s\n", "data", "method", "thr",
                "points/s", "spread", "mesh rms", "mesh max", "roughness", "drift rms", "drift max",
                "invalid", "x PCL2");
    const std::vector<RcMethod> table_c = {kApssEstG, kApssEstW, kApssRefG, kApssRefW,
                                           kPlaneG,   kPlaneW,   kPolyG};
    std::vector<const Dataset*> sets;
    for (const Dataset& set : scans) sets.push_back(&set);
    for (const Dataset& set : meshes) sets.push_back(&set);
    for (const Dataset* set : sets) {
      const std::vector<Vec3>& input = set->cloud.positions;
      const size_t m = input.size();
      auto print = [&](const std::string& name, int threads, const Output* o, double pcl_rate) {
        const std::vector<Vec3>& pts = o ? o->points : input;
        char err[2][16] = {"-", "-"};
        if (set->error) {
          const Stats e = set->error(pts);
          std::snprintf(err[0], sizeof(err[0]), "%.3e", e.rms);
          std::snprintf(err[1], sizeof(err[1]), "%.3e", e.max);
        }
        const Stats d = o ? drift(input, *o) : Stats{};
        const double rate = o ? static_cast<double>(m) / o->time.median : 0.0;
        std::printf("%-12s %-30s %3d %10.0f %5.0f%% %10s %10s %10.3e %10.3e %10.3e %7zu %7.2f\n",
                    set->name.c_str(), name.c_str(), threads, rate, o ? o->time.spreadPercent() : 0.0, err[0],
                    err[1], roughness(pts), d.rms, d.max, o ? m - o->points.size() : 0,
                    pcl_rate > 0 ? rate / pcl_rate : 0.0);
      };
      print("input", 0, nullptr, 0);
      for (int threads : {1, 2}) {
        double pcl_rate = 0;
#ifdef RC_HAVE_PCL
        const Output pcl2 = runPcl(input, 3 * set->h, 2, threads, runs);
        pcl_rate = static_cast<double>(m) / pcl2.time.median;
        print("pcl order 2 (default)", threads, &pcl2, pcl_rate);
        const Output pcl1 = runPcl(input, 3 * set->h, 1, threads, runs);
        print("pcl order 1", threads, &pcl1, pcl_rate);
#endif
        for (const RcMethod& rm : table_c) {
          const Output o = runRc(set->cloud, rm, 3 * set->h, threads, runs);
          print(rm.name + " it1", threads, &o, pcl_rate);
        }
      }
    }
  }

  // (b) ----------------------------------------------------------------------------------------------------
  if (!sweep) return 0;
  std::printf(
      "\n# (b) speed/accuracy of projectInputs on the noisy torus (%zu points, 2 threads, float inputs, no\n"
      "#     normals given: 'est-normals' estimates them in the run): support radius in units of h, fit and\n"
      "#     weight, iteration cap (projections stopped by the cap count as valid). PCL order 2 rows for\n"
      "#     reference. %d runs each.\n",
      n, front_runs);
  std::printf("%-24s %6s %5s %10s %12s %10s %10s %8s %7s\n", "fit", "r/h", "iters", "time ms", "points/s",
              "rms err", "max err", "invalid", "mean it");
  FILE* csv = nullptr;
  if (!csv_path.empty()) {
    csv = std::fopen(csv_path.c_str(), "w");
    if (!csv) {
      std::fprintf(stderr, "bench_mls: cannot write --csv '%s'\n", csv_path.c_str());
      return 1;
    }
    std::fprintf(csv,
                 "fit,radius_factor,max_iterations,time_s,points_per_s,rms_error,max_error,invalid,"
                 "mean_iterations,points,threads\n");
  }
  const Dataset& set = synthetic[1];
  auto row = [&](const std::string& fit, double factor, int cap, const Output& o) {
    const Stats e = set.error(o.points);
    const double rate = static_cast<double>(n) / o.time.median;
    std::printf("%-24s %6.1f %5d %10.2f %12.0f %10.3e %10.3e %8zu %7.2f\n", fit.c_str(), factor, cap,
                1e3 * o.time.median, rate, e.rms, e.max, n - o.points.size(), o.mean_iterations);
    if (csv)
      std::fprintf(csv, "%s,%.2f,%d,%.6e,%.6e,%.6e,%.6e,%zu,%.4f,%zu,2\n", fit.c_str(), factor, cap,
                   o.time.median, rate, e.rms, e.max, n - o.points.size(), o.mean_iterations, n);
  };
#ifdef RC_HAVE_PCL
  for (double factor : {2.0, 3.0, 4.0, 5.0})
    row("pcl order 2", factor, 1, runPcl(set.cloud.positions, factor * set.h, 2, 2, front_runs));
#endif
  for (const RcMethod& m : {kPlaneW, kPlaneG, kPolyG, kApssEstW, kApssEstG}) {
    for (double factor : {2.0, 3.0, 4.0, 5.0}) {
      for (int cap : {1, 2, 5}) {
        RcMethod capped = m;
        capped.max_iterations = cap;
        row(m.name.substr(3), factor, cap,
            runRc(set.cloud, capped, factor * set.h, 2, front_runs, 1e-10, false));
      }
    }
  }
  if (csv) std::fclose(csv);
  return 0;
}
