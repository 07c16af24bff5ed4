#include "relaxed_connectivity/sph/sph_dam_break_surge.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace rc {

const std::vector<SphSurgeSample>& martinMoyceSurge() {
  static const std::vector<SphSurgeSample> data = {
      {0.0, 1.0},   {0.41, 1.11}, {0.84, 1.22}, {1.19, 1.44}, {1.43, 1.67}, {1.63, 1.89}, {1.83, 2.11},
      {1.98, 2.33}, {2.20, 2.56}, {2.32, 2.78}, {2.51, 3.00}, {2.65, 3.22}, {2.83, 3.44}, {2.98, 3.67}};
  return data;
}

const std::vector<SphSurgeSample>& koshizukaOkaSurge() {
  static const std::vector<SphSurgeSample> data = {{0.0, 1.000},   {0.381, 1.111}, {0.769, 1.252},
                                                   {1.153, 1.505}, {1.537, 1.892}, {1.935, 2.241},
                                                   {2.323, 2.615}, {2.719, 3.003}, {3.096, 3.624}};
  return data;
}

SphDamBreak2D martinMoyceDamBreak(int particles_across, double smoothing_ratio) {
  if (particles_across < 1) throw std::invalid_argument("martinMoyceDamBreak: particles_across must be >= 1");
  SphDamBreak2D scene;
  scene.column_width = 0.1;
  scene.column_height = 0.2;
  scene.tank_width = 0.5;
  scene.tank_height = 0.25;
  scene.dx = scene.column_width / particles_across;
  scene.smoothing_ratio = smoothing_ratio;
  return scene;
}

SphFluidConfig martinMoyceDamBreakConfig(const SphDamBreak2D& scene) {
  SphFluidConfig c;
  // K = rho_0 c^2 with c = 10 sqrt(2 g H), rounded to 1 Pa as config/sph/dam_break_2d.yaml writes it
  c.stiffness = std::round(100.0 * 2.0 * 9.81 * scene.column_height * c.rest_density);
  c.viscosity = 0.5;
  c.xsph = 0.1;
  c.negative_pressure_scale = 0.01;
  return c;
}

double interpolateSurge(const std::vector<SphSurgeSample>& reference, double t_star) {
  if (reference.empty()) throw std::invalid_argument("interpolateSurge: the reference is empty");
  if (t_star <= reference.front().t_star) return reference.front().x_over_l;
  for (size_t k = 1; k < reference.size(); ++k)
    if (t_star <= reference[k].t_star) {
      const SphSurgeSample &a = reference[k - 1], &b = reference[k];
      return a.x_over_l + (b.x_over_l - a.x_over_l) * (t_star - a.t_star) / (b.t_star - a.t_star);
    }
  return reference.back().x_over_l;
}

double surgeFront(const SphParticles& particles, const SphDamBreak2D& scene, double smoothing_length) {
  double front = 0.0;
  for (size_t i = 0; i < particles.size(); ++i)
    if (particles.kinds[i] == SphParticleKind::kFluid && particles.positions[i].y() < smoothing_length)
      front = std::max(front, particles.positions[i].x() + 0.5 * scene.dx);
  return front / scene.column_width;
}

SphSurgeRun runDamBreakSurge(const SphDamBreak2D& scene, SphFluidConfig config,
                             const std::vector<SphSurgeSample>& reference, double t_star_end) {
  if (reference.empty()) throw std::invalid_argument("runDamBreakSurge: the reference is empty");
  for (size_t k = 1; k < reference.size(); ++k)
    if (!(reference[k].t_star > reference[k - 1].t_star))
      throw std::invalid_argument("runDamBreakSurge: reference times must increase");
  SphParticles particles = makeDamBreak2D(scene, config);  // sets dimension and h of config
  SphFluidSolver solver(config, std::move(particles));
  const double g = config.gravity.norm();
  if (!(g > 0.0)) throw std::invalid_argument("runDamBreakSurge: gravity must be non-zero");
  const double time_scale = std::sqrt(scene.column_width / (2.0 * g));  // t = t* time_scale
  SphSurgeRun run;
  run.fluid_particles = solver.particles().count(SphParticleKind::kFluid);
  for (const SphSurgeSample& ref : reference) {
    if (ref.t_star > t_star_end) break;
    const double duration = ref.t_star * time_scale - solver.time();
    if (duration > 0.0) {
      const auto t0 = std::chrono::steady_clock::now();
      solver.advance(duration);
      run.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    const double x = surgeFront(solver.particles(), scene, config.smoothing_length);
    run.front.push_back({ref.t_star, x});
    run.max_abs_error = std::max(run.max_abs_error, std::abs(x - ref.x_over_l));
    run.max_rel_error = std::max(run.max_rel_error, std::abs(x - ref.x_over_l) / ref.x_over_l);
  }
  run.steps = solver.stepCount();
  return run;
}

}  // namespace rc
