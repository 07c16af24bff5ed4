// Brush benchmark (thesis 5.4): one main-loop event (skeleton substeps + collision of the spring end points
// with the object + skinning) on objects of 300k and 750k surfels, the kd-tree build, the collision query
// against PCL's KdTreeFLANN, and the speed/accuracy curve of collision passes per event. Single-threaded (the
// brush runs on one core). Prints tables; `--quick` uses fewer events.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/paint/brush.h"
#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/surface/analytic_shapes.h"

#ifdef RC_HAVE_PCL
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>
#endif

namespace {

using rc::Vec3;
using Clock = std::chrono::steady_clock;

constexpr double kRadius = 0.1;               // object: a sphere of 10 cm radius
constexpr double kEvent = 1.0 / 30;           // the thesis' main-loop period
constexpr double kSpeed = 0.1;                // stroke speed [m/s]
constexpr double kLean = 0.5235987755982988;  // 30 degrees

/// The object: a Fibonacci-sampled sphere with exact normals and radii covering the sampling.
rc::SurfelCloud sphere(size_t count) {
  rc::SurfelCloud c = rc::AnalyticSphere(Vec3::Zero(), kRadius).sample(count);
  c.radii.assign(count, kRadius * std::sqrt(4.0 / count));
  return c;
}

/// Stylus pose at event e of a stroke along a great circle over the top of the sphere, the ferrule
/// `press` closer than the bristle length to the surface (the bristles bend against it). The stylus leans
/// 30 degrees against the motion so that the bristles trail (a stylus along the normal may bend them
/// either way, and integrators would pick different ways).
Eigen::Isometry3d strokePose(int e, double bristle_length, double press) {
  const double angle = kSpeed * kEvent * e / kRadius - 0.5;
  const Vec3 up(std::sin(angle), 0, std::cos(angle)), ahead(std::cos(angle), 0, -std::sin(angle));
  const Vec3 bristles = -std::cos(kLean) * up - std::sin(kLean) * ahead;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond::FromTwoVectors(Vec3(0, 0, -1), bristles).toRotationMatrix();
  t.translation() = (kRadius + bristle_length - press) * up;
  return t;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(p * v.size()))];
}

/// Mean and largest distance between the active masses of two runs of the same stroke.
std::pair<double, double> deviation(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double sum = 0, worst = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double d = (a[i] - b[i]).norm();
    sum += d, worst = std::max(worst, d);
  }
  return {sum / double(a.size()), worst};
}

rc::BrushPreset implicitEuler(rc::BrushPreset p, int steps_per_event) {
  p.integrator = rc::BrushIntegrator::kImplicitEuler;
  p.time_step = kEvent / steps_per_event;
  return p;
}

double skin_checksum = 0;  // keeps the skin reads from being optimised away

struct EventTimes {
  std::vector<double> us;
  std::vector<Vec3> actives;  // active-mass positions after every timed event
  double queries = 0, deepest_mean = 0, deepest_max = 0;
};

