// Save and load of the painted state: save -> load -> save is byte-identical, the loaded surface shows the
// same surfels with the same paint and the same father/child structure, and bad files are named with the
// vertex and the problem.
#include "relaxed_connectivity/paint/painted_surface_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>

#include "paint_test_surfaces.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/ply_io.h"
#include "relaxed_connectivity/paint/paint_transfer.h"

namespace rc {
namespace {

constexpr double kEvent = 1.0 / 30;

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "painted_io_" + name;
}

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// A plane (with colours and radii, or neither) painted by one stroke, with wet paint on some originals.
std::unique_ptr<PaintSurface> paintedPlane(bool colours_and_radii) {
  SurfelCloud plane = paint_test::planeCloud(0.02, 0.001);
  if (colours_and_radii) {
    plane.colors.resize(plane.size());
    for (size_t i = 0; i < plane.size(); ++i) plane.colors[i] = {uint8_t(i % 200), 40, 220, 255};
  } else {
    plane.radii.clear();
  }
  auto surface = std::make_unique<PaintSurface>(std::move(plane));
  for (size_t i = 0; i < surface->originalCount(); i += 3) surface->originalPaint(i).wet_volume = 0.25;
  Brush brush{BrushPreset()};
  const double l = brush.preset().bristle_length;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() =
      Eigen::Quaterniond::FromTwoVectors(Vec3(0, 0, -1), Vec3(-0.5, 0, -std::sqrt(0.75))).toRotationMatrix();
  PaintType paint;
  for (int e = 0; e <= 12; ++e) {
    t.translation() = Vec3(-0.006 + 0.001 * e, 0, l - std::min(1.0, e / 4.0) * 0.004);
    if (e == 0) brush.reset(t);
    brush.advance(kEvent, t, surface.get());
    transferPaint(brush, *surface, paint, kEvent);
  }
  return surface;
}

void expectSameSurfels(const PaintSurface& a, const PaintSurface& b) {
  ASSERT_EQ(a.originalCount(), b.originalCount());
  ASSERT_EQ(a.childCount(), b.childCount());
  for (size_t i = 0; i < a.originalCount(); ++i) {
    ASSERT_EQ(a.enabled(i), b.enabled(i)) << i;
    ASSERT_EQ(a.originalPaint(i), b.originalPaint(i)) << i;
    ASSERT_EQ(a.children(i), b.children(i)) << i;
    ASSERT_EQ(a.originals().positions[i], b.originals().positions[i]) << i;
    ASSERT_EQ(a.originals().normals[i], b.originals().normals[i]) << i;
  }
  EXPECT_EQ(a.originals().hasRadii(), b.originals().hasRadii());
  EXPECT_EQ(a.originals().hasColors(), b.originals().hasColors());
  EXPECT_EQ(a.typicalRadius(), b.typicalRadius());
}

TEST(PaintedSurfaceIo, SaveLoadSaveIsByteIdenticalAndRestoresTheFatherChildStructure) {
  for (bool colours_and_radii : {true, false}) {
    SCOPED_TRACE(colours_and_radii ? "with colours and radii" : "without");
    const auto painted = paintedPlane(colours_and_radii);
    ASSERT_GT(painted->childCount(), 50u);
    const std::string first = tempPath("first.ply"), second = tempPath("second.ply");
    savePaintedSurface(first, *painted);
    std::vector<double> fractions;
    const auto loaded =
        loadPaintedSurface(first, [&](double f, const std::string&) { fractions.push_back(f); });
    ASSERT_GE(fractions.size(), 4u);  // progress: from 0 to 1, never back
    EXPECT_EQ(fractions.front(), 0.0);
    EXPECT_EQ(fractions.back(), 1.0);
    EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
    EXPECT_TRUE(loaded->takeChangedOriginals().empty());
    expectSameSurfels(*painted, *loaded);
    savePaintedSurface(second, *loaded, true);
    const std::string a = fileBytes(first), b = fileBytes(second);
    EXPECT_GT(a.size(), 1000u);
    EXPECT_TRUE(a == b) << "the second save differs (" << a.size() << " vs " << b.size() << " bytes)";
    // The original colours (what the eraser restores) survive.
    for (size_t i = 0; i < painted->originalCount(); i += 97)
      EXPECT_EQ(painted->baseColour(i), loaded->baseColour(i));
  }
}

TEST(PaintedSurfaceIo, BadFilesNameTheVertexAndTheProblem) {
  const auto painted = paintedPlane(true);
  const std::string good = tempPath("good.ply");
  savePaintedSurface(good, *painted);
  SurfelCloud cloud = readPlyCloud(good);
  const auto errorOf = [&](const SurfelCloud& c, const std::string& name) -> std::string {
    const std::string path = tempPath(name);
    WriteOptions o;
    o.double_precision = true;
    writePlyCloud(path, c, o);
    try {
      loadPaintedSurface(path);
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
      return e.what();
    }
    return "no error";
  };
  const size_t last = cloud.size() - 1;
  SurfelCloud bad_father = cloud;
  bad_father.attributes.find(kSurfelFather)->set(last, 1e6);
  EXPECT_NE(errorOf(bad_father, "bad_father.ply").find("#" + std::to_string(last) + ": father"),
            std::string::npos);
  SurfelCloud late_original = cloud;
  late_original.attributes.find(kSurfelKind)->set(last, 0);
  EXPECT_NE(errorOf(late_original, "late.ply").find("after the children"), std::string::npos);
  SurfelCloud no_kind = cloud;
  no_kind.attributes.remove(kSurfelKind);
  EXPECT_NE(errorOf(no_kind, "no_kind.ply").find("not a painted state"), std::string::npos);
  SurfelCloud bad_kind = cloud;
  bad_kind.attributes.find(kSurfelKind)->set(3, 7);
  EXPECT_NE(errorOf(bad_kind, "bad_kind.ply").find("#3: surfel_kind 7"), std::string::npos);
  EXPECT_THROW(loadPaintedSurface(tempPath("missing.ply")), IoError);
}

}  // namespace
}  // namespace rc
