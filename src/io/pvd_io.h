// ParaView collection files (.pvd): a time series of VTK XML files (particles, polyhedral meshes, ...).
#pragma once

#include <string>
#include <vector>

namespace rc {

/// One entry of a ParaView collection: a file (relative to the .pvd) and its simulated time.
struct PvdEntry {
  std::string file;
  double time = 0.0;
};

/// Writes the collection. Throws IoError naming the file when it cannot be written.
void writePvd(const std::string& path, const std::vector<PvdEntry>& entries);

}  // namespace rc
