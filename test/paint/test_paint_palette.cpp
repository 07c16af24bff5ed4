// The palette (Fig. 5.1): the shipped palettes load, bad ones name file:line; its surfels carry the wells'
// wet paint; appended to the object, a dry brush dipped into a well loads that paint, a second well mixes
// into it (5.11), and the mixture goes onto the object.
#include "relaxed_connectivity/paint/paint_palette.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "paint_test_surfaces.h"
#include "relaxed_connectivity/paint/paint_attributes.h"
#include "relaxed_connectivity/paint/paint_transfer.h"

namespace rc {
namespace {

std::string paletteDir() {
  return std::string(RC_SOURCE_DIR) + "/config/paint/palettes";
}

TEST(PaintPalette, EveryShippedPaletteLoadsAndBadOnesNameTheLine) {
  size_t loaded = 0;
  for (const auto& entry : std::filesystem::directory_iterator(paletteDir())) {
    if (entry.path().extension() != ".yaml") continue;
    const PaletteSpec p = readPalette(entry.path().string());
    EXPECT_EQ(p.name, entry.path().stem().string());
    EXPECT_FALSE(p.wells.empty());
    ++loaded;
  }
  EXPECT_GE(loaded, 1u);
  const auto errorOf = [](const std::string& yaml) -> std::string {
    try {
      parsePalette(yaml, "p.yaml");
    } catch (const PaletteError& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string well = "  - {position: [0, 0], radius: 0.01, colour: [1, 0, 0]}\n";
  EXPECT_NE(errorOf("size: [0.1, 0.05]\nwells:\n" + well + well).find("p.yaml:4:"), std::string::npos);
  EXPECT_NE(errorOf("size: [0.1, 0.05]\nwells:\n" + well + well).find("overlaps"), std::string::npos);
  EXPECT_NE(errorOf("size: [0.01, 0.05]\nwells:\n" + well).find("does not lie on the board"),
            std::string::npos);
  EXPECT_NE(errorOf("wells:\n  - {position: [0, 0], colour: [2, 0, 0]}\n").find("p.yaml:2:"),
            std::string::npos);
  EXPECT_NE(errorOf("wels: []\n").find("unknown key 'wels'"), std::string::npos);
  EXPECT_NE(errorOf("name: x\n").find("wells"), std::string::npos);
}

PaletteSpec twoWells() {
  PaletteSpec p;
  p.centre = Vec3(0, -0.06, 0);
  p.width = 0.06;
  p.depth = 0.03;
  PaletteWell red, blue;
  red.x = -0.015, blue.x = 0.015;
  red.radius = blue.radius = 0.012;
  red.colour.rgb = Vec3(0.9, 0.05, 0.05);
  blue.colour.rgb = Vec3(0.05, 0.05, 0.9);
  p.wells = {red, blue};
  return p;
}

TEST(PaintPalette, TheBoardCarriesTheWellsWetPaint) {
  const PaletteSpec spec = twoWells();
  SurfelCloud c = makePaletteCloud(spec);
  EXPECT_EQ(c.size(), 61u * 31u);
  ASSERT_TRUE(hasPaintAttributes(c));
  size_t in_wells = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    const PaintState s = readPaint(c, i);
    const double d_red = (c.positions[i] - Vec3(-0.015, -0.06, 0)).norm();
    if (d_red <= 0.012 - 1e-9) {
      EXPECT_EQ(s.wet.rgb, spec.wells[0].colour.rgb);
      EXPECT_EQ(s.wet_volume, 20.0);
    }
    in_wells += s.wet_volume > 0;
    EXPECT_NEAR(s.dry.rgb.x(), 0.85, 1.0 / 255);
  }
  // Two discs of radius 12 mm at 1 mm spacing: about 2 pi 144 surfels.
  EXPECT_NEAR(double(in_wells), 2 * M_PI * 144, 40);
}

Eigen::Isometry3d stylusAt(const Vec3& ferrule) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = ferrule;
  t.linear() = Eigen::Quaterniond::FromTwoVectors(Vec3(0, 0, -1), Vec3(0, 0, -1)).toRotationMatrix();
  return t;
}

/// Lowers the brush 4 mm into the surface at (x, y) and lifts it again, transferring paint each event.
void dab(Brush& brush, PaintSurface& surface, const PaintType& paint, double x, double y) {
  const double l = brush.preset().bristle_length, dt = 1.0 / 30;
  brush.reset(stylusAt(Vec3(x, y, l + 0.002)));
  for (int e = 0; e <= 30; ++e) {
    const double lower = 0.006 * std::min(1.0, std::min(e, 30 - e) / 8.0);
    brush.advance(dt, stylusAt(Vec3(x, y, l + 0.002 - lower)), &surface);
    transferPaint(brush, surface, paint, dt);
  }
}

Vec3 brushColour(const Brush& brush) {
  Vec3 sum = Vec3::Zero();
  double v = 0;
  for (const PaintState& p : brush.skin().paint) sum += p.wet_volume * p.wet.rgb, v += p.wet_volume;
  return v > 0 ? Vec3(sum / v) : Vec3::Zero();
}

TEST(PaintPalette, ADryBrushLoadsFromAWellMixesInASecondAndPaintsTheMixture) {
  SurfelCloud object = paint_test::planeCloud(0.03, 0.001);
  const size_t first = appendPalette(object, twoWells());
  EXPECT_EQ(first, 61u * 61u);
  PaintSurface surface(object);
  Brush brush{BrushPreset()};
  PaintType paint;  // takes up paint from the palette as well as it gives
  paint.transfer_to_brush = 4.0;
  paint.eraser = true;  // loadBrush: a clean, dry brush
  loadBrush(brush.skin(), paint);
  paint.eraser = false;
  dab(brush, surface, paint, -0.015, -0.06);  // the red well
  double load = 0;
  for (const PaintState& p : brush.skin().paint) load += p.wet_volume;
  EXPECT_GT(load, 1.0);
  const Vec3 red = brushColour(brush);
  EXPECT_LT((red - Vec3(0.9, 0.05, 0.05)).norm(), 1e-9);
  dab(brush, surface, paint, 0.015, -0.06);  // the blue well mixes in
  const Vec3 mixed = brushColour(brush);
  EXPECT_GT(mixed.x(), 0.2);
  EXPECT_GT(mixed.z(), 0.2);
  EXPECT_NEAR(mixed.x() + mixed.z(), 0.95, 1e-9);  // a volume-weighted mix of the two (5.11)
  // On the object (z = 0 plane away from the palette) the mixture is deposited.
  dab(brush, surface, paint, 0.0, 0.01);
  double deposited = 0;
  for (size_t i = 0; i < first; ++i)
    for (const ChildSurfel& c : surface.children(i))
      if (c.paint.wet_volume > 0) {
        deposited += c.paint.wet_volume;
        EXPECT_GT(c.paint.wet.rgb.x(), 0.1);
        EXPECT_GT(c.paint.wet.rgb.z(), 0.1);
      }
  EXPECT_GT(deposited, 0.01);
}

}  // namespace
}  // namespace rc
