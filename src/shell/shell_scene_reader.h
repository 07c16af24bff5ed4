// Reading thin-shell scene files (config/shell/*.yaml) into a ShellScene, with errors that name the file, the
// line and the problem; the surfel source (a surfel or mesh file, or a generated sheet / sphere) is loaded
// here.
#pragma once

#include <string>

#include "relaxed_connectivity/shell/shell_scene.h"

namespace rc {

/// Reads a scene file. Throws ShellSceneError naming the file, line and problem (syntax, unknown key, wrong
/// type, bad value, unreadable surfel file).
ShellScene loadShellScene(const std::string& path);
/// Same for YAML text; `source_name` stands for the file name in error messages and relative file paths
/// are resolved against its folder.
ShellScene parseShellScene(const std::string& yaml_text, const std::string& source_name);

}  // namespace rc
