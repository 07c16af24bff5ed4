// MLS projection benchmark. (a) throughput and error of rc::MlsSurface (per-point project() through
// projectBatch, and the batched projectInputs) against pcl::MovingLeastSquares on the same noisy sampled
// sphere/torus (same search radius), 1 and 2 threads; (b) the speed/accuracy trade-off of projectInputs over
// support radius, fit type and iteration cap (also written as CSV with --csv PATH). Times are medians of 5
// runs. Usage: bench_mls [--quick] [--no-sweep] [--csv PATH]
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "surface/analytic_shapes.h"
#include "surface/mls_surface.h"

#ifdef RC_HAVE_PCL
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/mls.h>
#endif

namespace {

using namespace rc;

constexpr int kRuns = 5;

double medianSeconds(const std::function<void()>& run) {
  std::vector<double> t;
  for (int i = 0; i < kRuns; ++i) {
    const auto a = std::chrono::steady_clock::now();
    run();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
  }
  std::sort(t.begin(), t.end());
  return t[kRuns / 2];
}

struct ErrorStats {
  double rms = 0, max = 0;
  size_t count = 0;
};

ErrorStats errorsOf(const AnalyticSurface& shape, const std::vector<Vec3>& pts) {
  ErrorStats e;
  for (const Vec3& p : pts) {
    const double d = std::abs(shape.signedDistance(p));
    e.rms += d * d, e.max = std::max(e.max, d), ++e.count;
  }
  e.rms = e.count ? std::sqrt(e.rms / static_cast<double>(e.count)) : 0;
  return e;
}

struct Variant {
  std::string name;
  MlsFit fit;
  bool normals;  // give the cloud's normals to the fit (APSS Hermite fit)
};

struct RunResult {
  double seconds;
  ErrorStats err;
  size_t invalid;
  double mean_iterations;
};

/// `inputs`: MlsSurface::projectInputs, else projectBatch of the input positions (project() per point).
RunResult runOurs(const SurfelCloud& input, const AnalyticSurface& shape, const Variant& v, double radius,
                  int max_iterations, bool require_convergence, int threads, double tolerance, bool inputs) {
  SurfelCloud cloud = input;
  if (!v.normals) cloud.normals.clear();
  MlsConfig config;
  config.fit = v.fit;
  config.weight = WeightFunction::wendland(radius);
  config.max_iterations = max_iterations;
  config.require_convergence = require_convergence;
  config.tolerance = tolerance;
  std::vector<MlsProjection> out;
  omp_set_num_threads(threads);
  const double s = medianSeconds([&] {
    MlsSurface surface(cloud, config);  // kd-tree / neighbour lists included, like PCL's process()
    if (inputs)
      surface.projectInputs(out);
    else
      surface.projectBatch(cloud.positions, out);
  });
  std::vector<Vec3> pts;
  size_t invalid = 0;
  double iterations = 0;
  for (const MlsProjection& p : out) {
    if (p.valid)
      pts.push_back(p.point), iterations += p.iterations;
    else
      ++invalid;
  }
  return {s, errorsOf(shape, pts), invalid, pts.empty() ? 0 : iterations / static_cast<double>(pts.size())};
}

#ifdef RC_HAVE_PCL
RunResult runPcl(const SurfelCloud& input, const AnalyticSurface& shape, double radius, int order,
                 int threads) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr in(new pcl::PointCloud<pcl::PointXYZ>);
  for (const Vec3& p : input.positions)
    in->push_back(
        pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())));
  pcl::PointCloud<pcl::PointNormal> out;
  const double s = medianSeconds([&] {
    pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointNormal> mls;
    mls.setInputCloud(in);
    mls.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(new pcl::search::KdTree<pcl::PointXYZ>));
    mls.setSearchRadius(radius);
    mls.setPolynomialOrder(order);
    mls.setComputeNormals(true);
    mls.setNumberOfThreads(threads);
    out.clear();
    mls.process(out);
  });
  std::vector<Vec3> pts;
  for (const auto& p : out.points) pts.emplace_back(p.x, p.y, p.z);
  return {s, errorsOf(shape, pts), input.size() - pts.size(), 1.0};
}
#endif

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, sweep = true;
  std::string csv_path;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick"))
      quick = true;
    else if (!std::strcmp(argv[i], "--no-sweep"))
      sweep = false;
    else if (!std::strcmp(argv[i], "--csv") && i + 1 < argc)
      csv_path = argv[++i];
    else {
      std::fprintf(stderr, "usage: %s [--quick] [--no-sweep] [--csv PATH]\n", argv[0]);
      return 2;
    }
  }
  const size_t n = quick ? 10000 : 50000;
  const AnalyticSphere sphere(Vec3::Zero(), 1.0);
  const AnalyticTorus torus(Vec3::Zero(), 1.0, 0.4);
  struct Shape {
    const char* name;
    const AnalyticSurface* surface;
  };
  const std::vector<Shape> shapes = {{"sphere", &sphere}, {"torus", &torus}};
  const std::vector<Variant> variants = {{"rc plane", MlsFit::kPlane, false},
                                         {"rc polynomial2", MlsFit::kPolynomial, false},
                                         {"rc apss points", MlsFit::kSphere, false},
                                         {"rc apss normals", MlsFit::kSphere, true}};

  std::printf(
      "# (a) MLS projection of every input point: %zu uniform random samples, noise sigma = 0.15 h,\n", n);
  std::printf(
      "#     search radius 3 h (rc: Wendland support; PCL: search radius, Gaussian sqr param r^2).\n");
  std::printf(
      "#     rc 'conv': iterated until a step moves < 1e-6 r (<= 20 iterations); 'it1': one iteration.\n");
  std::printf(
      "#     'project': projectBatch (kd-tree query per point); 'inputs': projectInputs (neighbour "
      "lists).\n");
  std::printf(
      "#     Times include the kd-tree / neighbour lists; error = distance to the analytic surface.\n");
