// Skins of scene solids (enable: [skin], solid key skin; thesis 8.2.7, (8.38)): the generated box and sphere
// meshes, loading (mesh files, resolution, errors with file and line) and the per-frame skin files of a
// falling, bouncing elastic cube, which must stay on the particles and move with them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "relaxed_connectivity/core/kd_tree.h"
#include "relaxed_connectivity/io/obj_io.h"
#include "relaxed_connectivity/io/ply_io.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"
#include "relaxed_connectivity/sph/sph_scene_run.h"
#include "relaxed_connectivity/sph/sph_skinning.h"
#include "scene_file_test_support.h"

namespace rc {
namespace {

namespace fs = std::filesystem;

fs::path tempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rc_test_sph_scene_skin_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// Enclosed volume (divergence theorem; positive for outward-oriented closed meshes).
double signedVolume(const TriangleMesh& mesh) {
  double v = 0.0;
  const std::vector<Vec3>& x = mesh.vertices.positions;
  for (const Triangle& t : mesh.triangles) v += x[t[0]].dot(x[t[1]].cross(x[t[2]])) / 6.0;
  return v;
}

Vec3 centroid(const std::vector<Vec3>& points) {
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : points) c += p;
  return c / double(points.size());
}

TEST(SphSceneSkin, BoxAndSphereMeshesAreClosedWithTheirCounts) {
  const Vec3 half(0.2, 0.1, 0.3);
  for (int n : {1, 2, 4, 7}) {
    const TriangleMesh box = sphBoxSkinMesh(half, n);
    EXPECT_EQ(box.vertices.size(), size_t(6 * n * n + 2));
    EXPECT_EQ(box.triangles.size(), size_t(12 * n * n));
    EXPECT_EQ(openEdges(box), 0u);
    EXPECT_NEAR(signedVolume(box), 8.0 * half.x() * half.y() * half.z(), 1e-14);
    for (const Vec3& x : box.vertices.positions) {  // on the boundary of the box
      const Vec3 r = x.cwiseAbs().cwiseQuotient(half);
      EXPECT_NEAR(r.maxCoeff(), 1.0, 1e-15);
    }
  }
  const double radius = 0.5, exact = 4.0 / 3.0 * M_PI * radius * radius * radius;
  double last_error = 1.0;
  for (int n : {1, 2, 4, 8}) {
    const TriangleMesh ball = sphSphereSkinMesh(radius, n);
    EXPECT_EQ(ball.vertices.size(), size_t(10 * n * n + 2));
    EXPECT_EQ(ball.triangles.size(), size_t(20 * n * n));
    EXPECT_EQ(openEdges(ball), 0u);
    for (size_t i = 0; i < ball.vertices.size(); ++i) {
      EXPECT_NEAR(ball.vertices.positions[i].norm(), radius, 1e-15);
      EXPECT_NEAR((ball.vertices.normals[i] - ball.vertices.positions[i] / radius).norm(), 0.0, 1e-15);
    }
    // Inscribed: the volume grows towards the sphere's, the error falling about 4x per doubling of n.
    const double error = (exact - signedVolume(ball)) / exact;
    EXPECT_GT(error, 0.0);
    EXPECT_LT(error, 0.6 * last_error);
    last_error = error;
  }
  EXPECT_LT(last_error, 0.01);
  EXPECT_THROW(sphBoxSkinMesh(half, 0), std::invalid_argument);
  EXPECT_THROW(sphSphereSkinMesh(-1.0, 3), std::invalid_argument);
}

// A tilted elastic cube (0.3 m, fcc spacing d = 0.05) dropped 5 cm onto a floor: it lands, squashes and
// bounces within the 8 frames.
std::string cubeScene(const std::string& skin) {
  return "name: skin_cube\n"
         "dimension: 3\n"
         "spacing: 0.05\n"
         "enable: [elasticity, skin]\n"
         "solver: {smoothing_ratio: 2.0, rest_density: 1, stiffness: 20, gamma: 1,\n"
         "         negative_pressure_scale: 0.01, xsph: 0.1, gravity: [0, -9.81, 0]}\n"
         "solids:\n"
         "  - {lo: [-0.15, 0.15, -0.15], hi: [0.15, 0.45, 0.15], model: goal_position, goal_stiffness: "
         "2.0e5,\n"
         "     rotation: {axis: [1, 0, 1], angle: 25}, velocity: [0.5, 0, 0], skin: " +
         skin +
         "}\n"
         "boundary:\n"
         "  box_planes:\n"
         "    - {lo: [-1, 0, -1], hi: [1, 2, 1], restitution: 0.5, friction: 0.2}\n"
         "frames: {count: 8, time: 0.025}\n";
}

struct SkinRun {
  SphScene scene;
  std::vector<std::vector<Vec3>> particles;  ///< the solid's particles at frames 0..8
  std::vector<TriangleMesh> skins;           ///< the skin files of frames 0..8 read back
  SphRunStats stats;
};

SkinRun runCube(const std::string& skin, const std::string& dir_name) {
  SkinRun run;
  run.scene = parseSphScene(cubeScene(skin), "skin_cube.yaml");
  const SphSceneSolid& solid = run.scene.solids.at(0);
  auto solidPositions = [&](const SphParticles& p) {
    return std::vector<Vec3>(p.positions.begin() + solid.first,
                             p.positions.begin() + solid.first + solid.count);
  };
  run.particles.push_back(solidPositions(run.scene.particles));
  const fs::path dir = tempDir(dir_name);
  SphFluidSolver solver = makeSphSolver(run.scene);
  SphRunOptions options;
  options.out_dir = dir.string();
  options.on_frame = [&](const SphFrameReport&) {
    run.particles.push_back(solidPositions(solver.particles()));
  };
  run.stats = runSphScene(run.scene, solver, options);
  for (int frame = 0; frame <= run.scene.frame_count; ++frame) {
    char name[64];
    std::snprintf(name, sizeof(name), "skin_cube_skin0_%04d.obj", frame);
    if (!fs::exists(dir / name)) break;
    run.skins.push_back(readObjMesh((dir / name).string()));
  }
  return run;
}

TEST(SphSceneSkin, CubeSkinStaysOnTheParticlesAndMovesWithThem) {
  const double d = 0.05;
  const SkinRun fitted = runCube("{resolution: 3, ply: true}", "fitted");
  ASSERT_TRUE(fitted.stats.instability.empty()) << fitted.stats.instability;
  ASSERT_EQ(fitted.scene.skins.size(), 1u);
  EXPECT_FALSE(fitted.scene.skins[0].lattice_transforms);
  EXPECT_EQ(fitted.scene.skins[0].every, 1);
  EXPECT_EQ(fitted.scene.skins[0].skin.orphanCount(), 0u);
  // Frames 0..8, OBJ and PLY each, all listed in the run's files.
  ASSERT_EQ(fitted.skins.size(), 9u);
  ASSERT_EQ(fitted.particles.size(), 9u);
  EXPECT_EQ(fitted.stats.files.size(), 18u);
  const TriangleMesh ply = readPlyMesh(fitted.stats.files.back());
  EXPECT_EQ(ply.vertices.size(), 6u * 9u + 2u);
  EXPECT_EQ(fitted.stats.files.back().substr(fitted.stats.files.back().size() - 24),
            "skin_cube_skin0_0008.ply");

  const double rest_volume = 0.3 * 0.3 * 0.3;
  double max_gap = 0.0, max_drift = 0.0, min_volume = 1e9, max_volume = 0.0, lowest_centroid = 1e9;
  Vec3 offset0 = Vec3::Zero();
  for (size_t f = 0; f < fitted.skins.size(); ++f) {
    const TriangleMesh& skin = fitted.skins[f];
    ASSERT_EQ(skin.vertices.size(), 6u * 9u + 2u);  // 3 x 3 quads per face
    ASSERT_EQ(skin.triangles.size(), 12u * 9u);
    EXPECT_EQ(openEdges(skin), 0u);
    // Within about a lattice spacing of the particles: the nearest particle of every skin vertex.
    const KdTree tree(fitted.particles[f]);
    Neighbor nearest;
    for (const Vec3& x : skin.vertices.positions) {
      tree.knn(x, 1, &nearest);
      max_gap = std::max(max_gap, std::sqrt(nearest.sq_dist));
    }
    // The skin's vertex centroid follows the particle centroid.
    const Vec3 offset = centroid(skin.vertices.positions) - centroid(fitted.particles[f]);
    if (f == 0) offset0 = offset;
    max_drift = std::max(max_drift, (offset - offset0).norm());
    const double volume = signedVolume(skin);
    min_volume = std::min(min_volume, volume);
    max_volume = std::max(max_volume, volume);
    lowest_centroid = std::min(lowest_centroid, centroid(fitted.particles[f]).y());
  }
  const Vec3 moved = centroid(fitted.particles.back()) - centroid(fitted.particles.front());
  std::printf(
      "fitted skin: %zu steps, max strain %.3g, particle centroid moved %.3f m (lowest y %.3f), "
      "max vertex-particle gap %.4f m (%.2f d), centroid drift %.2e m (%.3f d), volume %.4f..%.4f "
      "(rest %.4f)\n",
      size_t(fitted.stats.steps), fitted.stats.max_strain, moved.norm(), lowest_centroid, max_gap,
      max_gap / d, max_drift, max_drift / d, min_volume, max_volume, rest_volume);
  EXPECT_GT(moved.norm(), 0.05);             // it moved (fell, slid) ...
  EXPECT_LT(lowest_centroid, 0.3 - 0.04);    // ... and landed
  EXPECT_GT(fitted.stats.max_strain, 0.01);  // and deformed
  EXPECT_NEAR(offset0.norm(), 0.0, 1e-6);    // the cube's skin and lattice are centred alike
  EXPECT_LT(max_gap, d);
  EXPECT_LT(max_drift, 0.1 * d);
  EXPECT_GT(min_volume, 0.9 * rest_volume);
  EXPECT_LT(max_volume, 1.1 * rest_volume);

  // The solid's lattice transforms A_i (8.23) give nearly the same skin.
  const SkinRun lattice = runCube("{resolution: 3, transforms: lattice, every: 4}", "lattice");
  ASSERT_TRUE(lattice.stats.instability.empty()) << lattice.stats.instability;
  EXPECT_TRUE(lattice.scene.skins[0].lattice_transforms);
  ASSERT_EQ(lattice.skins.size(), 1u);  // frame 0 only: frame 4 is skin_cube_skin0_0004.obj
  const fs::path dir = fs::temp_directory_path() / "rc_test_sph_scene_skin_lattice";
  EXPECT_FALSE(fs::exists(dir / "skin_cube_skin0_0001.obj"));
  ASSERT_TRUE(fs::exists(dir / "skin_cube_skin0_0008.obj"));
  EXPECT_EQ(lattice.stats.files.size(), 3u);
  const TriangleMesh last = readObjMesh((dir / "skin_cube_skin0_0008.obj").string());
  double difference = 0.0;
  for (size_t i = 0; i < last.vertices.size(); ++i)
    difference =
        std::max(difference, (last.vertices.positions[i] - fitted.skins.back().vertices.positions[i]).norm());
  std::printf("lattice vs fitted transforms at frame 8: max vertex difference %.4f m (%.3f d)\n", difference,
              difference / d);
  EXPECT_LT(difference, 0.25 * d);
}

TEST(SphSceneSkin, MeshFilesAndSpheresLoadAndBind) {
  const fs::path dir = tempDir("mesh");
  // A ball mesh (world coordinates) inside a sphere solid of radius 0.2 at (0, 0.5, 0); relative path.
  TriangleMesh ball = sphSphereSkinMesh(0.18, 3);
  for (Vec3& x : ball.vertices.positions) x += Vec3(0, 0.5, 0);
  fs::create_directories(dir / "meshes");
  writeObjMesh((dir / "meshes" / "ball.obj").string(), ball);
  const std::string head =
      "dimension: 3\nspacing: 0.05\nenable: [elasticity, skin]\n"
      "solver: {smoothing_ratio: 2.0, stiffness: 20, rest_density: 1}\nframes: {count: 1, time: 0.01}\n"
      "solids:\n  - shape: sphere\n    center: [0, 0.5, 0]\n    radius: 0.2\n";  // lines 1-9
  std::ofstream(dir / "ball.yaml") << head << "    skin: {mesh: meshes/ball.obj, ply: true, obj: false}\n";
  const SphScene scene = loadSphScene((dir / "ball.yaml").string());
  ASSERT_EQ(scene.skins.size(), 1u);
  EXPECT_EQ(scene.skins[0].rest.vertices.size(), ball.vertices.size());
  EXPECT_EQ(scene.skins[0].rest.triangles.size(), ball.triangles.size());
  EXPECT_EQ(scene.skins[0].skin.pointCount(), ball.vertices.size());
  EXPECT_TRUE(scene.skins[0].ply && !scene.skins[0].obj);

  // The sphere's own surface: an icosphere of the solid's radius around its centre.
  const SphScene own = parseSphScene(head + "    skin: {resolution: 2}\n", "own.yaml");
  ASSERT_EQ(own.skins.size(), 1u);
  EXPECT_EQ(own.skins[0].rest.vertices.size(), 42u);
  for (const Vec3& x : own.skins[0].rest.vertices.positions)
    EXPECT_NEAR((x - Vec3(0, 0.5, 0)).norm(), 0.2, 1e-12);

  // A mesh far from the solid: an error at the mesh's line, or bound to the nearest particles.
  TriangleMesh far = ball;
  for (Vec3& x : far.vertices.positions) x += Vec3(2, 0, 0);
  writeObjMesh((dir / "far.obj").string(), far);
  std::ofstream(dir / "far.yaml") << head << "    skin:\n      mesh: far.obj\n";  // line 11
  try {
    loadSphScene((dir / "far.yaml").string());
    ADD_FAILURE() << "an orphan vertex loaded";
  } catch (const SphSceneError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("far.yaml:11:"), std::string::npos) << message;
    EXPECT_NE(message.find("no solid particle within support_radius"), std::string::npos) << message;
  }
  std::ofstream(dir / "near.yaml") << head << "    skin: {mesh: far.obj, orphans: nearest}\n";
  const SphScene nearest = loadSphScene((dir / "near.yaml").string());
  EXPECT_EQ(nearest.skins[0].skin.orphanCount(), far.vertices.size());
}

