// Thesis Fig. 8.7: the three 2D material scenes of config/sph run through the scene runner (the code path of
// rc_sph): (a) an elastic cube bounces and returns to its shape, (b) a plastic cube keeps the deformation of
// its landing, (c) a cube fixed to the wall fractures under gravity. Also: fracture and plasticity with
// adaptive time steps (SphForceTerm::beginStep), and the docked_points field of the particle outputs.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <numeric>
#include <sstream>
#include <vector>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/sph/sph_elastic_solid.h"
#include "relaxed_connectivity/sph/sph_output.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"
#include "scene_file_test_support.h"

namespace rc {
namespace {

namespace fs = std::filesystem;

const std::string kSceneDir = sphSceneDir();

/// The scene's (only) elastic solid in the solver.
std::shared_ptr<SphElasticSolid> solidOf(const SphFluidSolver& solver) {
  for (const auto& term : solver.forceTerms())
    if (auto solid = std::dynamic_pointer_cast<SphElasticSolid>(term)) return solid;
  return nullptr;
}

/// Global shape of the particles [first, first + count) against their rest positions: the least-squares
/// affine map A from rest to current offsets (about the centres of mass), its singular values (stretches)
/// and the residual of the fit per particle (RMS, in metres).
struct Shape {
  Eigen::Vector2d stretch = Eigen::Vector2d::Ones();  // singular values of A, descending
  Vec3 center = Vec3::Zero(), velocity = Vec3::Zero();
  double residual = 0.0;
  double height = 0.0, width = 0.0;  // extents along y and x
  double strain() const { return std::max(std::abs(stretch(0) - 1.0), std::abs(stretch(1) - 1.0)); }
};

Shape measureShape(const SphParticles& p, const std::vector<Vec3>& rest, size_t first, size_t count) {
  Shape s;
  Vec3 rest_center = Vec3::Zero();
  double mass = 0.0;
  double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300;
  for (size_t i = first; i < first + count; ++i) {
    mass += p.masses[i];
    s.center += p.masses[i] * p.positions[i];
    s.velocity += p.masses[i] * p.velocities[i];
    rest_center += p.masses[i] * rest[i];
    lo_x = std::min(lo_x, p.positions[i].x());
    hi_x = std::max(hi_x, p.positions[i].x());
    lo_y = std::min(lo_y, p.positions[i].y());
    hi_y = std::max(hi_y, p.positions[i].y());
  }
  s.center /= mass;
  s.velocity /= mass;
  rest_center /= mass;
  s.width = hi_x - lo_x;
  s.height = hi_y - lo_y;
  Eigen::Matrix2d xr = Eigen::Matrix2d::Zero(), rr = Eigen::Matrix2d::Zero();
  for (size_t i = first; i < first + count; ++i) {
    const Eigen::Vector2d x = (p.positions[i] - s.center).head<2>(), r = (rest[i] - rest_center).head<2>();
    xr += x * r.transpose();
    rr += r * r.transpose();
  }
  const Eigen::Matrix2d a = xr * rr.inverse();
  s.stretch = Eigen::JacobiSVD<Eigen::Matrix2d>(a).singularValues();
  double sum = 0.0;
  for (size_t i = first; i < first + count; ++i) {
    const Eigen::Vector2d x = (p.positions[i] - s.center).head<2>(), r = (rest[i] - rest_center).head<2>();
    sum += (x - a * r).squaredNorm();
  }
  s.residual = std::sqrt(sum / double(count));
  return s;
}

/// Connected pieces of the solid particles (phase != 0, any kind): particles closer than `link` are joined.
/// Returns the piece sizes, largest first.
std::vector<size_t> pieces(const SphParticles& p, double link) {
  std::vector<size_t> members;
  for (size_t i = 0; i < p.size(); ++i)
    if (p.phases[i] != 0) members.push_back(i);
  std::vector<size_t> parent(members.size());
  std::iota(parent.begin(), parent.end(), size_t(0));
  const auto root = [&](size_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (size_t a = 0; a < members.size(); ++a)
    for (size_t b = a + 1; b < members.size(); ++b)
      if ((p.positions[members[a]] - p.positions[members[b]]).norm() < link) parent[root(a)] = root(b);
  std::vector<size_t> size(members.size(), 0);
  for (size_t a = 0; a < members.size(); ++a) ++size[root(a)];
  std::vector<size_t> out;
  for (size_t s : size)
    if (s > 0) out.push_back(s);
  std::sort(out.rbegin(), out.rend());
  return out;
}

/// Forwards everything but beginStep to `inner`: the force-term interface before the solver announced its
/// steps (the solid then uses config().time_step for every evaluation).
class UnannouncedTerm : public SphForceTerm {
 public:
  explicit UnannouncedTerm(std::shared_ptr<SphForceTerm> inner) : inner_(std::move(inner)) {}
  void addForces(const SphParticles& p, const std::vector<Vec3>& v, std::vector<Vec3>& f) override {
    inner_->addForces(p, v, f);
  }
  double stableTimeStep(const SphParticles& p, double cfl) const override {
    return inner_->stableTimeStep(p, cfl);
  }
  double potentialEnergy() const override { return inner_->potentialEnergy(); }

 private:
  std::shared_ptr<SphForceTerm> inner_;
};

/// The stretch tensor S of the polar decomposition A = R S of the shape fit.
Eigen::Matrix2d stretchTensor(const SphParticles& p, const std::vector<Vec3>& rest, size_t first,
                              size_t count) {
  Vec3 c = Vec3::Zero(), c0 = Vec3::Zero();
  double mass = 0.0;
  for (size_t i = first; i < first + count; ++i) {
    mass += p.masses[i];
    c += p.masses[i] * p.positions[i];
    c0 += p.masses[i] * rest[i];
  }
  c /= mass;
  c0 /= mass;
  Eigen::Matrix2d xr = Eigen::Matrix2d::Zero(), rr = Eigen::Matrix2d::Zero();
  for (size_t i = first; i < first + count; ++i) {
    const Eigen::Vector2d x = (p.positions[i] - c).head<2>(), r = (rest[i] - c0).head<2>();
    xr += x * r.transpose();
    rr += r * r.transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(xr * rr.inverse(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixV() * svd.singularValues().asDiagonal() * svd.matrixV().transpose();
}

TEST(SphFig87, ElasticCubeBouncesAndReturnsToItsShape) {
  // Fig. 8.7 (a): elastic_cube_2d.yaml falls 3 cm, is squashed by the impact, bounces and vibrates about its
  // rest shape: the stretch tensor averaged over the frames after the first bounce is the identity.
  const SphScene scene = loadSphScene(kSceneDir + "elastic_cube_2d.yaml");
  ASSERT_EQ(scene.solids.size(), 1u);
  const SphSceneSolid& cube = scene.solids[0];
  const std::vector<Vec3> rest = scene.particles.positions;
  SphFluidSolver solver = makeSphSolver(scene);
  double max_rise = -1e300, max_strain = 0.0;
  bool bounced = false;
  Eigen::Matrix2d mean_stretch = Eigen::Matrix2d::Zero();
  int averaged = 0;
  SphRunOptions options;
  options.on_frame = [&](const SphFrameReport&) {
    const Shape s = measureShape(solver.particles(), rest, cube.first, cube.count);
    if (s.velocity.y() > 0.0) bounced = true;
    max_strain = std::max(max_strain, s.strain());
    if (!bounced) return;
    max_rise = std::max(max_rise, s.velocity.y());
    mean_stretch += stretchTensor(solver.particles(), rest, cube.first, cube.count);
    ++averaged;
  };
  const SphRunStats stats = runSphScene(scene, solver, options);
  mean_stretch /= averaged;
  const Eigen::Vector2d eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(mean_stretch).eigenvalues();
  const double residual = std::max(std::abs(eig(0) - 1.0), std::abs(eig(1) - 1.0));
  const Shape end = measureShape(solver.particles(), rest, cube.first, cube.count);
  std::printf(
      "Fig 8.7a elastic: %llu steps, fastest rise %.3f m/s, max global strain %.4f, residual strain (mean "
      "stretch over %d frames after the bounce) %.4f, end fit residual %.2g m\n",
      (unsigned long long)stats.steps, max_rise, max_strain, averaged, residual, end.residual);
  ASSERT_TRUE(stats.instability.empty()) << stats.instability;
  ASSERT_GE(averaged, 5);
  EXPECT_GT(max_rise, 0.3);                                     // it bounced off the floor
  EXPECT_GT(max_strain, 0.08);                                  // the impact squashed it by more than 8%
  EXPECT_LT(residual, 0.02);                                    // and it vibrates about its rest shape
  EXPECT_LT(end.residual, 0.1 * cube.elastic.lattice_spacing);  // no particle left its place in the block
}

/// Height / width of the cube of `scene` after its run, and the end speed of its centre of mass.
double runPlasticCube(const SphScene& scene, double* speed, double* max_plastic_strain, SphRunStats* stats) {
  const SphSceneSolid& cube = scene.solids[0];
  SphFluidSolver solver = makeSphSolver(scene);
  *stats = runSphScene(scene, solver, {});
  const Shape end = measureShape(solver.particles(), scene.particles.positions, cube.first, cube.count);
  *speed = end.velocity.norm();
  *max_plastic_strain = solidOf(solver)->stats().max_plastic_strain;
  return end.height / end.width;
}

TEST(SphFig87, PlasticCubeKeepsItsLandingDeformation) {
  const SphScene scene = loadSphScene(kSceneDir + "fig87_plastic_cube_2d.yaml");
  ASSERT_EQ(scene.solids.size(), 1u);
  ASSERT_TRUE(scene.solids[0].elastic.plasticity());
  EXPECT_EQ(scene.config.fixed_dt, 0.0);  // adaptive steps
  const SphSceneSolid& cube = scene.solids[0];
  const Shape start = measureShape(scene.particles, scene.particles.positions, cube.first, cube.count);
  const double ratio_start = start.height / start.width;
  double speed = 0.0, plastic_strain = 0.0, speed_elastic = 0.0, plastic_strain_elastic = 0.0;
  SphRunStats stats, stats_elastic;
  const double ratio_end = runPlasticCube(scene, &speed, &plastic_strain, &stats);
  SphScene elastic = scene;  // control: plasticity off
  elastic.solids[0].elastic.yield_strain = std::numeric_limits<double>::infinity();
  const double ratio_elastic =
      runPlasticCube(elastic, &speed_elastic, &plastic_strain_elastic, &stats_elastic);
  std::printf(
      "Fig 8.7b plastic: %llu steps (mean dt %.3g), height/width %.4f -> %.4f (plasticity off: %.4f), end "
      "speed %.3g, max plastic log-stretch %.3f\n",
      (unsigned long long)stats.steps, stats.mean_dt, ratio_start, ratio_end, ratio_elastic, speed,
      plastic_strain);
  ASSERT_TRUE(stats.instability.empty()) << stats.instability;
  ASSERT_TRUE(stats_elastic.instability.empty()) << stats_elastic.instability;
  EXPECT_GT(stats.mean_dt, 2.5e-4);         // adaptive: beyond the old fixed step
  EXPECT_LT(ratio_end, 0.7 * ratio_start);  // flattened by more than 30% ...
  EXPECT_GT(ratio_end, 0.3 * ratio_start);  // ... but still a block
  // Without stored plasticity the impact leaves less (the inherent plasticity of 8.2.5 keeps a little).
  EXPECT_GT(ratio_elastic, ratio_end + 0.2);
  EXPECT_LT(speed, 0.03);  // at rest: the deformation is permanent
  EXPECT_GT(plastic_strain, 0.2);
  EXPECT_EQ(plastic_strain_elastic, 0.0);
}

/// Smallest distance between particles of two index sets.
double gapBetween(const SphParticles& p, const std::vector<size_t>& a, const std::vector<size_t>& b) {
  double gap = 1e300;
  for (size_t i : a)
    for (size_t j : b) gap = std::min(gap, (p.positions[i] - p.positions[j]).norm());
  return gap;
}

TEST(SphFig87, FracturingCubeCracksAndWritesDockedPoints) {
  SphScene scene = loadSphScene(kSceneDir + "fig87_fracturing_cube_2d.yaml");
  ASSERT_EQ(scene.solids.size(), 1u);
  ASSERT_TRUE(scene.solids[0].elastic.docking);
  EXPECT_EQ(scene.config.fixed_dt, 0.0);  // adaptive steps
  const double d = scene.solids[0].elastic.lattice_spacing, h = scene.config.smoothing_length;
  scene.output.every = scene.frame_count;  // frames 0 and the last
  scene.output.ply = scene.output.vtp = true;
  const fs::path dir = fs::temp_directory_path() / "rc_test_sph_fig87";
  fs::remove_all(dir);
  SphFluidSolver solver = makeSphSolver(scene);
  SphRunOptions options;
  options.out_dir = dir.string();
  const SphRunStats stats = runSphScene(scene, solver, options);
  ASSERT_TRUE(stats.instability.empty()) << stats.instability;
  const auto solid = solidOf(solver);
  const SphParticles& p = solver.particles();
  // The pieces: the falling body (the largest) and the one holding the anchored particles.
  std::vector<size_t> anchored, body;
  for (size_t i = 0; i < p.size(); ++i)
    if (p.kinds[i] == SphParticleKind::kStaticBoundary) anchored.push_back(i);
  const std::vector<size_t> parts = pieces(p, 1.5 * d);
  std::vector<size_t> near_anchor;  // free particles within 1.5 d of the anchor, transitively
  {
    std::vector<uint8_t> in(p.size(), 0);
    for (size_t i : anchored) in[i] = 1;
    for (bool grew = true; grew;) {
      grew = false;
      for (size_t i = 0; i < p.size(); ++i) {
        if (in[i]) continue;
        for (size_t j = 0; j < p.size() && !in[i]; ++j)
          if (in[j] && (p.positions[i] - p.positions[j]).norm() < 1.5 * d) in[i] = grew = 1;
      }
    }
    for (size_t i = 0; i < p.size(); ++i) (in[i] ? near_anchor : body).push_back(i);
  }
  const double gap = gapBetween(p, near_anchor, body);
  std::vector<uint32_t> docked;
  ASSERT_TRUE(sphDockedPoints(solver, docked));
  // Crack and surface particles (the dark ones of Fig. 8.7 c) have fewer docked lattice points than the
  // interior of the falling body.
  uint32_t most = 0, fewest = 1000;
  for (size_t i = 0; i < p.size(); ++i)
    if (p.kinds[i] == SphParticleKind::kFluid) {
      most = std::max(most, docked[i]);
      fewest = std::min(fewest, docked[i]);
    }
  std::printf(
      "Fig 8.7c fracture: %llu steps (mean dt %.3g), %llu detached, %llu redocked, %zu pieces (largest %zu), "
      "anchored piece %zu, rest %zu, gap %.4f (h %.3f), docked points %u..%u\n",
      (unsigned long long)stats.steps, stats.mean_dt, (unsigned long long)solid->totalDetached(),
      (unsigned long long)solid->totalRedocked(), parts.size(), parts[0], near_anchor.size(), body.size(),
      gap, h, fewest, most);
  EXPECT_GT(stats.mean_dt, 2.5e-4);                     // adaptive: beyond the old fixed step
  EXPECT_EQ(solid->stepTime(), solver.lastStats().dt);  // the solid drew with the solver's step
  EXPECT_GT(solid->totalDetached(), 100u);
  EXPECT_GE(parts.size(), 2u);
  EXPECT_GE(parts[0], 60u);  // a big piece broke off ...
  EXPECT_GE(body.size(), 60u);
  EXPECT_GT(gap, 1.5 * d);  // ... with a gap of more than a lattice spacing to the anchored rest
  EXPECT_GE(most, fewest + 4u);

  // docked_points in the particle files of the last frame.
  char stem[64];
  std::snprintf(stem, sizeof(stem), "_%04d", scene.frame_count);
  const SurfelCloud cloud = readCloud((dir / (scene.name + stem + ".ply")).string());
  const Attribute* field = cloud.attributes.find("docked_points");
  ASSERT_TRUE(field != nullptr);
  EXPECT_EQ(field->type, ScalarType::kUInt32);
  ASSERT_EQ(cloud.size(), p.size());
  for (size_t i = 0; i < p.size(); ++i) ASSERT_EQ(field->get(i), double(docked[i])) << i;
  std::ifstream vtp((dir / (scene.name + stem + ".vtp")).string(), std::ios::binary);
  std::stringstream text;
  text << vtp.rdbuf();
  EXPECT_NE(text.str().find("<DataArray type=\"UInt32\" Name=\"docked_points\" format=\"appended\""),
            std::string::npos);
  // Scenes without fracture write no such field.
  SphParticles plain = p;
  writeSphVtp((dir / "plain.vtp").string(), plain, VtpEncoding::kAscii);
  std::ifstream plain_in((dir / "plain.vtp").string());
  std::stringstream plain_text;
  plain_text << plain_in.rdbuf();
  EXPECT_EQ(plain_text.str().find("docked_points"), std::string::npos);
}

TEST(SphFig87, FixedStepFractureIsUnchangedByTheStepAnnouncement) {
  // With a fixed step the solver announces fixed_dt for every (not shortened) step, which is what the solid
  // used before (config time_step = fixed_dt): bitwise the same run as with the announcement withheld.
  SphScene scene = loadSphScene(kSceneDir + "fig87_fracturing_cube_2d.yaml");
  scene.config.fixed_dt = 2.5e-4;
  scene.solids[0].elastic.time_step = 2.5e-4;
  SphFluidSolver announced = makeSphSolver(scene);
  SphFluidSolver withheld(scene.config, scene.particles);
  for (const SphPlane& plane : scene.planes) withheld.addPlane(plane);
  const auto solid = std::make_shared<SphElasticSolid>(scene.solids[0].elastic, withheld.kernels(),
                                                       scene.solids[0].phase, scene.solids[0].orientation);
  withheld.addForceTerm(std::make_shared<UnannouncedTerm>(solid));
  for (int k = 0; k < 400; ++k) {
    announced.step();
    withheld.step();
  }
  const auto announced_solid = solidOf(announced);
  std::printf("fixed step: %llu | %llu detached after 400 steps\n",
              (unsigned long long)announced_solid->totalDetached(),
              (unsigned long long)solid->totalDetached());
  EXPECT_GT(solid->totalDetached(), 0u);
  EXPECT_EQ(announced_solid->totalDetached(), solid->totalDetached());
  const auto& a = announced.particles().positions;
  const auto& b = withheld.particles().positions;
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)), 0);
  // Adaptive: the step changes, and the solid follows it.
  SphScene adaptive = loadSphScene(kSceneDir + "fig87_fracturing_cube_2d.yaml");
  SphFluidSolver solver = makeSphSolver(adaptive);
  solver.step();
  EXPECT_EQ(solidOf(solver)->stepTime(), solver.lastStats().dt);
  EXPECT_EQ(solver.lastStats().limit, SphStepLimit::kElastic);
}

}  // namespace
}  // namespace rc
