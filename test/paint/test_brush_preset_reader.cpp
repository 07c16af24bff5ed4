// Brush presets: every shipped preset loads; bad keys, values and unstable steps fail with file:line.
#include "relaxed_connectivity/paint/brush_preset_reader.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "relaxed_connectivity/paint/brush_skeleton.h"

namespace rc {
namespace {

std::string brushDir() {
  return std::string(RC_SOURCE_DIR) + "/config/paint/brushes";
}

TEST(BrushPresetReader, EveryShippedPresetLoadsAndIsStable) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(brushDir())) {
    if (entry.path().extension() != ".yaml") continue;
    const BrushPreset p = readBrushPreset(entry.path().string());
    EXPECT_EQ(p.name, entry.path().stem().string());
    EXPECT_LT(p.time_step, BrushSkeleton(p).stepLimit()) << entry.path();
    ++count;
  }
  EXPECT_GE(count, 2);
  EXPECT_EQ(readBrushPreset(brushDir() + "/flat.yaml").shape, BrushShape::kFlat);
  EXPECT_EQ(readBrushPreset(brushDir() + "/round.yaml").shape, BrushShape::kRound);
}

std::string errorOf(const std::string& yaml) {
  try {
    parseBrushPreset(yaml, "brush.yaml");
  } catch (const BrushPresetError& e) {
    return e.what();
  }
  return "";
}

TEST(BrushPresetReader, BadInputNamesTheLineAndTheProblem) {
  EXPECT_EQ(errorOf("name: a\nbristle_lenght: 0.02\n").rfind("brush.yaml:2:1: ", 0), 0u)
      << errorOf("name: a\nbristle_lenght: 0.02\n");
  EXPECT_NE(errorOf("name: a\nbristle_lenght: 0.02\n").find("bristle_lenght"), std::string::npos);
  EXPECT_EQ(errorOf("shape: square\n"), "brush.yaml:1:8: shape: unknown 'square' (known: round, flat)");
  EXPECT_EQ(errorOf("mass: -1\n").rfind("brush.yaml:1:7: ", 0), 0u) << errorOf("mass: -1\n");
  EXPECT_EQ(errorOf("segments: 0\n").rfind("brush.yaml:1:11: ", 0), 0u);
  // Skeleton size bounded (its step limit is a dense eigen-problem of 3 x the masses).
  EXPECT_EQ(errorOf("shape: flat\nsegments: 16\nchains: 32\n"),
            "brush.yaml:3:9: chains x segments = 512 bristle masses, more than 128");
  EXPECT_EQ(errorOf("shape: flat\nsegments: 8\nchains: 16\n"), "");
  EXPECT_NE(errorOf("paint_colour: [2, 0, 0]\n").find("paint_colour"), std::string::npos);
  EXPECT_NE(errorOf("split_angle_deg: 180\n").find("(0, 180)"), std::string::npos);
  EXPECT_NE(errorOf("- 1\n").find("a map"), std::string::npos);
  EXPECT_THROW(readBrushPreset("/nonexistent/brush.yaml"), BrushPresetError);
}

TEST(BrushPresetReader, AStiffPresetAboveTheStepLimitIsRefused) {
  const std::string e = errorOf("spring_stiffness: 4000\ntime_step: 1.0e-3\n");
  EXPECT_EQ(e.rfind("brush.yaml:2:12: time_step 0.001 s exceeds the skeleton's explicit step limit", 0), 0u)
      << e;
  EXPECT_NO_THROW(parseBrushPreset("spring_stiffness: 4000\ntime_step: 1.0e-4\n", "ok.yaml"));
  EXPECT_NE(e.find("integrator: implicit_euler"), std::string::npos) << e;
  // The implicit integrator has no step limit: the same stiff preset loads with one step per event.
  const BrushPreset p =
      parseBrushPreset("spring_stiffness: 4000\nintegrator: implicit_euler\ntime_step: 0.0333\n", "ok.yaml");
  EXPECT_EQ(p.integrator, BrushIntegrator::kImplicitEuler);
  EXPECT_EQ(errorOf("integrator: rk4\n"),
            "brush.yaml:1:13: integrator: unknown 'rk4' (known: verlet, implicit_euler)");
}

TEST(BrushPresetReader, StepLimitProblemOfAPresetBuiltInCode) {
  // What paint_model's dynamic_reconfigure checks before rebuilding the brush.
  BrushPreset p;
  const double limit = BrushSkeleton(p).stepLimit();
  p.time_step = 0.5 * limit;
  EXPECT_EQ(brushStepLimitProblem(p), "");
  p.time_step = 2 * limit;
  EXPECT_EQ(brushStepLimitProblem(p).rfind("time_step ", 0), 0u) << brushStepLimitProblem(p);
  EXPECT_NE(brushStepLimitProblem(p).find("explicit step limit"), std::string::npos);
  p.integrator = BrushIntegrator::kImplicitEuler;
  EXPECT_EQ(brushStepLimitProblem(p), "");
}

}  // namespace
}  // namespace rc