/// Runs `events` events of the stroke (after 30 warm-up events, so that the bristles are bent and touching);
/// with `read_skin` the skin is read (and so skinned) after every event, inside the timing.
EventTimes runStroke(const rc::BrushPreset& preset, const rc::BrushOptions& options,
                     const rc::PaintSurface* surface, int events, bool read_skin = true) {
  rc::Brush brush(preset, options);
  const double press = 0.006;
  brush.reset(strokePose(0, preset.bristle_length, -0.002));
  EventTimes out;
  for (int e = 1; e <= 30 + events; ++e) {
    const auto t0 = Clock::now();
    const rc::BrushEventStats s = brush.advance(kEvent, strokePose(e, preset.bristle_length, press), surface);
    if (read_skin) skin_checksum += brush.skin().positions()[0].x();
    const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    if (e <= 30) continue;
    out.us.push_back(us);
    for (int a = 0; a < brush.skeleton().activeCount(); ++a)
      out.actives.push_back(brush.skeleton().positions()[brush.skeleton().handleCount() + a]);
    out.queries += s.queries;
    out.deepest_mean += s.deepest;
    out.deepest_max = std::max(out.deepest_max, s.deepest);
  }
  out.queries /= events;
  out.deepest_mean /= events;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int events = quick ? 100 : 600;
  const std::string brushes = std::string(RC_SOURCE_DIR) + "/config/paint/brushes/";
  const rc::BrushPreset round = rc::readBrushPreset(brushes + "round.yaml");
  const rc::BrushPreset flat = rc::readBrushPreset(brushes + "flat.yaml");

  std::printf(
      "Brush per main-loop event (1/30 s of device motion at %.2f m/s over a %.0f cm sphere), one core;\n"
      "median and p99 over %d events after 30 warm-up events. Thesis (Pentium 4): below 100 us.\n\n",
      kSpeed, 100 * kRadius, events);
  std::printf("%-9s %-6s %-9s %-26s %10s %10s %9s %9s\n", "surfels", "brush", "skeleton", "work", "median us",
              "p99 us", "queries", "substeps");
  for (size_t count : {size_t(300000), size_t(750000)}) {
    std::vector<double> build;
    std::unique_ptr<rc::PaintSurface> surface;
    for (int r = 0; r < 3; ++r) {
      rc::SurfelCloud cloud = sphere(count);
      const auto t0 = Clock::now();
      surface = std::make_unique<rc::PaintSurface>(std::move(cloud));
      build.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
    for (const rc::BrushPreset* base : {&round, &flat}) {
      const struct {
        const char* name;
        const rc::PaintSurface* surface;
        bool read_skin;
      } rows[] = {{"skeleton (no surface)", nullptr, false},
                  {"skeleton + collision", surface.get(), false},
                  {"skeleton + collision + skin", surface.get(), true}};
      for (const rc::BrushPreset& p : {*base, implicitEuler(*base, 1)}) {
        for (const auto& row : rows) {
          const EventTimes t = runStroke(p, rc::BrushOptions(), row.surface, events, row.read_skin);
          std::printf("%-9zu %-6s %-9s %-26s %10.1f %10.1f %9.1f %9d\n", count, p.name.c_str(),
                      p.integrator == rc::BrushIntegrator::kVerlet ? "Verlet" : "implicit", row.name,
                      median(t.us), percentile(t.us, 0.99), t.queries,
                      int(std::ceil(kEvent / p.time_step - 1e-9)));
        }
      }
    }
    std::printf("%-9zu PaintSurface build (kd-tree + collision grid): %.0f ms (median of 3)\n\n", count,
                median(build));

    // The collision query (10 nearest originals) against PCL's KdTreeFLANN on the same points and queries.
    std::vector<Vec3> queries;
    for (int e = 0; e < 2000; ++e) {
      const Eigen::Isometry3d pose = strokePose(e % 300, round.bristle_length, 0.006);
      queries.push_back(pose * Vec3(0.001 * (e % 7), 0.0005 * (e % 5), -0.01 * (e % 3)));
    }
    std::vector<double> ours, tree_times, pcl_times;
    rc::Neighbor found[10];
    double checksum = 0;
    const rc::KdTree tree(surface->originals().positions);
    for (int r = 0; r < 5; ++r) {
      auto t0 = Clock::now();
      for (const Vec3& q : queries) surface->nearestOriginals(q, 10, found), checksum += found[9].sq_dist;
      ours.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count() / queries.size());
      t0 = Clock::now();
      for (const Vec3& q : queries) tree.knn(q, 10, found), checksum -= found[9].sq_dist;
      tree_times.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count() /
                           queries.size());
    }
#ifdef RC_HAVE_PCL
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    for (const Vec3& x : surface->originals().positions) cloud->push_back(pcl::PointXYZ(x.x(), x.y(), x.z()));
    pcl::KdTreeFLANN<pcl::PointXYZ> pcl_tree;
    pcl_tree.setInputCloud(cloud);
    std::vector<int> idx(10);
    std::vector<float> d2(10);
    for (int r = 0; r < 5; ++r) {
      const auto t0 = Clock::now();
      for (const Vec3& q : queries)
        pcl_tree.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 10, idx, d2), checksum += d2[9];
      pcl_times.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count() /
                          queries.size());
    }
    std::printf(
        "%-9zu 10-nearest query: PaintSurface (grid, kd-tree where it cannot certify) %.2f us, rc::KdTree "
        "%.2f us, PCL KdTreeFLANN %.2f us (ratio to PCL %.2f)  [checksum %.3g]\n\n",
        count, median(ours), median(tree_times), median(pcl_times), median(pcl_times) / median(ours),
        checksum);
