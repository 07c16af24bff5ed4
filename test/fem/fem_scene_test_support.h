// Shared by the FEM scene tests: the message of parsing YAML text as "bad.yaml", an expectation that it names
// a line and contains some words, and a run's probe CSV.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../csv_test_support.h"
#include "../scene_error_support.h"
#include "relaxed_connectivity/fem/fem_scene_reader.h"
#include "relaxed_connectivity/fem/fem_scene_run.h"

namespace rc {

/// The error of parsing `yaml` as "bad.yaml" ("" if it parses).
inline std::string femSceneParseError(const std::string& yaml) {
  return test::sceneParseError<FemSceneError>([&] { parseFemScene(yaml, "bad.yaml"); });
}

/// Parsing `yaml` fails with "bad.yaml:<line>:..." containing `words`.
inline void expectFemSceneErrorAt(const std::string& yaml, int line, const std::string& words) {
  test::expectMessageAt(femSceneParseError(yaml), "bad.yaml", line, words);
}

/// Runs the scene with its output in a fresh temporary folder `folder` and returns the rows of its
/// <name>_probes.csv (header first; none when the run fails, with the failure reported).
inline std::vector<std::vector<std::string>> runFemSceneProbes(const FemScene& scene,
                                                               const std::string& folder) {
  const std::string dir = ::testing::TempDir() + folder;
  std::filesystem::remove_all(dir);
  FemRunOptions options;
  options.out_dir = dir;
  const FemRunStats stats = runFemScene(scene, options);
  if (!stats.error.empty()) {
    ADD_FAILURE() << stats.error;
    return {};
  }
  std::ifstream csv(dir + "/" + scene.name + "_probes.csv");
  return test::readCsvRows(csv);
}

}  // namespace rc
