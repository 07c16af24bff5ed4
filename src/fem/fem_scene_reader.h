// Reading FEM scene files (config/fem/*.yaml) into an FemScene, with errors that name the file, the line and
// the problem.
#pragma once

#include <string>

#include "relaxed_connectivity/fem/fem_scene.h"

namespace rc {

/// Reads a scene file. Throws FemSceneError naming the file, line and problem (syntax, unknown key, wrong
/// type, bad value, a mesh that cannot be built).
FemScene loadFemScene(const std::string& path);
/// Same for YAML text; `source_name` stands for the file name in error messages, relative mesh files are
/// resolved against `base_dir` (empty: the working directory).
FemScene parseFemScene(const std::string& yaml_text, const std::string& source_name,
                       const std::string& base_dir = "");

}  // namespace rc