#else
    std::printf(
        "%-9zu 10-nearest query: PaintSurface %.2f us, rc::KdTree %.2f us (PCL not found: no peer)  "
        "[checksum %.3g]\n\n",
        count, median(ours), median(tree_times), checksum);
#endif
  }

  // Speed against accuracy: exact collision passes per event, with and without the tangent-plane proxy
  // between them. Without it, active masses sink into the object between passes (they all end on the surface
  // after the last pass).
  std::printf(
      "Collision per event (750k surfels, skeleton + collision + skin): time against how deep active\n"
      "masses sink before an exact pass projects them (mean over events of the deepest, and the "
      "maximum).\n\n");
  std::printf("%-6s %7s %6s %10s %10s %8s %14s %14s\n", "brush", "passes", "proxy", "median us", "p99 us",
              "queries", "mean deepest", "max deepest");
  const rc::PaintSurface big(sphere(750000));
  for (const rc::BrushPreset* p : {&round, &flat}) {
    const int substeps = int(std::ceil(kEvent / p->time_step - 1e-9));
    for (bool proxy : {true, false}) {
      for (int passes : {1, 4, substeps}) {
        rc::BrushOptions o;
        o.collision_passes = passes;
        o.plane_proxy = proxy;
        const EventTimes t = runStroke(*p, o, &big, events);
        std::printf("%-6s %7d %6s %10.1f %10.1f %8.1f %11.4f mm %11.4f mm\n", p->name.c_str(), passes,
                    proxy ? "on" : "off", median(t.us), percentile(t.us, 0.99), t.queries,
                    1e3 * t.deepest_mean, 1e3 * t.deepest_max);
      }
    }
  }
  // Speed against accuracy: the integrator. Implicit Euler steps per event against the Verlet brush of the
  // preset on the same stroke (both with the default collision options, skin not read).
  std::printf(
      "\nIntegrator per event (750k surfels, skeleton + collision): time against the distance of the active\n"
      "masses from the Verlet brush's on the same stroke (mean over events and masses, and the "
      "maximum).\n\n");
  std::printf("%-6s %-10s %6s %10s %10s %8s %12s %12s\n", "brush", "integrator", "steps", "median us",
              "p99 us", "queries", "mean off", "max off");
  for (const rc::BrushPreset* p : {&round, &flat}) {
    const EventTimes reference = runStroke(*p, rc::BrushOptions(), &big, events, false);
    std::printf("%-6s %-10s %6d %10.1f %10.1f %8.1f %9.3f mm %9.3f mm\n", p->name.c_str(), "Verlet",
                int(std::ceil(kEvent / p->time_step - 1e-9)), median(reference.us),
                percentile(reference.us, 0.99), reference.queries, 0.0, 0.0);
    for (int steps : {1, 2, 4, 8, 16}) {
      const EventTimes t = runStroke(implicitEuler(*p, steps), rc::BrushOptions(), &big, events, false);
      const auto [mean_off, max_off] = deviation(t.actives, reference.actives);
      std::printf("%-6s %-10s %6d %10.1f %10.1f %8.1f %9.3f mm %9.3f mm\n", p->name.c_str(), "implicit",
                  steps, median(t.us), percentile(t.us, 0.99), t.queries, 1e3 * mean_off, 1e3 * max_off);
    }
  }
  std::printf(
      "\nLeft out: painting (paint transfer, resampling) and rendering, which the next issues add to an "
      "event;\n"
      "the haptic force loop (bench_haptic_loop).\n");
  std::printf("[skin checksum %.3g]\n", skin_checksum);
  return 0;
}
