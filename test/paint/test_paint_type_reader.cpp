// Paint types: every shipped preset loads; bad keys and values fail with file:line:column.
#include "relaxed_connectivity/paint/paint_type_reader.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

namespace rc {
namespace {

std::string paintDir() {
  return std::string(RC_SOURCE_DIR) + "/config/paint/paints";
}

TEST(PaintTypeReader, EveryShippedPaintLoads) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(paintDir())) {
    if (entry.path().extension() != ".yaml") continue;
    const PaintType p = readPaintType(entry.path().string());
    EXPECT_EQ(p.name, entry.path().stem().string());
    names.insert(p.name);
  }
  EXPECT_EQ(names, (std::set<std::string>{"acrylic", "eraser", "metallic", "oil", "watercolour"}));
  EXPECT_GT(readPaintType(paintDir() + "/watercolour.yaml").diffusion, 0);
  EXPECT_GT(readPaintType(paintDir() + "/oil.yaml").imprint_depth, 0);
  EXPECT_GT(readPaintType(paintDir() + "/metallic.yaml").colour.reflectivity, 0.5);
  EXPECT_TRUE(readPaintType(paintDir() + "/eraser.yaml").eraser);
  // The shipped imprint patterns are at least two paint buffer pixels (the brushes' 0.5 mm skin spacing).
  for (const char* name : {"oil", "acrylic"})
    EXPECT_GE(readPaintType(paintDir() + "/" + name + ".yaml").imprint_spacing, 2 * 5e-4) << name;
}

TEST(PaintType, LoadingTheBrushReplacesItsWetPaintAndTheEraserCarriesNone) {
  const BrushPreset preset;
  const BrushSkeleton skeleton(preset);
  BrushSkin skin(preset, skeleton);
  const PaintType oil = readPaintType(paintDir() + "/oil.yaml");
  loadBrush(skin, oil);
  ASSERT_GT(skin.size(), 10u);
  for (const PaintState& p : skin.paint) {
    EXPECT_EQ(p.wet, oil.colour);
    EXPECT_EQ(p.wet_volume, oil.load_volume);
    EXPECT_EQ(p.optical_density, oil.optical_density);
  }
  loadBrush(skin, readPaintType(paintDir() + "/eraser.yaml"));
  for (const PaintState& p : skin.paint) EXPECT_EQ(p.wet_volume, 0.0);
}

std::string errorOf(const std::string& yaml) {
  try {
    parsePaintType(yaml, "paint.yaml");
  } catch (const PaintTypeError& e) {
    return e.what();
  }
  return "";
}

TEST(PaintTypeReader, BadInputNamesTheLineAndTheProblem) {
  EXPECT_EQ(errorOf("name: a\ndrying_rte: 1\n").rfind("paint.yaml:2:1: ", 0), 0u)
      << errorOf("name: a\ndrying_rte: 1\n");
  EXPECT_NE(errorOf("name: a\ndrying_rte: 1\n").find("drying_rte"), std::string::npos);
  EXPECT_EQ(errorOf("colour: [1.5, 0, 0]\n").rfind("paint.yaml:1:9: ", 0), 0u)
      << errorOf("colour: [1.5, 0, 0]\n");
  EXPECT_EQ(errorOf("transfer_to_brush: -1\n").rfind("paint.yaml:1:20: ", 0), 0u);
  EXPECT_NE(errorOf("reflectivity: 2\n").find("reflectivity"), std::string::npos);
  EXPECT_NE(errorOf("drying: {brighten: 0.1, shine: 1}\n").find("shine"), std::string::npos);
  EXPECT_NE(errorOf("imprint: {depth: 1.0e-4}\n").find("both depth and spacing"), std::string::npos);
  EXPECT_NE(errorOf("eraser: maybe\n").find("eraser"), std::string::npos);
  EXPECT_NE(errorOf("- 1\n").find("a map"), std::string::npos);
  EXPECT_THROW(readPaintType("/nonexistent/paint.yaml"), PaintTypeError);
}

}  // namespace
}  // namespace rc
