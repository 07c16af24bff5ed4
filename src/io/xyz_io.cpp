#include "relaxed_connectivity/io/xyz_io.h"

#include <string_view>

#include "relaxed_connectivity/io/file_bytes.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/scalar_codec.h"
#include "relaxed_connectivity/io/text_lines.h"

namespace rc {

SurfelCloud readXyzCloud(const std::string& path, const ReadOptions& options) {
  const std::string bytes = readFileBytes(path);
  LineReader lines(bytes);
  std::string_view line;
  std::vector<std::string_view> tokens;
  SurfelCloud cloud;
  cloud.positions.reserve(bytes.size() / 24);
  size_t columns = 0;
  while (lines.next(&line)) {
    splitTokens(stripComment(line), &tokens);
    if (tokens.empty()) continue;
    const std::string where = "line " + std::to_string(lines.lineNumber());
    if (columns == 0) {
      if (tokens.size() != 3 && tokens.size() != 6)
        throw IoError(path, where,
                      "expected 3 or 6 values (x y z [nx ny nz]), found " + std::to_string(tokens.size()));
      columns = tokens.size();
    } else if (tokens.size() != columns) {
      throw IoError(path, where,
                    "expected " + std::to_string(columns) + " values like the first point, found " +
                        std::to_string(tokens.size()));
    }
    double v[6];
    for (size_t k = 0; k < columns; ++k)
      if (!parseDouble(tokens[k], &v[k]))
        throw IoError(path, where, "cannot parse '" + std::string(tokens[k]) + "' as a number");
    cloud.positions.emplace_back(v[0], v[1], v[2]);
    if (columns == 6) cloud.normals.emplace_back(v[3], v[4], v[5]);
  }
  applyReadOptions(options, &cloud);
  return cloud;
}

void writeXyzCloud(const std::string& path, const SurfelCloud& cloud) {
  try {
    cloud.validate();
  } catch (const std::invalid_argument& e) {
    throw IoError(path, e.what());
  }
  std::string out;
  out.reserve(cloud.size() * (cloud.hasNormals() ? 100 : 50));
  for (size_t i = 0; i < cloud.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      if (a) out += ' ';
      appendDoubleText(cloud.positions[i][a], &out);
    }
    if (cloud.hasNormals())
      for (int a = 0; a < 3; ++a) {
        out += ' ';
        appendDoubleText(cloud.normals[i][a], &out);
      }
    out += '\n';
  }
  writeFileBytes(path, out);
}

}  // namespace rc