#ifndef RC_HAVE_PCL
  std::printf("#     PCL not found at build time: no PCL rows.\n");
#endif
  std::printf("%-7s %-30s %3s %12s %11s %11s %8s %8s %8s %7s\n", "shape", "method", "thr", "points/s",
              "rms err", "max err", "invalid", "x PCL2", "x PCL1", "iters");
  for (const Shape& sh : shapes) {
    const double h = sh.surface->spacing(n);
    const SurfelCloud cloud = sh.surface->sample(n, {SamplingPattern::kUniformRandom, 0.15 * h, 17});
    const ErrorStats input = errorsOf(*sh.surface, cloud.positions);
    std::printf("%-7s %-30s %3s %12s %11.3e %11.3e\n", sh.name, "input (noisy)", "-", "-", input.rms,
                input.max);
    for (int threads : {1, 2}) {
      double pcl_rate[3] = {0, 0, 0};  // by order, measured in this run
#ifdef RC_HAVE_PCL
      RunResult pcl[3];
      for (int order : {2, 1}) {
        pcl[order] = runPcl(cloud, *sh.surface, 3 * h, order, threads);
        pcl_rate[order] = static_cast<double>(n) / pcl[order].seconds;
      }
#endif
      auto print = [&](const std::string& name, const RunResult& r, double iterations) {
        const double rate = static_cast<double>(n) / r.seconds;
        std::printf("%-7s %-30s %3d %12.0f %11.3e %11.3e %8zu %8.2f %8.2f %7.2f\n", sh.name, name.c_str(),
                    threads, rate, r.err.rms, r.err.max, r.invalid,
                    pcl_rate[2] > 0 ? rate / pcl_rate[2] : 0.0, pcl_rate[1] > 0 ? rate / pcl_rate[1] : 0.0,
                    iterations);
      };
#ifdef RC_HAVE_PCL
      print("pcl order 2", pcl[2], 1.0);
      print("pcl order 1", pcl[1], 1.0);
#endif
      for (const Variant& v : variants) {
        struct Mode {
          const char* suffix;
          bool inputs;
          int max_iterations;
        };
        for (const Mode& m :
             {Mode{"project conv", false, 20}, Mode{"inputs it1", true, 1}, Mode{"inputs conv", true, 20}}) {
          const RunResult r = runOurs(cloud, *sh.surface, v, 3 * h, m.max_iterations, m.max_iterations > 1,
                                      threads, 1e-6, m.inputs);
          print(v.name + " " + m.suffix, r, r.mean_iterations);
        }
      }
    }
  }

  if (!sweep) return 0;
  std::printf(
      "\n# (b) speed/accuracy trade-off of projectInputs on the noisy torus (%zu points, 2 threads): "
      "support\n",
      n);
  std::printf(
      "#     radius in units of the spacing h, fit, iteration cap (projections stopped by the cap count as\n"
      "#     valid).\n");
  std::printf("%-16s %6s %5s %10s %12s %11s %11s %8s %7s\n", "fit", "r/h", "iters", "time ms", "points/s",
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
  const double h = torus.spacing(n);
  const SurfelCloud cloud = torus.sample(n, {SamplingPattern::kUniformRandom, 0.15 * h, 17});
  for (const Variant& v : variants) {
    for (double factor : {1.5, 2.0, 3.0, 4.0}) {
      for (int cap : {1, 2, 5, 20}) {
        const RunResult r = runOurs(cloud, torus, v, factor * h, cap, false, 2, 1e-10, true);
        const double rate = static_cast<double>(n) / r.seconds;
        std::printf("%-16s %6.1f %5d %10.2f %12.0f %11.3e %11.3e %8zu %7.2f\n", v.name.c_str() + 3, factor,
                    cap, 1e3 * r.seconds, rate, r.err.rms, r.err.max, r.invalid, r.mean_iterations);
        if (csv)
          std::fprintf(csv, "%s,%.2f,%d,%.6e,%.6e,%.6e,%.6e,%zu,%.4f,%zu,2\n", v.name.c_str() + 3, factor,
                       cap, r.seconds, rate, r.err.rms, r.err.max, r.invalid, r.mean_iterations, n);
      }
    }
  }
  if (csv) std::fclose(csv);
  return 0;
}
