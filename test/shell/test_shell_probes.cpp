// Probes of dynamic shell scenes (key probes): a sheet hanging from a pinned edge under gravity, damped to
// rest: the first row has no motion and the pins carry only their own weight; at rest the pins carry the
// whole sheet's weight (their reaction, sum over pinned nodes of dE/dx - m g, is -M g), the lower edge has
// sagged and the momentum has died away. A free fall's momentum is -M g t. Bad probes are named with their
// line.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "../csv_test_support.h"
#include "../scene_error_support.h"
#include "relaxed_connectivity/shell/shell_scene_reader.h"
#include "relaxed_connectivity/shell/shell_scene_run.h"

namespace rc {
namespace {

const std::string kHanging =
    "name: hanging\n"
    "source:\n"
    "  sheet: {size: [1, 1], spacing: 0.02}\n"
    "nodes: {spacing: 0.1}\n"
    "material: {stretch_stiffness: 100, bending_stiffness: 1, density: 1, damping: 4}\n"
    "dynamics: {time_step: auto, gravity: [0, -1, 0]}\n"
    "pins:\n"
    "  - {lo: [-0.5, 0.44, -1], hi: [0.5, 0.5, 1]}\n"
    "frames: {count: 30, time: 0.2}\n"
    "output: {every: 0}\n"
    "probes:\n"
    "  - {name: top, lo: [-0.5, 0.44, -1], hi: [0.5, 0.5, 1]}\n"
    "  - {name: bottom, lo: [-0.5, -0.5, -1], hi: [0.5, -0.44, 1]}\n";

struct Table {
  std::vector<std::vector<std::string>> rows;
  double at(size_t row, const std::string& name) const {
    for (size_t c = 0; c < rows[0].size(); ++c)
      if (rows[0][c] == name) return std::stod(rows[row][c]);
    ADD_FAILURE() << "no column " << name;
    return 0.0;
  }
};

Table runWithProbes(const std::string& yaml, const std::string& name) {
  const std::string dir = ::testing::TempDir() + "shell_probes_" + name;
  std::filesystem::remove_all(dir);
  ShellRunOptions options;
  options.out_dir = dir;
  const ShellRunStats stats = runShellScene(parseShellScene(yaml, name + ".yaml"), options);
  EXPECT_TRUE(stats.instability.empty()) << stats.instability;
  std::ifstream csv(dir + "/" + name + "_probes.csv");
  return Table{test::readCsvRows(csv)};
}

TEST(ShellProbes, APinnedEdgeCarriesTheHangingSheet) {
  const Table t = runWithProbes(kHanging, "hanging");
  ASSERT_EQ(t.rows.size(), 1u + 31u);  // header, the start, 30 frames
  ASSERT_EQ(t.rows[0].size(), 9u + 2u * 9u);
  ShellSimulation sim(parseShellScene(kHanging, "hanging.yaml"));
  double total_mass = 0.0;
  for (double m : sim.solver().energy().masses()) total_mass += m;
  EXPECT_NEAR(t.at(1, "mass"), total_mass, 1e-12 * total_mass);
  const double top_mass = t.at(1, "top_mass");
  EXPECT_GE(t.at(1, "top_nodes"), 3.0);
  EXPECT_EQ(t.at(1, "kinetic_energy"), 0.0);
  EXPECT_NEAR(t.at(1, "top_reaction_y"), top_mass, 1e-12);  // at rest, only the pins' own weight: -m g
  const size_t last = t.rows.size() - 1;
  std::printf(
      "after %.1f s: top reaction y %.5f (sheet weight %.5f), bottom sag %.4f, kinetic %.2e, momentum "
      "y %.2e\n",
      t.at(last, "time"), t.at(last, "top_reaction_y"), total_mass, -t.at(last, "bottom_uy"),
      t.at(last, "kinetic_energy"), t.at(last, "momentum_y"));
  EXPECT_NEAR(t.at(last, "top_reaction_y"), total_mass, 0.01 * total_mass);
  EXPECT_NEAR(t.at(last, "top_reaction_x"), 0.0, 1e-3 * total_mass);
  EXPECT_LT(t.at(last, "bottom_uy"), 0.0);  // sagged
  EXPECT_EQ(t.at(last, "top_max_u"), 0.0);  // pinned
  EXPECT_LT(t.at(last, "kinetic_energy"), 1e-6 * t.at(last, "membrane_energy"));
  EXPECT_GT(t.at(last, "membrane_energy"), 0.0);
}

TEST(ShellProbes, AFreeFallsMomentumIsMinusMgt) {
  std::string yaml = kHanging;
  yaml.replace(yaml.find("pins:"), yaml.find("frames:") - yaml.find("pins:"), "");
  yaml.replace(yaml.find("damping: 4"), 10, "damping: 0");
  yaml.replace(yaml.find("count: 30"), 9, "count: 3");
  yaml.replace(yaml.find("name: hanging"), 13, "name: falling");
  const Table t = runWithProbes(yaml, "falling");
  ASSERT_EQ(t.rows.size(), 1u + 4u);
  ShellSimulation sim(parseShellScene(yaml, "falling.yaml"));
  double total_mass = 0.0;
  for (double m : sim.solver().energy().masses()) total_mass += m;
  for (size_t r = 1; r < t.rows.size(); ++r) {
    EXPECT_NEAR(t.at(r, "momentum_y"), -total_mass * t.at(r, "time"), 1e-9 * total_mass) << r;
    EXPECT_EQ(t.at(r, "top_reaction_y"), 0.0);            // nothing pinned
    EXPECT_NEAR(t.at(r, "membrane_energy"), 0.0, 1e-20);  // falls undeformed
  }
}

TEST(ShellProbes, HeldComponentsAndLoadsInADynamicRun) {
  // No pins: every node holds z (a sheet on a frictionless table), gravity pulls along -z, a constant load of
  // 0.5 along +x acts on the right edge: nothing leaves the plane, and (no damping, nothing held along x) the
  // momentum along x is 0.5 t exactly (Verlet integrates a constant force exactly).
  std::string yaml = kHanging;
  yaml.replace(yaml.find("pins:"), yaml.find("frames:") - yaml.find("pins:"),
               "held:\n  - {lo: [-1, -1, -1], hi: [1, 1, 1], components: z}\n"
               "loads:\n  - {lo: [0.44, -0.5, -1], hi: [0.5, 0.5, 1], force: [0.5, 0, 0]}\n");
  yaml.replace(yaml.find("damping: 4"), 10, "damping: 0");
  yaml.replace(yaml.find("gravity: [0, -1, 0]"), 19, "gravity: [0, 0, -1]");
  yaml.replace(yaml.find("count: 30"), 9, "count: 5");
  yaml.replace(yaml.find("name: hanging"), 13, "name: table");
  yaml += "  - {name: all, lo: [-1, -1, -1], hi: [1, 1, 1]}\n";
  const Table t = runWithProbes(yaml, "table");
  ASSERT_EQ(t.rows.size(), 1u + 6u);
  for (size_t r = 1; r < t.rows.size(); ++r) {
    const double time = t.at(r, "time");
    EXPECT_EQ(t.at(r, "all_uz"), 0.0) << time;  // held exactly, gravity or not
    EXPECT_EQ(t.at(r, "momentum_z"), 0.0) << time;
    EXPECT_NEAR(t.at(r, "momentum_x"), 0.5 * time, 1e-9) << time;
    if (r > 1) {
      EXPECT_GT(t.at(r, "all_ux"), 0.0);
    }
  }
}

TEST(ShellProbes, BadProbesAreNamedWithTheirLine) {
  const std::string head = kHanging.substr(0, kHanging.find("probes:"));  // 10 lines
  auto errorOf = [](const std::string& yaml) {
    return test::sceneParseError<ShellSceneError>([&] { parseShellScene(yaml, "bad.yaml"); });
  };
  test::expectMessageAt(errorOf(head + "probes:\n  - {name: a b, lo: [0, 0, 0], hi: [1, 1, 1]}\n"),
                        "bad.yaml", 12, "'a b' (letters, digits and _");
  test::expectMessageAt(
      errorOf(head + "probes:\n  - {name: a, lo: [0, 0, 0], hi: [1, 1, 1]}\n  - {name: a, lo: "
                     "[0, 0, 0], hi: [1, 1, 1]}\n"),
      "bad.yaml", 13, "'a' is taken");
  test::expectMessageAt(errorOf(head + "probes:\n  - {name: a, lo: [5, 5, 5], hi: [6, 6, 6]}\n"), "bad.yaml",
                        12, "holds no surfel");
  test::expectMessageAt(errorOf(head + "probes:\n  - {name: a, lo: [0, 0, 0], hi: [1, 1, 1], what: 1}\n"),
                        "bad.yaml", 12, "unknown key 'what'");
}

}  // namespace
}  // namespace rc
