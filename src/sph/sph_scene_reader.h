// Reading SPH scene files (config/sph/*.yaml) into an SphScene, with errors that name the file, the line and
// the problem. The dispatcher is in sph_scene_reader.cpp, the section readers (solver and particles, solids,
// temperature and sources, outputs) in sph_scene_reader_*.cpp.
#pragma once

#include <string>

#include "relaxed_connectivity/sph/sph_scene.h"

namespace rc {

/// Reads a scene file. Throws SphSceneError naming the file, line and problem (syntax, unknown key, wrong
/// type, bad value, unsupported physics).
SphScene loadSphScene(const std::string& path);
/// Same for YAML text; `source_name` stands for the file name in error messages.
SphScene parseSphScene(const std::string& yaml_text, const std::string& source_name);

}  // namespace rc
