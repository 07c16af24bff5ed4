// rc_surface: the point-sampled surface operators of thesis chapter 3 on files.
//   rc_surface info     IN
//   rc_surface estimate IN OUT            normals (+ consistent orientation) and covering radii
//   rc_surface smooth   IN OUT            project every point onto its MLS surface
//   rc_surface project  IN QUERIES OUT    project arbitrary query points onto the MLS surface of IN
//   rc_surface sample   IN OUT            resample the MLS surface with a given number of points
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/surface/mls_surface.h"
#include "relaxed_connectivity/surface/normal_estimation.h"
#include "relaxed_connectivity/surface/radius_estimation.h"

namespace {

using rc::SurfelCloud;
using rc::Vec3;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Mean distance to the k-th nearest neighbour over a subsample: the sampling spacing h.
double estimateSpacing(const SurfelCloud& cloud, int k = 6) {
  rc::KdTree tree(cloud.positions);
  std::vector<rc::Neighbor> nb(k + 1);
  const size_t step = std::max<size_t>(1, cloud.size() / 2000);
  double sum = 0;
  size_t count = 0;
  for (size_t i = 0; i < cloud.size(); i += step) {
    if (tree.knn(cloud.positions[i], k + 1, nb.data()) == size_t(k + 1)) {
      sum += std::sqrt(nb[k].sq_dist);
      ++count;
    }
  }
  return count ? sum / count : 0.0;
}

/// A progress line on stderr for long inputs ("\r" updates).
class Progress {
 public:
  Progress(const char* what, size_t total) : what_(what), total_(total), start_(Clock::now()) {}
  void update(size_t done) const {
    if (total_ < 20000) return;
    std::fprintf(stderr, "\r%s: %3d%% (%zu/%zu) %.1f s", what_, int(100.0 * done / total_), done, total_,
                 secondsSince(start_));
    if (done == total_) std::fprintf(stderr, "\n");
  }

 private:
  const char* what_;
  size_t total_;
  Clock::time_point start_;
};

/// Projects `xs` in chunks, reporting progress; returns the number of invalid projections.
size_t projectWithProgress(const rc::MlsSurface& mls, const std::vector<Vec3>& xs,
                           std::vector<rc::MlsProjection>& out) {
  out.resize(xs.size());
  const Progress progress("project", xs.size());
  const size_t chunk = 20000;
  std::vector<Vec3> in;
  std::vector<rc::MlsProjection> part;
  size_t invalid = 0;
  for (size_t b = 0; b < xs.size(); b += chunk) {
    const size_t e = std::min(xs.size(), b + chunk);
    in.assign(xs.begin() + b, xs.begin() + e);
    mls.projectBatch(in, part);
    for (size_t i = b; i < e; ++i) {
      out[i] = part[i - b];
      invalid += !out[i].valid;
    }
    progress.update(e);
  }
  return invalid;
}

struct MlsOptions {
  std::string fit = "plane";
  std::string weight = "wendland";
  double support = 0;  // 0: 3 x spacing (Gaussians: sigma = 1 x spacing)
  double clip = 3.0;
  int degree = 2;
  int iterations = 20;
  bool hermite = false;
  bool strict = false;
  std::string normals = "auto";

