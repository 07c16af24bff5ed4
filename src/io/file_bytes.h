// Whole-file reading and writing (the readers parse from memory), and extension helpers.
#pragma once

#include <string>

namespace rc {

/// The complete contents of `path`; throws IoError naming the file when it cannot be opened or read.
std::string readFileBytes(const std::string& path);
/// Writes `bytes` to `path` (replacing it); throws IoError on failure.
void writeFileBytes(const std::string& path, const std::string& bytes);
/// Lower-case extension including the dot (".ply"), or "" when there is none.
std::string lowerCaseExtension(const std::string& path);

}  // namespace rc
