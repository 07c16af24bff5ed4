// Scene-file error checks shared by the FEM scene tests: the message of parsing YAML text as "bad.yaml", and
// an expectation that it names a line and contains some words.
#pragma once

#include <string>

#include "../scene_error_support.h"
#include "relaxed_connectivity/fem/fem_scene_reader.h"

namespace rc {

/// The error of parsing `yaml` as "bad.yaml" ("" if it parses).
inline std::string femSceneParseError(const std::string& yaml) {
  return test::sceneParseError<FemSceneError>([&] { parseFemScene(yaml, "bad.yaml"); });
}

/// Parsing `yaml` fails with "bad.yaml:<line>:..." containing `words`.
inline void expectFemSceneErrorAt(const std::string& yaml, int line, const std::string& words) {
  test::expectMessageAt(femSceneParseError(yaml), "bad.yaml", line, words);
}

}  // namespace rc
