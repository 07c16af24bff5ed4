// Shared by the SPH scene-file tests: the scene folder of the source tree and the parse-error checks.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
#include <utility>

#include "../scene_error_support.h"
#include "relaxed_connectivity/core/triangle_mesh.h"
#include "relaxed_connectivity/sph/sph_scene_reader.h"

namespace rc {

/// config/sph/ of this checkout (with the trailing slash).
inline std::string sphSceneDir() {
  const std::string here = __FILE__;
  return here.substr(0, here.rfind("/test/")) + "/config/sph/";
}

/// The loader's message for `yaml` read as "bad.yaml" (empty if it loads).
inline std::string parseError(const std::string& yaml) {
  return test::sceneParseError<SphSceneError>([&] { parseSphScene(yaml, "bad.yaml"); });
}

/// The message starts with "bad.yaml:<line>:" and contains `words`.
inline void expectErrorAt(const std::string& yaml, int line, const std::string& words) {
  test::expectMessageAt(parseError(yaml), "bad.yaml", line, words);
}

/// Edges used by other than exactly two triangles (0 for a closed manifold mesh).
inline size_t openEdges(const TriangleMesh& mesh) {
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  size_t open = 0;
  for (const auto& e : edges) open += e.second != 2;
  return open;
}

}  // namespace rc