const std::string kHead =
    "dimension: 3\n"                                                    // 1
    "spacing: 0.05\n"                                                   // 2
    "solver: {smoothing_ratio: 2.0, stiffness: 20, rest_density: 1}\n"  // 3
    "frames: {count: 2, time: 0.01}\n";                                 // 4
const std::string kSolid =
    "solids:\n"                   // 6
    "  - lo: [0, 0, 0]\n"         // 7
    "    hi: [0.2, 0.2, 0.2]\n";  // 8

TEST(SphSceneSkin, BadSkinKeysNameFileAndLine) {
  const std::string on = kHead + "enable: [elasticity, skin]\n" + kSolid;  // skin: line 9
  ASSERT_EQ(parseError(on + "    skin: {resolution: 2}\n"), "");
  expectErrorAt(kHead + "enable: [elasticity]\n" + kSolid + "    skin: {resolution: 2}\n", 9,
                "needs 'skin' in the scene's 'enable' list");
  expectErrorAt(kHead + "enable: [skin]\n" + kSolid + "    skin: {resolution: 2}\n", 5,
                "'skin' needs 'elasticity'");
  expectErrorAt(on, 5, "no solid has a 'skin' key");
  expectErrorAt(on + "    skin:\n      resolutoin: 2\n", 10, "unknown key 'resolutoin'");
  expectErrorAt(on + "    skin:\n      mesh: a.obj\n      resolution: 2\n", 11, "not both");
  expectErrorAt(on + "    skin: {every: 2}\n", 9, "give 'mesh'");
  expectErrorAt(on + "    skin:\n      resolution: 0\n", 10, "resolution");
  expectErrorAt(on + "    skin:\n      resolution: 2\n      transforms: rigid\n", 11,
                "unknown 'rigid' (known: fitted, lattice)");
  expectErrorAt(on + "    skin:\n      resolution: 2\n      orphans: drop\n", 11,
                "unknown 'drop' (known: error, nearest)");
  expectErrorAt(on + "    skin:\n      resolution: 2\n      every: 0\n", 11, "every");
  expectErrorAt(on + "    skin:\n      resolution: 2\n      obj: false\n", 11, "obj and ply are both false");
  expectErrorAt(on + "    skin:\n      mesh: no_such_skin.obj\n", 10, "no_such_skin.obj");
  expectErrorAt(on + "    skin:\n      mesh: points.xyz\n", 10, "not an OBJ, PLY or OFF file");
  // 2D solids have no generated surface.
  expectErrorAt(
      "dimension: 2\nspacing: 0.05\nsolver: {smoothing_ratio: 2.0, stiffness: 20, rest_density: 1}\n"
      "frames: {count: 2, time: 0.01}\nenable: [elasticity, skin]\nsolids:\n"
      "  - {lo: [0, 0], hi: [0.2, 0.2], skin: {resolution: 2}}\n",
      7, "needs a 3D scene");
}

}  // namespace
}  // namespace rc
