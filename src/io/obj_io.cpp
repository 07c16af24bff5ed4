#include "relaxed_connectivity/io/obj_io.h"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "relaxed_connectivity/io/file_bytes.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/scalar_codec.h"
#include "relaxed_connectivity/io/text_lines.h"

namespace rc {

namespace {

// Resolves a 1-based (or negative, relative) OBJ index against `count` defined items; -1 if invalid.
int64_t resolveIndex(int64_t index, size_t count) {
  const int64_t resolved = index > 0 ? index - 1 : static_cast<int64_t>(count) + index;
  return index != 0 && resolved >= 0 && resolved < static_cast<int64_t>(count) ? resolved : -1;
}

uint8_t colorByte(double c) {
  return static_cast<uint8_t>(std::lround(std::min(1.0, std::max(0.0, c)) * 255.0));
}

}  // namespace

TriangleMesh readObjMesh(const std::string& path, const ReadOptions& options) {
  const std::string bytes = readFileBytes(path);
  LineReader lines(bytes);
  std::string_view line;
  std::vector<std::string_view> tokens;
  TriangleMesh mesh;
  SurfelCloud& cloud = mesh.vertices;
  std::vector<Rgba> colors;
  size_t colored = 0;
  std::vector<Vec3> normals;
  std::vector<int64_t> vertex_normal;  // index into normals per vertex, -1 if none
  std::vector<int64_t> polygon;
  while (lines.next(&line)) {
    splitTokens(stripComment(line), &tokens);
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    const auto where = [&] { return "line " + std::to_string(lines.lineNumber()); };
    if (keyword == "v" || keyword == "vn") {
      const size_t values = tokens.size() - 1;
      const bool vertex = keyword == "v";
      if (vertex ? (values < 3 || values > 7) : values != 3)
        throw IoError(path, where(),
                      std::string(vertex ? "'v' needs 3 to 7 values" : "'vn' needs 3 values") + ", found " +
                          std::to_string(values));
      double v[7];
      for (size_t k = 0; k < values; ++k)
        if (!parseDouble(tokens[k + 1], &v[k]))
          throw IoError(path, where(), "cannot parse '" + std::string(tokens[k + 1]) + "' as a number");
      if (!vertex) {
        normals.emplace_back(v[0], v[1], v[2]);
        continue;
      }
      cloud.positions.emplace_back(v[0], v[1], v[2]);
      vertex_normal.push_back(-1);
      if (values >= 6) {  // x y z r g b [a]
        colors.push_back(Rgba{colorByte(v[3]), colorByte(v[4]), colorByte(v[5]),
                              values == 7 ? colorByte(v[6]) : uint8_t(255)});
        ++colored;
      } else {
        colors.push_back(Rgba{0, 0, 0, 255});
      }
    } else if (keyword == "f") {
      if (tokens.size() < 4) throw IoError(path, where(), "a face needs at least 3 vertices");
      polygon.clear();
      for (size_t k = 1; k < tokens.size(); ++k) {
        const std::string_view corner = tokens[k];
        const size_t slash = corner.find('/');
        int64_t index;
        if (!parseInt64(corner.substr(0, slash), &index))
          throw IoError(path, where(), "malformed face corner '" + std::string(corner) + "'");
        const int64_t vertex = resolveIndex(index, cloud.positions.size());
        if (vertex < 0)
          throw IoError(path, where(),
                        "vertex index " + std::to_string(index) + " out of range (" +
                            std::to_string(cloud.positions.size()) + " vertices defined)");
        polygon.push_back(vertex);
        const size_t second = slash == std::string_view::npos ? slash : corner.find('/', slash + 1);
        if (second != std::string_view::npos && second + 1 < corner.size()) {
          int64_t normal_index;
          if (!parseInt64(corner.substr(second + 1), &normal_index))
            throw IoError(path, where(), "malformed face corner '" + std::string(corner) + "'");
          const int64_t normal = resolveIndex(normal_index, normals.size());
          if (normal < 0)
            throw IoError(path, where(),
                          "normal index " + std::to_string(normal_index) + " out of range (" +
                              std::to_string(normals.size()) + " normals defined)");
          vertex_normal[vertex] = normal;
        }
      }
      for (size_t k = 1; k + 1 < polygon.size(); ++k)
        mesh.triangles.push_back(
            Triangle{uint32_t(polygon[0]), uint32_t(polygon[k]), uint32_t(polygon[k + 1])});
    }
    // vt, vp, g, o, s, usemtl, mtllib, l, p, ...: not geometry of a triangle mesh
  }
  const size_t n = cloud.positions.size();
  if (!normals.empty()) {
    const bool complete =
        std::all_of(vertex_normal.begin(), vertex_normal.end(), [](int64_t k) { return k >= 0; });
    if (complete) {
      cloud.normals.resize(n);
      for (size_t i = 0; i < n; ++i) cloud.normals[i] = normals[vertex_normal[i]];
    } else if (normals.size() == n) {
      cloud.normals = normals;
    }
  }
  if (colored == n && n > 0) cloud.colors = std::move(colors);
  applyReadOptions(options, &mesh);
  return mesh;
}

void writeObjMesh(const std::string& path, const TriangleMesh& mesh) {
  const SurfelCloud& cloud = mesh.vertices;
  try {
    cloud.validate();
  } catch (const std::invalid_argument& e) {
    throw IoError(path, e.what());
  }
  const size_t n = cloud.size();
  std::string out = "# written by relaxed_connectivity\n";
  for (size_t i = 0; i < n; ++i) {
    out += 'v';
    for (int a = 0; a < 3; ++a) {
      out += ' ';
      appendDoubleText(cloud.positions[i][a], &out);
    }
    if (cloud.hasColors())
      for (int a = 0; a < 3; ++a) {
        out += ' ';
        appendDoubleText(cloud.colors[i][a] / 255.0, &out);
      }
    out += '\n';
  }
  if (cloud.hasNormals())
    for (size_t i = 0; i < n; ++i) {
      out += "vn";
      for (int a = 0; a < 3; ++a) {
        out += ' ';
        appendDoubleText(cloud.normals[i][a], &out);
      }
      out += '\n';
    }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    out += 'f';
    for (uint32_t index : mesh.triangles[t]) {
      if (index >= n)
        throw IoError(
            path, "triangle #" + std::to_string(t),
            "vertex index " + std::to_string(index) + " out of range [0, " + std::to_string(n) + ")");
      const std::string k = std::to_string(index + 1);
      out += ' ';
      out += cloud.hasNormals() ? k + "//" + k : k;
    }
    out += '\n';
  }
  writeFileBytes(path, out);
}

}  // namespace rc
