// Fluid sources (emitters) and static boundary cylinders: the disc lattice, the emission schedule (mass rate
// rho_0 A v independent of the step, exact offsets, velocity, temperature, cap, occupied points), the scene
// keys `sources` and `boundary.cylinders` with their errors, and the thesis' Fig. 8.5 scene in 3D
// (config/sph/fig8_5_freezing_rod.yaml): slime poured onto a cooled rod freezes onto it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "relaxed_connectivity/sph/sph_fluid_source.h"
#include "relaxed_connectivity/sph/sph_scene_builders.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"
#include "scene_file_test_support.h"

namespace rc {
namespace {

double fluidMass(const SphParticles& p) {
  double m = 0.0;
  for (size_t i = 0; i < p.size(); ++i)
    if (p.kinds[i] == SphParticleKind::kFluid) m += p.masses[i];
  return m;
}

TEST(SphFluidSource, DiscLatticeCountsAndPlane) {
  // Square lattice points within r: r = 2.5 d: 21 (Gauss circle), r = 4 d: 49, r = 0.5 d: the centre.
  const Vec3 axis = Vec3(1, 2, -0.5);
  EXPECT_EQ(latticeDisc(axis, 0.25, 0.1, 3).size(), 21u);
  EXPECT_EQ(latticeDisc(Vec3(0, -1, 0), 0.44, 0.11, 3).size(), 49u);
  EXPECT_EQ(latticeDisc(axis, 0.05, 0.1, 3).size(), 1u);
  EXPECT_EQ(latticeDisc(Vec3(0, -1, 0), 0.2, 0.1, 2).size(), 5u);  // 2D: a segment of 2 r
  for (const Vec3& p : latticeDisc(axis, 0.25, 0.1, 3)) {
    EXPECT_NEAR(p.dot(axis.normalized()), 0.0, 1e-15);
    EXPECT_LE(p.norm(), 0.25 + 1e-12);
  }
  for (const Vec3& p : latticeDisc(Vec3(1, 1, 0), 0.2, 0.1, 2)) EXPECT_EQ(p.z(), 0.0);
  EXPECT_THROW(latticeDisc(Vec3::Zero(), 0.2, 0.1, 3), std::invalid_argument);
  EXPECT_THROW(latticeDisc(Vec3(0, 0, 1), 0.2, 0.1, 2), std::invalid_argument);
  EXPECT_THROW(latticeDisc(Vec3(0, 1, 0), 0.2, 0.0, 3), std::invalid_argument);
}

TEST(SphFluidSource, CylinderIsFilledWithinItsRadius) {
  SphParticles p;
  const Vec3 from(-1.1, 1.2, 0), to(1.1, 1.2, 0);
  const size_t added = addLatticeCylinder(p, from, to, 0.275, 0.11, 1.0);
  EXPECT_EQ(added, 20u * 21u);  // 20 cell-centred cross-sections of 21 points
  ASSERT_EQ(p.size(), added);
  double lo = 1e9, hi = -1e9;
  for (size_t i = 0; i < p.size(); ++i) {
    EXPECT_EQ(p.kinds[i], SphParticleKind::kStaticBoundary);
    const Vec3& x = p.positions[i];
    EXPECT_LE(std::hypot(x.y() - 1.2, x.z()), 0.275 + 1e-12);
    lo = std::min(lo, x.x());
    hi = std::max(hi, x.x());
  }
  EXPECT_NEAR(lo, -1.1 + 0.055, 1e-12);
  EXPECT_NEAR(hi, 1.1 - 0.055, 1e-12);
  EXPECT_THROW(addLatticeCylinder(p, from, from, 0.2, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(addLatticeCylinder(p, from, to, 0.0, 0.1, 1.0), std::invalid_argument);
}

SphFluidSourceConfig downwardSource() {
  SphFluidSourceConfig c;
  c.dimension = 3;
  c.center = Vec3(0, 1, 0);
  c.direction = Vec3(0, -2, 0);  // normalised on use
  c.radius = 0.25;
  c.speed = 1.5;
  c.spacing = 0.1;
  c.temperature = 30.0;
  return c;
}

// Emitted particles move away with the source velocity (a free stream), `steps` steps of dt up to t_end.
SphFluidSourceStats streamFor(double dt, int steps, SphParticles* out) {
  const SphKernels kernels(3, 0.2);
  SphFluidSource source(downwardSource(), kernels, 1.0);
  SphParticles p;
  source.emit(p, 0.0);
  for (int k = 1; k <= steps; ++k) {
    for (size_t i = 0; i < p.size(); ++i) p.positions[i] += dt * p.velocities[i];
    source.emit(p, k * dt);
  }
  if (out) *out = p;
  return source.stats();
}

TEST(SphFluidSource, MassRateIsRhoAreaSpeedForAnyStep) {
  const SphKernels kernels(3, 0.2);
  const SphFluidSource source(downwardSource(), kernels, 1.0);
  EXPECT_EQ(source.layerSize(), 21u);
  EXPECT_DOUBLE_EQ(source.particleMass(), latticeParticleMass(kernels, 1.0, 0.1));
  // The pitch makes N m / p = rho_0 pi r^2 exactly; it is within the Gauss-circle error of d.
  EXPECT_NEAR(21 * source.particleMass() / source.layerPitch(), M_PI * 0.25 * 0.25, 1e-15);
  EXPECT_NEAR(source.layerPitch(), 0.1059, 0.0005);  // 21 points vs pi 2.5^2 = 19.6
  const double t_end = 2.0, rate = source.massRate();
  EXPECT_NEAR(rate, M_PI * 0.0625 * 1.5, 1e-15);
  SphParticles a, b;
  const SphFluidSourceStats sa = streamFor(0.004, 500, &a);  // 2 s
  const SphFluidSourceStats sb = streamFor(0.01, 200, &b);   // 2 s
  const double layer_mass = 21 * source.particleMass();
  for (const SphFluidSourceStats* s : {&sa, &sb}) {
    EXPECT_EQ(s->skipped, 0u);
    EXPECT_FALSE(s->capped);
    EXPECT_NEAR(s->emitted_mass, source.scheduledMass(t_end), 1e-12);
    // Within one layer of rho_0 pi r^2 v t (31 layers here: 3.2%).
    EXPECT_LE(std::abs(s->emitted_mass - rate * t_end), layer_mass);
    EXPECT_EQ(s->emitted, s->layers * 21u);
  }
  EXPECT_EQ(sa.emitted, sb.emitted);  // the schedule does not depend on the step
  EXPECT_NEAR(fluidMass(a), sa.emitted_mass, 1e-12);
  // Every layer sits at its exact offset v (t - t_k) below the disc, whatever the step: the streams agree.
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a.positions[i].y(), b.positions[i].y(), 1e-12);
}

TEST(SphFluidSource, ParticlesAppearAtTheirOffsetWithTheSourceVelocity) {
  const SphKernels kernels(3, 0.2);
  SphFluidSource source(downwardSource(), kernels, 1.0);
  SphParticles p;
  EXPECT_EQ(source.emit(p, 0.0), 21u);  // layer 0 leaves at start
  const double pitch = source.layerPitch(), v = 1.5;
  // At t = 2.5 p / v layers 1 and 2 are due, at offsets 1.5 p and 0.5 p.
  EXPECT_EQ(source.emit(p, 2.5 * pitch / v), 42u);
  ASSERT_EQ(p.size(), 63u);
  for (size_t i = 0; i < p.size(); ++i) {
    EXPECT_EQ(p.kinds[i], SphParticleKind::kFluid);
    EXPECT_EQ(p.phases[i], 0);
    EXPECT_DOUBLE_EQ(p.masses[i], source.particleMass());
    EXPECT_TRUE(p.velocities[i].isApprox(Vec3(0, -1.5, 0), 1e-15));
    const double offset = 1.0 - p.positions[i].y();
    const double expected = i < 21 ? 0.0 : (i < 42 ? 1.5 * pitch : 0.5 * pitch);
    EXPECT_NEAR(offset, expected, 1e-12) << i;
    EXPECT_LE(std::hypot(p.positions[i].x(), p.positions[i].z()), 0.25 + 1e-12);
  }
  EXPECT_EQ(source.emit(p, 2.5 * pitch / v), 0u);  // nothing new at the same time
  // Before start and after stop nothing is emitted.
  SphFluidSourceConfig late = downwardSource();
  late.start_time = 1.0;
  late.stop_time = 1.0 + 1.5 * pitch / v;  // layers 0 and 1
  SphFluidSource delayed(late, kernels, 1.0);
  SphParticles q;
  EXPECT_EQ(delayed.emit(q, 0.99), 0u);
  EXPECT_EQ(delayed.emit(q, 5.0), 42u);
  EXPECT_EQ(delayed.emit(q, 9.0), 0u);
  EXPECT_EQ(delayed.stats().layers, 2u);
}

TEST(SphFluidSource, StopsAtTheCapAndSkipsOccupiedPoints) {
  const SphKernels kernels(3, 0.2);
  SphFluidSourceConfig capped = downwardSource();
  capped.max_particles = 50;
  SphParticles out;
  SphFluidSource source(capped, kernels, 1.0);
  for (int k = 0; k <= 200; ++k) {
    for (size_t i = 0; i < out.size(); ++i) out.positions[i] += 0.01 * out.velocities[i];
    source.emit(out, 0.01 * k);
  }
  EXPECT_EQ(out.size(), 50u);
  EXPECT_EQ(source.stats().emitted, 50u);
  EXPECT_TRUE(source.stats().capped);
  EXPECT_EQ(source.stats().layers, 3u);  // 21 + 21 + 8

  // A boundary particle 0.04 from the disc centre blocks that lattice point only (within d / 2 = 0.05).
  SphParticles p;
  p.add(Vec3(0.0, 1.04, 0.0), Vec3::Zero(), 1.0, SphParticleKind::kStaticBoundary);
  p.add(Vec3(0.1, 1.06, 0.0), Vec3::Zero(), 1.0, SphParticleKind::kFluid);  // 0.06 away: not blocking
  SphFluidSource blocked(downwardSource(), kernels, 1.0);
  EXPECT_EQ(blocked.emit(p, 0.0), 20u);
  EXPECT_EQ(blocked.stats().skipped, 1u);
  EXPECT_EQ(p.size(), 22u);
  for (size_t i = 2; i < p.size(); ++i) EXPECT_GE((p.positions[i] - p.positions[0]).norm(), 0.05);

  SphFluidSourceConfig bad = downwardSource();
  bad.radius = 0.04;  // below d / 2
  EXPECT_THROW(SphFluidSource(bad, kernels, 1.0), std::invalid_argument);
  bad = downwardSource();
  bad.stop_time = 0.0;
  EXPECT_THROW(SphFluidSource(bad, kernels, 1.0), std::invalid_argument);
  bad = downwardSource();
  bad.direction = Vec3::Zero();
  EXPECT_THROW(SphFluidSource(bad, kernels, 1.0), std::invalid_argument);
  EXPECT_THROW(SphFluidSource(downwardSource(), SphKernels(2, 0.2), 1.0), std::invalid_argument);
}

const char* kHead =
    "dimension: 3\n"                                                    // 1
    "spacing: 0.1\n"                                                    // 2
    "solver: {smoothing_ratio: 2.0, stiffness: 20, rest_density: 1}\n"  // 3
    "frames: {count: 2, time: 0.01}\n";                                 // 4

TEST(SphFluidSource, SceneKeysAndTheirErrors) {
  const std::string head = kHead;
  const std::string ok_source =
      "sources:\n  - {center: [0, 1, 0], direction: [0, -1, 0], radius: 0.25, speed: 1}\n";  // 5-6
  ASSERT_EQ(parseError(head + ok_source), "");
  const SphScene scene = parseSphScene(head + ok_source, "ok.yaml");  // a source instead of fluid
  ASSERT_EQ(scene.sources.size(), 1u);
  EXPECT_EQ(scene.sources[0].spacing, 0.1);  // the scene's spacing
  EXPECT_EQ(scene.sources[0].max_particles, 0u);
  EXPECT_TRUE(std::isinf(scene.sources[0].stop_time));
  EXPECT_TRUE(scene.particles.empty());
  auto source = [&](const std::string& keys) {
    return head + "sources:\n  - {center: [0, 1, 0], direction: [0, -1, 0], " + keys + "}\n";
  };
  expectErrorAt(source("radius: 0, speed: 1"), 6, "radius");
  expectErrorAt(source("radius: -1, speed: 1"), 6, "radius");
  expectErrorAt(source("radius: 0.04, speed: 1"), 6, "below half the spacing");
  expectErrorAt(source("radius: 0.2, speed: 0"), 6, "speed");
  expectErrorAt(source("radius: 0.2"), 6, "missing 'speed'");
  expectErrorAt(source("radius: 0.2, speed: 1, start: 2, stop: 1"), 6, "must exceed start");
  expectErrorAt(source("radius: 0.2, speed: 1, start: -1"), 6, "start");
  expectErrorAt(source("radius: 0.2, speed: 1, max_particles: 0"), 6, "max_particles");
  expectErrorAt(source("radius: 0.2, speed: 1, temperature: 3"), 6, "needs 'temperature'");
  expectErrorAt(source("radius: 0.2, speed: 1, sped: 1"), 6, "unknown key 'sped'");
  expectErrorAt(head + "sources:\n  - {center: [0, 1, 0], direction: [0, 0, 0], radius: 0.2, speed: 1}\n", 6,
                "direction must be non-zero");
  expectErrorAt(head + "sources: []\n", 5, "expected a list of sources");
  // 2D: the direction lies in the plane.
  expectErrorAt(
      "dimension: 2\nspacing: 0.1\nsolver: {smoothing_ratio: 2.0, stiffness: 20}\nframes: {count: 1, time: "
      "0.01}\nsources:\n  - {center: [0, 1], direction: [0, -1, 1], radius: 0.2, speed: 1}\n",
      6, "z must be 0");

  // Cylinders: 3D only, from != to, radius > 0; held cylinders select the particles inside.
  const std::string fluid = "fluid:\n  - {lo: [0, 0, 0], hi: [0.4, 0.4, 0.4]}\n";  // 5-6
  auto cylinder = [&](const std::string& keys) {
    return head + fluid + "boundary:\n  cylinders:\n    - {" + keys + "}\n";  // 9
  };
  ASSERT_EQ(parseError(cylinder("from: [0, 1, 0], to: [1, 1, 0], radius: 0.15")), "");
  const SphScene rod = parseSphScene(cylinder("from: [0, 1, 0], to: [1, 1, 0], radius: 0.15"), "rod.yaml");
  EXPECT_EQ(rod.particles.count(SphParticleKind::kStaticBoundary), 10u * 9u);  // 9 within 1.5 d
  expectErrorAt(cylinder("from: [0, 1, 0], to: [0, 1, 0], radius: 0.15"), 9, "'from' and 'to' must differ");
  expectErrorAt(cylinder("from: [0, 1, 0], to: [1, 1, 0], radius: 0"), 9, "radius");
  expectErrorAt(cylinder("from: [0, 1, 0], to: [1, 1, 0]"), 9, "missing 'radius'");
  expectErrorAt(cylinder("from: [0, 1, 0], to: [1, 1, 0], radius: 0.1, lo: [0, 0, 0]"), 9,
                "unknown key 'lo'");
  expectErrorAt(
      "dimension: 2\nspacing: 0.1\nsolver: {smoothing_ratio: 2.0, stiffness: 20}\nframes: {count: 1, time: "
      "0.01}\nfluid:\n  - {lo: [0, 0], hi: [0.4, 0.4]}\nboundary:\n  cylinders:\n    - {from: [0, 1], to: "
      "[1, 1], radius: 0.2}\n",
      9, "needs a 3D scene");
  const std::string held = head + fluid + "boundary:\n  cylinders:\n    - {from: [0, 1, 0], to: [1, 1, 0], " +
                           "radius: 0.15}\nenable: [temperature]\ntemperature:\n  held:\n";  // 10-12
  ASSERT_EQ(parseError(held + "    - {from: [0, 1, 0], to: [1, 1, 0], radius: 0.2, temperature: -5}\n"), "");
  const SphScene cooled = parseSphScene(
      held + "    - {from: [0, 1, 0], to: [1, 1, 0], radius: 0.2, temperature: -5}\n", "cooled.yaml");
  ASSERT_EQ(cooled.thermal.held.size(), 1u);
  EXPECT_EQ(cooled.thermal.held[0].indices.size(), 90u);  // the rod, not the fluid
  expectErrorAt(held + "    - {from: [5, 5, 5], to: [6, 5, 5], radius: 0.2, temperature: -5}\n", 13,
                "no particles inside the cylinder");
  expectErrorAt(held + "    - {from: [0, 1, 0], to: [1, 1, 0], radius: 0.2, hi: [1, 1, 1], temperature: 0}\n",
                13, "unknown key 'hi'");
}

// A sources-only scene through the scene runner with two fixed steps: the emitted mass follows rho_0 pi r^2 v
// t, the stats account for it, and the stream keeps the source's temperature.
TEST(SphFluidSource, SceneRunnerEmitsAtTheSameRateForTwoSteps) {
  auto run = [](double dt) {
    const std::string yaml =
        "dimension: 3\nspacing: 0.1\nenable: [temperature]\n"
        "solver: {smoothing_ratio: 2.0, stiffness: 20, rest_density: 1, gravity: [0, -9.81, 0], xsph: 0,"
        " fixed_dt: " +
        std::to_string(dt) +
        "}\n"
        "temperature: {conductivity: 0.01, initial: 5}\n"
        "sources:\n  - {center: [0, 0, 0], direction: [0, -1, 0], radius: 0.25, speed: 1.5, temperature: "
        "30}\n"
        "frames: {count: 4, time: 0.1}\n";
    const SphScene scene = parseSphScene(yaml, "stream.yaml");
    SphFluidSolver solver = makeSphSolver(scene);
    SphRunOptions options;
    options.thermal = makeSphThermal(scene, solver);
    const SphRunStats stats = runSphScene(scene, solver, options);
    EXPECT_TRUE(stats.instability.empty()) << stats.instability;
    EXPECT_EQ(stats.particles, 0u);
    EXPECT_EQ(stats.particles_end, stats.emitted);
    EXPECT_EQ(solver.particles().size(), stats.emitted);
    EXPECT_NEAR(fluidMass(solver.particles()), stats.emitted_mass, 1e-12);
    EXPECT_NEAR(stats.mass_drift, 0.0, 1e-12);
    EXPECT_EQ(stats.source_skipped, 0u);
    // Free fall from the nozzle: the momentum balance closes (no boundary).
    EXPECT_LT(stats.boundary_impulse.norm(), 1e-9 * std::max(1.0, stats.momentum_end.norm()));
    for (size_t i = 0; i < solver.particles().size(); ++i)
      EXPECT_EQ(options.thermal->temperatures()[i], 30.0);
    const std::string json = sphRunStatsJson(stats);
    for (const char* key : {"\"particles_end\"", "\"emitted\"", "\"emitted_mass\"", "\"source_skipped\""})
      EXPECT_NE(json.find(key), std::string::npos) << key;
    return stats;
  };
  const SphRunStats a = run(0.002), b = run(0.005);
  const SphFluidSource reference(
      parseSphScene("dimension: 3\nspacing: 0.1\nsolver: {smoothing_ratio: 2.0, stiffness: 20, rest_density: "
                    "1}\nsources:\n  - {center: [0, 0, 0], direction: [0, -1, 0], radius: 0.25, speed: 1.5}\n"
                    "frames: {count: 1, time: 0.1}\n",
                    "ref.yaml")
          .sources[0],
      SphKernels(3, 0.2), 1.0);
  const double layer = reference.layerSize() * reference.particleMass();
  for (const SphRunStats* s : {&a, &b}) {
    EXPECT_NEAR(s->simulated_time, 0.4, 1e-12);
    EXPECT_LE(std::abs(s->emitted_mass - reference.massRate() * 0.4), layer);
  }
  EXPECT_EQ(a.emitted, b.emitted);
  // Without sources the JSON has no emission keys.
  const SphScene plain =
      parseSphScene(std::string(kHead) + "fluid:\n  - {lo: [0, 0, 0], hi: [0.3, 0.3, 0.3]}\n", "plain.yaml");
  SphFluidSolver solver = makeSphSolver(plain);
  const SphRunStats stats = runSphScene(plain, solver);
  EXPECT_EQ(stats.particles_end, stats.particles);
  EXPECT_EQ(sphRunStatsJson(stats).find("\"emitted\""), std::string::npos);
}

// Thesis Fig. 8.5 in 3D: the first second of the shipped scene. Slime poured onto the cooled static rod
// freezes onto it; the mass is the initial plus the emitted.
TEST(SphFluidSource, SlimeFreezesOntoTheCooledRod) {
  SphScene scene = loadSphScene(sphSceneDir() + "fig8_5_freezing_rod.yaml");
  EXPECT_EQ(scene.particles.size(), 1620u);
  ASSERT_EQ(scene.sources.size(), 1u);
  EXPECT_EQ(scene.config.smoothing_length, 0.22);
  EXPECT_EQ(scene.thermal.held.size(), 1u);
  EXPECT_EQ(scene.thermal.held[0].indices.size(), 420u);  // the rod
  EXPECT_TRUE(scene.solids[0].elastic.anchor_boundary_particles);
  scene.frame_count = 25;  // 1 s
  const double mass_start = fluidMass(scene.particles);
  SphFluidSolver solver = makeSphSolver(scene);
  SphRunOptions options;
  options.thermal = makeSphThermal(scene, solver);
  const SphRunStats stats = runSphScene(scene, solver, options);
  ASSERT_TRUE(stats.instability.empty()) << stats.instability;
  const SphParticles& p = solver.particles();
  size_t frozen = 0, far = 0, below = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.kinds[i] != SphParticleKind::kFluid) continue;
    const double to_axis = std::hypot(p.positions[i].y() - 1.2, p.positions[i].z());
    if (p.phases[i] == 0) {
      below += p.positions[i].y() < 0.8;
      continue;
    }
    ++frozen;
    far += to_axis > 0.275 + 3 * 0.22 || std::abs(p.positions[i].x()) > 1.1 + 0.44;
  }
  std::printf(
      "fig 8.5: %zu -> %zu particles in %.2f s (%llu steps, dt %.4f s), %zu frozen (%zu away from the rod), "
      "%zu fluid below the rod, %.3f s wall\n",
      stats.particles, stats.particles_end, stats.simulated_time, (unsigned long long)stats.steps,
      stats.mean_dt, frozen, far, below, stats.wall_seconds);
  EXPECT_EQ(stats.particles_end, 1620u + stats.emitted);
  EXPECT_EQ(p.size(), stats.particles_end);
  EXPECT_GT(stats.emitted, 800u);  // 890 particles/s
  EXPECT_EQ(stats.frozen, frozen);
  EXPECT_GT(frozen, 50u);
  EXPECT_LT(far, frozen / 4);  // the ice is on the rod
  EXPECT_GT(below, 100u);      // the rest drips past
  EXPECT_NEAR(fluidMass(p), mass_start + stats.emitted_mass, 1e-12 * fluidMass(p));
  EXPECT_NEAR(stats.mass_drift, 0.0, 1e-12);
  EXPECT_GE(stats.min_temperature, -20.0);
  EXPECT_LE(stats.max_temperature, 20.0);
}

}  // namespace
}  // namespace rc
