// SPH scene files: solids of shape mesh (a triangle mesh sampled on the fcc lattice (8.20) inside its
// generalised winding number), the Fig. 8.4 melting bunny and the 2D colliding blocks (penalty (8.37)).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/sph/sph_fluid_solver.h"
#include "relaxed_connectivity/sph/sph_kernels.h"
#include "relaxed_connectivity/sph/sph_lattice.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"
#include "scene_file_test_support.h"

namespace rc {
namespace {

namespace fs = std::filesystem;

const std::string kSceneDir = sphSceneDir();

/// A fresh folder under the system temp dir.
std::string tempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rc_sph_scene_mesh_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

/// The closed cube [-s/2, s/2]^3 + offset, 12 outward triangles, as OBJ text.
std::string cubeObj(double side, const Vec3& offset = Vec3::Zero()) {
  std::string text;
  const double h = side / 2;
  for (int k = 0; k < 8; ++k)
    text += "v " + std::to_string(offset.x() + ((k & 1) ? h : -h)) + " " +
            std::to_string(offset.y() + ((k & 2) ? h : -h)) + " " +
            std::to_string(offset.z() + ((k & 4) ? h : -h)) + "\n";
  // Faces (1-based), counter-clockwise seen from outside.
  const int quads[6][4] = {{1, 5, 7, 3}, {2, 4, 8, 6}, {1, 2, 6, 5},
                           {3, 7, 8, 4}, {1, 3, 4, 2}, {5, 6, 8, 7}};
  for (const auto& q : quads)
    text += "f " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) + "\nf " +
            std::to_string(q[0]) + " " + std::to_string(q[2]) + " " + std::to_string(q[3]) + "\n";
  return text;
}

/// Unit icosphere (icosahedron subdivided `levels` times, outward triangles) scaled to `radius`.
TriangleMesh icosphere(double radius, int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Triangle> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                             {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                             {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                             {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (Vec3& x : v) x.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = uint32_t(v.size() - 1);
    };
    std::vector<Triangle> g;
    for (const Triangle& tri : f) {
      const uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f = g;
  }
  TriangleMesh mesh;
  for (const Vec3& x : v) mesh.vertices.positions.push_back(radius * x);
  mesh.triangles = f;
  return mesh;
}

std::string meshObj(const TriangleMesh& mesh) {
  std::string text;
  char line[128];
  for (const Vec3& x : mesh.vertices.positions) {
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", x.x(), x.y(), x.z());
    text += line;
  }
  for (const Triangle& t : mesh.triangles)
    text += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
            std::to_string(t[2] + 1) + "\n";
  return text;
}

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

/// A 3D scene with one elastic solid `solid` (flow-map YAML text) at spacing d = 0.1, h = 0.2.
std::string solidScene(const std::string& solid) {
  return "dimension: 3\nspacing: 0.1\nenable: [elasticity]\n"
         "solver: {smoothing_ratio: 2.0, rest_density: 1, stiffness: 20, gravity: [0, 0, 0]}\n"
         "solids:\n  - " +
         solid + "\nframes: {count: 1, time: 0.01}\n";
}

SphScene loadText(const std::string& dir, const std::string& yaml) {
  const std::string path = dir + "/scene.yaml";
  writeFile(path, yaml);
  return loadSphScene(path);
}

std::string loadError(const std::string& dir, const std::string& yaml) {
  try {
    loadText(dir, yaml);
  } catch (const SphSceneError& e) {
    return e.what();
  }
  return "";
}

size_t solidCount(const SphScene& scene, uint8_t phase) {
  size_t n = 0;
  for (size_t i = 0; i < scene.particles.size(); ++i) n += scene.particles.phases[i] == phase;
  return n;
}

TEST(SphSceneMesh, CubeMeshGivesTheBoxSolidsParticles) {
  const std::string dir = tempDir("cube");
  const SphLattice lattice(3, 0.1);
  // Side 1.03: no lattice point lies within 1e-3 of a face (the x coordinates are multiples of d/2 = 0.05,
  // the others are checked below), so the winding number (1 inside, 0 outside) and the closed box agree
  // point by point. Placed, rotated cube vs. the box solid of the same placement: the same positions.
  writeFile(dir + "/cube.obj", cubeObj(1.03));
  const Vec3 half = Vec3::Constant(0.515);
  const std::vector<Vec3> box = sampleLatticeBox(lattice, -half, half, SphLatticeFrame());
  for (const Vec3& x : box) ASSERT_GT((half - x.cwiseAbs()).minCoeff(), 1e-3);
  const std::string rotation = "rotation: {axis: [1, 2, 3], angle: 25}";
  const SphScene mesh_scene =
      loadText(dir, solidScene("{shape: mesh, mesh: cube.obj, translation: [1, 2, 3], " + rotation + "}"));
  const SphScene box_scene =
      loadText(dir, solidScene("{lo: [0.485, 1.485, 2.485], hi: [1.515, 2.515, 3.515], " + rotation + "}"));
  ASSERT_EQ(mesh_scene.solids.size(), 1u);
  EXPECT_EQ(mesh_scene.solids[0].count, box.size());
  ASSERT_EQ(mesh_scene.particles.size(), box_scene.particles.size());
  double worst = 0.0;
  for (size_t i = 0; i < box_scene.particles.size(); ++i)
    worst = std::max(worst, (mesh_scene.particles.positions[i] - box_scene.particles.positions[i]).norm());
  EXPECT_LT(worst, 1e-12);
  EXPECT_EQ(mesh_scene.particles.masses, box_scene.particles.masses);
  EXPECT_TRUE(mesh_scene.solids[0].orientation.isApprox(box_scene.solids[0].orientation, 1e-15));

  // Side 1.0: lattice planes x = +-0.5 (and others) lie on the faces. The closed box counts the points on
  // its faces; the winding number there is ~1/2 either way, so the mesh count lies between the box count
  // without and with its face points (the boundary layer).
  writeFile(dir + "/unit.obj", cubeObj(1.0));
  const Vec3 unit_half = Vec3::Constant(0.5);
  const std::vector<Vec3> unit_box = sampleLatticeBox(lattice, -unit_half, unit_half, SphLatticeFrame());
  size_t on_faces = 0;
  for (const Vec3& x : unit_box) on_faces += (unit_half - x.cwiseAbs()).minCoeff() < 1e-9;
  ASSERT_GT(on_faces, 0u);
  const size_t unit_count = loadText(dir, solidScene("{shape: mesh, mesh: unit.obj}")).solids[0].count;
  EXPECT_LE(unit_count, unit_box.size());
  EXPECT_GE(unit_count, unit_box.size() - on_faces);
  // A scale: the unit cube mesh scaled by 1.03 is the first cube.
  EXPECT_EQ(loadText(dir, solidScene("{shape: mesh, mesh: unit.obj, scale: 1.03}")).solids[0].count,
            box.size());
  EXPECT_EQ(
      loadText(dir, solidScene("{shape: mesh, mesh: unit.obj, scale: [1.03, 1.03, 1.03]}")).solids[0].count,
      box.size());
}

TEST(SphSceneMesh, IcosphereMatchesTheExactWindingNumberSampling) {
  // The scene samples with a hierarchical (far-field) winding number; the exact one of sampleLatticeMesh
  // must give the same points (a closed mesh, its bounds centred at the origin).
  const std::string dir = tempDir("ico");
  const TriangleMesh sphere = icosphere(0.73, 3);  // 1280 triangles
  writeFile(dir + "/ico.obj", meshObj(sphere));
  const SphScene scene = loadText(dir, solidScene("{shape: mesh, mesh: ico.obj}"));
  TriangleMesh centred = sphere;
  Vec3 lo = centred.vertices.positions[0], hi = lo;
  for (const Vec3& x : centred.vertices.positions) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  for (Vec3& x : centred.vertices.positions) x -= 0.5 * (lo + hi);
  const std::vector<Vec3> exact = sampleLatticeMesh(SphLattice(3, 0.1), centred, SphLatticeFrame());
  ASSERT_EQ(scene.particles.size(), exact.size());
  for (size_t i = 0; i < exact.size(); ++i)
    EXPECT_LT((scene.particles.positions[i] - (exact[i] + 0.5 * (lo + hi))).norm(), 1e-12) << i;
  // Count vs. volume: the points in a body of volume V number V / cell up to the boundary layer.
  const double cell = SphLattice(3, 0.1).cellVolume();
  EXPECT_NEAR(double(exact.size()) * cell, 4.0 / 3.0 * M_PI * std::pow(0.73, 3), 0.1);
}

TEST(SphSceneMesh, MeshSkinIsThePlacedMesh) {
  const std::string dir = tempDir("skin");
  writeFile(dir + "/unit.obj", cubeObj(1.0));
  const std::string yaml =
      "dimension: 3\nspacing: 0.1\nenable: [elasticity, skin]\n"
      "solver: {smoothing_ratio: 2.0, rest_density: 1, stiffness: 20}\n"
      "solids:\n  - {shape: mesh, mesh: unit.obj, scale: 1.03, translation: [0, 2, 0],"
      " rotation: {axis: [0, 0, 1], angle: 30}, skin: {mesh: same}}\n"
      "frames: {count: 1, time: 0.01}\n";
  const SphScene scene = loadText(dir, yaml);
  ASSERT_EQ(scene.skins.size(), 1u);
  const std::vector<Vec3>& v = scene.skins[0].rest.vertices.positions;
  ASSERT_EQ(v.size(), 8u);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(M_PI / 6, Vec3::UnitZ()).toRotationMatrix();
  for (int k = 0; k < 8; ++k) {
    const Vec3 corner((k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5);
    EXPECT_LT((v[k] - (Vec3(0, 2, 0) + r * (1.03 * corner))).norm(), 1e-12) << k;
  }
  EXPECT_EQ(scene.skins[0].rest.triangles.size(), 12u);
}

TEST(SphSceneMesh, BadMeshSolidsAreRejectedNamingFileAndKey) {
  const std::string dir = tempDir("bad");
  const std::string path = dir + "/scene.yaml";
  auto expectError = [&](const std::string& solid, const std::vector<std::string>& words) {
    const std::string message = loadError(dir, solidScene(solid));
    EXPECT_EQ(message.rfind(path + ":6:", 0), 0u) << message;  // the solid's line
    for (const std::string& w : words)
      EXPECT_NE(message.find(w), std::string::npos) << w << " in: " << message;
  };
  expectError("{shape: mesh, mesh: missing.obj}", {"solids[0].mesh", dir + "/missing.obj", "does not exist"});
  expectError("{shape: mesh, mesh: cube.stl}", {"solids[0].mesh", "cube.stl", "not an OBJ, PLY or OFF"});
  expectError("{shape: mesh}", {"solids[0]", "mesh"});
  // Two cubes of 0.05 m at x = +-1: no lattice point of spacing 0.19 (x coordinates: multiples of 0.095)
  // lies inside, and the bounds centre (a lattice point) lies between them.
  writeFile(
      dir + "/pair.obj", cubeObj(0.05, Vec3(-1, 0, 0)) + [] {
        std::string second = cubeObj(0.05, Vec3(1, 0, 0)), out;
        // Shift the second cube's face indices by 8.
        size_t pos = 0;
        while (pos < second.size()) {
          const size_t end = second.find('\n', pos);
          std::string line = second.substr(pos, end - pos);
          if (line[0] == 'f') {
            int a, b, c;
            std::sscanf(line.c_str(), "f %d %d %d", &a, &b, &c);
            line = "f " + std::to_string(a + 8) + " " + std::to_string(b + 8) + " " + std::to_string(c + 8);
          }
          out += line + "\n";
          pos = end + 1;
        }
        return out;
      }());
  expectError("{shape: mesh, mesh: pair.obj, spacing: 0.19}",
              {"solids[0].mesh", "pair.obj", "no lattice point"});
  writeFile(dir + "/unit.obj", cubeObj(1.0));
  expectError("{shape: mesh, mesh: unit.obj, radius: 1}", {"solids[0]", "unknown key 'radius'"});
  expectError("{shape: box, lo: [0, 0, 0], hi: [1, 1, 1], scale: 2}", {"solids[0]", "unknown key 'scale'"});
  expectError("{shape: mesh, mesh: unit.obj, scale: -1}", {"solids[0].scale"});
  expectError("{shape: mesh, mesh: unit.obj, scale: [1, 0, 1]}", {"solids[0].scale"});
  expectError("{shape: cone}", {"solids[0].shape", "unknown shape 'cone'", "mesh"});
  // 2D scenes have no mesh solids.
  const std::string message = loadError(
      dir,
      "dimension: 2\nspacing: 0.1\nenable: [elasticity]\nsolver: {smoothing_ratio: 2.0, rest_density: 1}\n"
      "solids:\n  - {shape: mesh, mesh: unit.obj}\nframes: {count: 1, time: 0.01}\n");
  EXPECT_NE(message.find("solids[0].shape: mesh needs a 3D scene"), std::string::npos) << message;
  // skin: {mesh: same} only for mesh solids.
  const std::string skin_message = loadError(
      dir,
      "dimension: 3\nspacing: 0.1\nenable: [elasticity, skin]\nsolver: {smoothing_ratio: 2.0}\n"
      "solids:\n  - {lo: [0, 0, 0], hi: [1, 1, 1], skin: {mesh: same}}\nframes: {count: 1, time: 0.01}\n");
  EXPECT_NE(skin_message.find("solids[0].skin.mesh: 'same' needs a solid of shape mesh"), std::string::npos)
      << skin_message;
}

/// Mass-weighted centre and velocity of the particles of `phase`.
void centreOfMass(const SphParticles& p, uint8_t phase, Vec3* x, Vec3* v) {
  double m = 0.0;
  x->setZero();
  v->setZero();
  for (size_t i = 0; i < p.size(); ++i)
    if (p.phases[i] == phase) {
      m += p.masses[i];
      *x += p.masses[i] * p.positions[i];
      *v += p.masses[i] * p.velocities[i];
    }
  *x /= m;
  *v /= m;
}

TEST(SphSceneMesh, MeltingBunnySceneLoadsAndConservesMass) {
  const std::string bunny = std::string(RC_SHARED_DATA_DIR) + "/bunny.ply";
  if (!fs::exists(bunny)) GTEST_SKIP() << "needs ../shared/data: " << bunny << " is missing";
  const SphScene scene = loadSphScene(kSceneDir + "fig8_4_melting_bunny.yaml");
  ASSERT_EQ(scene.solids.size(), 1u);
  const size_t n = scene.solids[0].count;
  EXPECT_NEAR(double(n), 9871.0, 0.05 * 9871.0);  // Table 8.1
  EXPECT_EQ(n, scene.particles.size());
  EXPECT_TRUE(scene.thermal.enabled && scene.thermal.config.melting);
  // The interior is filled: the particles fill the volume V of the placed scan (divergence theorem; its
  // small holes in the base hardly change it) up to the boundary layer: the lattice points within half a
  // spacing of the surface of area A number about A (d / 2) / cell, a bound on |n cell - V| / cell.
  const YAML::Node solid = YAML::LoadFile(kSceneDir + "fig8_4_melting_bunny.yaml")["solids"][0];
  const double scale = solid["scale"].as<double>();
  const TriangleMesh mesh = readMesh(bunny);
  double volume = 0.0, area = 0.0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 a = scale * mesh.vertices.positions[t[0]], b = scale * mesh.vertices.positions[t[1]],
               c = scale * mesh.vertices.positions[t[2]];
    volume += a.dot(b.cross(c)) / 6.0;
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  const double d = scene.solids[0].elastic.lattice_spacing;
  const double cell = SphLattice(3, d).cellVolume();
  EXPECT_LT(std::abs(double(n) - volume / cell), area * d / 2 / cell);
  // The count is stable: the mesh is sampled around its bounds centre in the solid's frame, so translation
  // and rotation change nothing; a slightly larger scale moves the mesh against the lattice: the count
  // follows the volume, (8.45 / 8.4)^3, up to a reshuffled boundary layer, a few times the square root of
  // the number of boundary points A / (sqrt(3) / 2 d^2) (random rounding).
  std::ifstream in(kSceneDir + "fig8_4_melting_bunny.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string key = "scale: " + solid["scale"].as<std::string>();
  ASSERT_NE(text.find(key), std::string::npos);
  text.replace(text.find(key), key.size(), "scale: " + std::to_string(scale * 8.45 / 8.4));
  const size_t scaled = parseSphScene(text, kSceneDir + "scaled.yaml").solids[0].count;
  const double expected_scaled = double(n) * std::pow(8.45 / 8.4, 3);
  const double boundary_points = area / (std::sqrt(3.0) / 2 * d * d);
  EXPECT_LT(std::abs(double(scaled) - expected_scaled), 3.0 * std::sqrt(boundary_points)) << scaled;
  std::printf(
      "bunny: %zu particles (scaled by 8.45 / 8.4: %zu, volume ratio %.0f), V / cell %.0f, boundary "
      "points %.0f\n",
      n, scaled, expected_scaled, volume / cell, boundary_points);
  SphFluidSolver solver = makeSphSolver(scene);
  double mass_before = 0.0;
  for (double m : scene.particles.masses) mass_before += m;
  SphRunOptions options;
  SphScene short_run = scene;
  short_run.frame_count = 1;
  short_run.frame_time = 0.01;  // two or three steps (dt <= max_dt = 0.005)
  const SphRunStats stats = runSphScene(short_run, solver, options);
  EXPECT_TRUE(stats.instability.empty()) << stats.instability;
  EXPECT_GE(stats.steps, 2u);
  EXPECT_TRUE(stats.thermal);
  double mass_after = 0.0;
  for (double m : solver.particles().masses) mass_after += m;
  EXPECT_EQ(solver.particles().size(), scene.particles.size());
  EXPECT_EQ(mass_after, mass_before);
}

TEST(SphSceneMesh, CollidingBlocksBounceApartWithoutInterpenetrating) {
  SphScene scene = loadSphScene(kSceneDir + "colliding_blocks_2d.yaml");
  ASSERT_EQ(scene.solids.size(), 2u);
  ASSERT_TRUE(scene.collisions.enabled);
  EXPECT_EQ(solidCount(scene, 1), 115u);
  EXPECT_EQ(solidCount(scene, 2), 115u);
  SphFluidSolver solver = makeSphSolver(scene);
  const SphParticles& p = solver.particles();
  const double d = scene.solids[0].elastic.lattice_spacing;
  auto momentum = [&] {
    Vec3 total = Vec3::Zero();
    for (size_t i = 0; i < p.size(); ++i) total += p.masses[i] * p.velocities[i];
    return total;
  };
  double total_mass = 0.0, max_speed = 0.0;
  for (size_t i = 0; i < p.size(); ++i) {
    total_mass += p.masses[i];
    max_speed = std::max(max_speed, p.velocities[i].norm());
  }
  const Vec3 momentum_start = momentum();
  Vec3 x1, v1, x2, v2;
  centreOfMass(p, 1, &x1, &v1);
  centreOfMass(p, 2, &x2, &v2);
  EXPECT_LT((v2 - v1).dot(x2 - x1), 0.0);  // approaching
  double min_distance = std::numeric_limits<double>::infinity(), max_momentum_error = 0.0;
  const double end = scene.frame_count * scene.frame_time;
  while (solver.time() < end - 1e-12) {
    solver.step();
    for (size_t i = 0; i < p.size(); ++i)
      if (p.phases[i] == 1)
        for (size_t j = 0; j < p.size(); ++j)
          if (p.phases[j] == 2)
            min_distance = std::min(min_distance, (p.positions[i] - p.positions[j]).norm());
    max_momentum_error = std::max(max_momentum_error, (momentum() - momentum_start).norm());
  }
  centreOfMass(p, 1, &x1, &v1);
  centreOfMass(p, 2, &x2, &v2);
  EXPECT_GT((v2 - v1).dot(x2 - x1), 0.0);  // separating
  EXPECT_LT(v1.x(), 0.0);
  EXPECT_GT(v2.x(), 0.0);
  // They touched: the penalty acts below d, so the closest pair came within d.
  EXPECT_LT(min_distance, d);
  // No particle of one block entered the other: the closest pair of the two blocks stays above half a
  // spacing (inside a block the nearest lattice neighbour is d away, so a particle of the other block
  // between them would be within d / 2 of one of them).
  EXPECT_GT(min_distance, 0.5 * d);
  // Every force between particles (pressure, viscosity, penalty (8.37)) is pairwise antisymmetric and XSPH
  // exchanges velocity symmetrically; the elastic forces of a block sum to zero. With no gravity and no
  // walls the momentum changes only by rounding: relative to the momentum scale M v_max.
  EXPECT_LT(max_momentum_error, 1e-9 * total_mass * max_speed) << max_momentum_error;
  std::printf(
      "colliding blocks: min distance %.4f d, max momentum error %.3g (M v %.3g), steps %llu, centre "
      "distance %.4f, v1 (%.4f, %.4f), v2 (%.4f, %.4f)\n",
      min_distance / d, max_momentum_error, total_mass * max_speed,
      static_cast<unsigned long long>(solver.stepCount()), (x2 - x1).norm(), v1.x(), v1.y(), v2.x(), v2.y());
}

}  // namespace
}  // namespace rc