  void add(CLI::App* app) {
    app->add_option("--fit", fit, "MLS fit: plane | polynomial | sphere")->capture_default_str();
    app->add_option("--weight", weight, "weight: wendland | gaussian | clipped_gaussian")
        ->capture_default_str();
    app->add_option("--support", support,
                    "support radius (Gaussians: sigma); 0 = 3 x sample spacing (Gaussians: 1 x spacing)");
    app->add_option("--clip", clip, "clipped_gaussian: cut-off in units of sigma (PCL's weight: 1.414)")
        ->capture_default_str();
    app->add_option("--degree", degree, "polynomial degree for --fit polynomial")->capture_default_str();
    app->add_option("--iterations", iterations, "projection iterations")->capture_default_str();
    app->add_flag("--hermite", hermite, "normals from input normals (3.8)");
    app->add_flag("--strict", strict, "drop points whose projection did not converge within --iterations");
    app->add_option("--normals", normals,
                    "sample normals of the sphere fit and --hermite: auto (the file's, else refined), input, "
                    "estimated (plane fits over the support), refined (+ one pass of sphere fits), none "
                    "(points-only sphere fit)")
        ->check(CLI::IsMember({"auto", "input", "estimated", "refined", "none"}))
        ->capture_default_str();
  }
  /// The normals the surface uses: "none" drops the file's (the points-only sphere fit).
  bool dropsNormals() const { return normals == "none"; }
  rc::MlsConfig config(const SurfelCloud& cloud) const {
    rc::MlsConfig c;
    c.fit = rc::parseMlsFit(fit);
    const rc::WeightKind kind = rc::parseWeightKind(weight);
    const double r =
        support > 0 ? support : (kind == rc::WeightKind::kWendlandC2 ? 3.0 : 1.0) * estimateSpacing(cloud);
    if (!(clip > 0) || !std::isfinite(clip)) throw std::invalid_argument("--clip must be a positive number");
    c.weight = rc::WeightFunction{kind, r, kind == rc::WeightKind::kClippedGaussian ? clip : 0.0};
    c.polynomial_degree = degree;
    c.max_iterations = iterations;
    c.require_convergence = strict;
    c.normal_source = hermite ? rc::MlsNormalSource::kHermite : rc::MlsNormalSource::kCovariance;
    std::string source = normals;
    if (source == "input" && !cloud.hasNormals())
      throw std::invalid_argument("--normals input: the file has no normals");
    if (source == "auto") source = cloud.hasNormals() ? "input" : "refined";
    c.estimate_normals = source == "estimated" || source == "refined";
    c.normal_refinement_passes = source == "refined" ? 1 : 0;
    const bool uses_normals = c.fit == rc::MlsFit::kSphere || hermite;
    std::fprintf(stderr, "MLS: fit %s, weight %s, %s %.6g, up to %d iterations%s%s\n", fit.c_str(),
                 weight.c_str(), kind == rc::WeightKind::kWendlandC2 ? "support" : "sigma", r, iterations,
                 uses_normals ? ", normals: " : "", uses_normals ? source.c_str() : "");
    return c;
  }
};

SurfelCloud load(const std::string& path) {
  const auto t0 = Clock::now();
  SurfelCloud c = rc::readCloud(path);
  const size_t dropped = c.removeNonFinite();
  std::fprintf(stderr, "read %s: %zu points, %zu non-finite dropped (%.2f s)\n", path.c_str(), c.size(),
               dropped, secondsSince(t0));
  if (c.empty()) throw std::runtime_error(path + ": no finite points");
  return c;
}

void save(const std::string& path, const SurfelCloud& c) {
  rc::writeCloud(path, c);
  std::fprintf(stderr, "wrote %s: %zu surfels\n", path.c_str(), c.size());
}

void printInfo(const SurfelCloud& c) {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  c.bounds(&lo, &hi);
  std::printf("points     %zu%s\n", c.size(), c.isOrganized() ? " (organised)" : "");
  std::printf("bounds     [%g %g %g] - [%g %g %g]\n", lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z());
  std::printf("channels   %s%s%s%s%s%s\n", c.hasNormals() ? "normals " : "", c.hasRadii() ? "radii " : "",
              c.hasAxes() ? "axes " : "", c.hasColors() ? "colors " : "",
              c.hasConfidence() ? "confidence " : "", c.hasCurvature() ? "curvature" : "");
  for (const auto& a : c.attributes.columns())
    std::printf("attribute  %s (%s x %u)\n", a.name.c_str(), rc::scalarName(a.type), a.count);
  SurfelCloud finite = c;
  finite.removeNonFinite();
  if (finite.size() > 1)
    std::printf("spacing    %g (mean distance to the 6th neighbour)\n", estimateSpacing(finite));
}

/// Runs smooth / project / sample: the MLS projection of a set of points. Without `xs`, the cloud's own
/// points are projected (smooth), through the batched neighbour-list path.
SurfelCloud runProjection(const SurfelCloud& c, const MlsOptions& opts, const std::vector<Vec3>* xs_or_null) {
  SurfelCloud positions_only;
  if (opts.dropsNormals() && c.hasNormals()) {
    positions_only.positions = c.positions;
    positions_only.frame_id = c.frame_id;
  }
  const SurfelCloud& source = positions_only.empty() ? c : positions_only;
  const rc::MlsSurface surface(source, opts.config(source));
  const bool own_points = xs_or_null == nullptr;
  const std::vector<Vec3>& xs = own_points ? c.positions : *xs_or_null;
  std::vector<rc::MlsProjection> proj;
  const auto t0 = Clock::now();
  size_t invalid = 0;
  if (own_points) {
    surface.projectInputs(proj);
    for (const auto& p : proj) invalid += !p.valid;
  } else {
    invalid = projectWithProgress(surface, xs, proj);
  }
  const double s = secondsSince(t0);
  std::fprintf(stderr, "projected %zu points in %.2f s (%.0f points/s), %zu without a valid projection\n",
               xs.size(), s, xs.size() / std::max(s, 1e-9), invalid);
  SurfelCloud result;
  if (own_points) result = c;
  result.positions.resize(xs.size());
  result.normals.resize(xs.size());
  std::vector<size_t> keep;
  for (size_t i = 0; i < xs.size(); ++i) {
    if (!proj[i].valid) continue;
    result.positions[i] = proj[i].point;
    result.normals[i] = proj[i].normal;
    keep.push_back(i);
  }
  if (keep.size() != xs.size()) result.select(keep);
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rc_surface: MLS surface operators (thesis ch. 3) on point files (ply, pcd, off, obj, xyz)"};
  app.require_subcommand(1);
  std::string in, out, queries;

  auto* info = app.add_subcommand("info", "print what a point file holds");
  info->add_option("input", in, "point file")->required();

  auto* estimate = app.add_subcommand("estimate", "estimate oriented normals and covering radii");
  rc::NormalEstimationConfig ncfg;
  rc::RadiusEstimationConfig rcfg;
  std::vector<double> viewpoint;
  estimate->add_option("input", in)->required();
  estimate->add_option("output", out)->required();
  estimate->add_option("--k", ncfg.k, "neighbours per normal fit")->capture_default_str();
  estimate->add_option("--viewpoint", viewpoint, "orient normals towards x y z (else MST propagation)")
      ->expected(3);
  estimate->add_option("--radius-k", rcfg.k, "neighbours for the radius rule")->capture_default_str();
  estimate->add_option("--radius-scale", rcfg.scale, "radius multiplier (>= 1 keeps coverage)")
      ->capture_default_str();

  MlsOptions mls_opts;
  auto* smooth = app.add_subcommand("smooth", "project every point onto the MLS surface");
  smooth->add_option("input", in)->required();
  smooth->add_option("output", out)->required();
  mls_opts.add(smooth);

  auto* project =
      app.add_subcommand("project", "project the points of QUERIES onto the MLS surface of INPUT");
  project->add_option("input", in)->required();
  project->add_option("queries", queries)->required();
  project->add_option("output", out)->required();
  mls_opts.add(project);

  size_t count = 0;
  unsigned seed = 1;
  auto* sample = app.add_subcommand("sample", "resample the MLS surface with COUNT points");
  sample->add_option("input", in)->required();
  sample->add_option("output", out)->required();
  sample->add_option("--count", count, "number of output points (default: as many as the input)");
  sample->add_option("--seed", seed, "random seed")->capture_default_str();
  mls_opts.add(sample);

  CLI11_PARSE(app, argc, argv);
  try {
    if (*info) {
      printInfo(rc::readCloud(in));
    } else if (*estimate) {
      SurfelCloud c = load(in);
      if (!viewpoint.empty()) ncfg.viewpoint = Vec3(viewpoint[0], viewpoint[1], viewpoint[2]);
      const auto t0 = Clock::now();
      rc::estimateNormals(c, ncfg);
      rc::estimateRadii(c, rcfg);
      std::fprintf(stderr, "normals + radii: %.2f s\n", secondsSince(t0));
      save(out, c);
    } else if (*smooth) {
      const SurfelCloud c = load(in);
      save(out, runProjection(c, mls_opts, nullptr));
    } else if (*project) {
      const SurfelCloud c = load(in);
      const std::vector<Vec3> xs = load(queries).positions;
      save(out, runProjection(c, mls_opts, &xs));
    } else if (*sample) {
      // Jitter randomly chosen input points by about the spacing, then project them onto the surface.
      const SurfelCloud c = load(in);
      const double h = estimateSpacing(c);
      std::mt19937 rng(seed);
      std::uniform_int_distribution<size_t> pick(0, c.size() - 1);
      std::normal_distribution<double> jitter(0.0, 0.5 * h);
      std::vector<Vec3> xs(count ? count : c.size());
      for (auto& x : xs) x = c.positions[pick(rng)] + Vec3(jitter(rng), jitter(rng), jitter(rng));
      save(out, runProjection(c, mls_opts, &xs));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rc_surface: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
