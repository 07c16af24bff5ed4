#include "relaxed_connectivity/io/pvd_io.h"

#include <cstdio>
#include <fstream>

#include "relaxed_connectivity/io/io_error.h"

namespace rc {

void writePvd(const std::string& path, const std::vector<PvdEntry>& entries) {
  std::ofstream out(path);
  if (!out) throw IoError(path, "cannot open for writing");
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  char time[32];
  for (const PvdEntry& e : entries) {
    std::snprintf(time, sizeof(time), "%.9g", e.time);
    out << "    <DataSet timestep=\"" << time << "\" part=\"0\" file=\"" << e.file << "\"/>\n";
  }
  out << "  </Collection>\n</VTKFile>\n";
  if (!out) throw IoError(path, "write failed");
}

}  // namespace rc
