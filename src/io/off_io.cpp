#include "relaxed_connectivity/io/off_io.h"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "relaxed_connectivity/io/file_bytes.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/scalar_codec.h"
#include "relaxed_connectivity/io/text_lines.h"

namespace rc {

namespace {

std::string lineWhere(const LineReader& lines) {
  return "line " + std::to_string(lines.lineNumber());
}

// Next line with tokens (comments and blank lines skipped); false at the end of the file.
bool nextTokens(LineReader* lines, std::vector<std::string_view>* tokens) {
  std::string_view line;
  while (lines->next(&line)) {
    splitTokens(stripComment(line), tokens);
    if (!tokens->empty()) return true;
  }
  return false;
}

bool isIntegerToken(std::string_view token) {
  return token.find_first_of(".eEnN") == std::string_view::npos;
}

}  // namespace

TriangleMesh readOffMesh(const std::string& path, const ReadOptions& options) {
  const std::string bytes = readFileBytes(path);
  LineReader lines(bytes);
  std::vector<std::string_view> tokens;
  if (!nextTokens(&lines, &tokens)) throw IoError(path, "header", "empty file");
  const std::string_view keyword = tokens[0];
  if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF")
    throw IoError(path, lineWhere(lines), "not an OFF file (header '" + std::string(keyword) + "')");
  bool has_colors = false, has_normals = false;
  for (char c : keyword.substr(0, keyword.size() - 3)) {
    if (c == 'C')
      has_colors = true;
    else if (c == 'N')
      has_normals = true;
    else
      throw IoError(path, lineWhere(lines), "unsupported OFF variant '" + std::string(keyword) + "'");
  }
  tokens.erase(tokens.begin());
  if (tokens.empty() && !nextTokens(&lines, &tokens))
    throw IoError(path, "header", "missing vertex/face counts");
  int64_t vertex_count = -1, face_count = -1;
  if (tokens.size() < 2 || !parseInt64(tokens[0], &vertex_count) || !parseInt64(tokens[1], &face_count) ||
      vertex_count < 0 || face_count < 0)
    throw IoError(path, lineWhere(lines), "malformed vertex/face counts");

  // Counts far beyond what the file can hold are refused before anything is allocated for them (a vertex
  // needs at least "x y z" and a separator, a face "n" and a separator; up to twice that, plus 1024, the
  // reader names the line where the data ends).
  const uint64_t room = bytes.size() + 1;
  if (uint64_t(vertex_count) > 2 * (room / 6) + 1024 || uint64_t(face_count) > 2 * (room / 2) + 1024)
    throw IoError(path, lineWhere(lines),
                  "counts of " + std::to_string(vertex_count) + " vertices and " +
                      std::to_string(face_count) + " faces, but the file has " +
                      std::to_string(bytes.size()) + " bytes");
  TriangleMesh mesh;
  SurfelCloud& cloud = mesh.vertices;
  cloud.positions.resize(vertex_count);
  if (has_normals) cloud.normals.resize(vertex_count);
  if (has_colors) cloud.colors.assign(vertex_count, Rgba{0, 0, 0, 255});
  const size_t color_start = has_normals ? 6 : 3;
  for (int64_t i = 0; i < vertex_count; ++i) {
    if (!nextTokens(&lines, &tokens))
      throw IoError(path, "vertex #" + std::to_string(i),
                    "unexpected end of file (expected " + std::to_string(vertex_count) + " vertices)");
    const std::string where = "vertex #" + std::to_string(i) + " (" + lineWhere(lines) + ")";
    const size_t needed = color_start + (has_colors ? 3 : 0);
    if (tokens.size() < needed)
      throw IoError(path, where,
                    "expected " + std::to_string(needed) + " values, found " + std::to_string(tokens.size()));
    double v[6];
    for (size_t k = 0; k < color_start; ++k)
      if (!parseDouble(tokens[k], &v[k]))
        throw IoError(path, where, "cannot parse '" + std::string(tokens[k]) + "' as a number");
    cloud.positions[i] = Vec3(v[0], v[1], v[2]);
    if (has_normals) cloud.normals[i] = Vec3(v[3], v[4], v[5]);
    if (has_colors) {
      const size_t components = std::min<size_t>(4, tokens.size() - color_start);
      bool integers = true;
      for (size_t k = 0; k < components; ++k) integers = integers && isIntegerToken(tokens[color_start + k]);
      for (size_t k = 0; k < components; ++k) {
        double c;
        if (!parseDouble(tokens[color_start + k], &c))
          throw IoError(path, where, "cannot parse colour '" + std::string(tokens[color_start + k]) + "'");
        if (!integers) c *= 255.0;
        cloud.colors[i][k] = static_cast<uint8_t>(std::lround(std::min(255.0, std::max(0.0, c))));
      }
    }
  }
  mesh.triangles.reserve(face_count);
  std::vector<int64_t> polygon;
  for (int64_t f = 0; f < face_count; ++f) {
    if (!nextTokens(&lines, &tokens))
      throw IoError(path, "face #" + std::to_string(f),
                    "unexpected end of file (expected " + std::to_string(face_count) + " faces)");
    const std::string where = "face #" + std::to_string(f) + " (" + lineWhere(lines) + ")";
    int64_t n = -1;
    if (!parseInt64(tokens[0], &n) || n < 0)
      throw IoError(path, where, "invalid vertex count '" + std::string(tokens[0]) + "'");
    if (tokens.size() < static_cast<size_t>(n) + 1)
      throw IoError(
          path, where,
          "expected " + std::to_string(n) + " vertex indices, found " + std::to_string(tokens.size() - 1));
    polygon.resize(n);
    for (int64_t k = 0; k < n; ++k) {
      if (!parseInt64(tokens[k + 1], &polygon[k]))
        throw IoError(path, where, "cannot parse vertex index '" + std::string(tokens[k + 1]) + "'");
      if (polygon[k] < 0 || polygon[k] >= vertex_count)
        throw IoError(path, where,
                      "vertex index " + std::to_string(polygon[k]) + " out of range [0, " +
                          std::to_string(vertex_count) + ")");
    }
    for (int64_t k = 1; k + 1 < n; ++k)
      mesh.triangles.push_back(
          Triangle{uint32_t(polygon[0]), uint32_t(polygon[k]), uint32_t(polygon[k + 1])});
  }
  applyReadOptions(options, &mesh);
  return mesh;
}

void writeOffMesh(const std::string& path, const TriangleMesh& mesh) {
  const SurfelCloud& cloud = mesh.vertices;
  try {
    cloud.validate();
  } catch (const std::invalid_argument& e) {
    throw IoError(path, e.what());
  }
  const size_t n = cloud.size();
  std::string out = std::string(cloud.hasColors() ? "C" : "") + (cloud.hasNormals() ? "N" : "") + "OFF\n";
  out += std::to_string(n) + " " + std::to_string(mesh.triangles.size()) + " 0\n";
  for (size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      if (a) out += ' ';
      appendDoubleText(cloud.positions[i][a], &out);
    }
    if (cloud.hasNormals())
      for (int a = 0; a < 3; ++a) {
        out += ' ';
        appendDoubleText(cloud.normals[i][a], &out);
      }
    if (cloud.hasColors())
      for (int a = 0; a < 4; ++a) out += " " + std::to_string(cloud.colors[i][a]);
    out += '\n';
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (uint32_t index : tri)
      if (index >= n)
        throw IoError(
            path, "triangle #" + std::to_string(t),
            "vertex index " + std::to_string(index) + " out of range [0, " + std::to_string(n) + ")");
    out += "3 " + std::to_string(tri[0]) + " " + std::to_string(tri[1]) + " " + std::to_string(tri[2]) + "\n";
  }
  writeFileBytes(path, out);
}

}  // namespace rc
