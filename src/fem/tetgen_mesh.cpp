#include "relaxed_connectivity/fem/tetgen_mesh.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include "relaxed_connectivity/io/file_bytes.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/text_lines.h"

#if RC_HAVE_TETGEN
#define TETLIBRARY
#include <tetgen.h>
#endif

namespace rc {
namespace {

std::string formatNumber(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}

// Enclosed surface checks: face indices, degenerate faces, every undirected edge used an even number of
// times.
void checkClosedSurface(const TriangleMesh& surface) {
  const size_t n = surface.vertices.size();
  if (n < 4 || surface.triangles.size() < 4)
    throw std::invalid_argument(
        "tetrahedralizeSurface: the surface needs at least 4 vertices and 4 triangles, got " +
        std::to_string(n) + " and " + std::to_string(surface.triangles.size()));
  for (const Vec3& p : surface.vertices.positions)
    if (!p.allFinite()) throw std::invalid_argument("tetrahedralizeSurface: a vertex position is not finite");
  std::map<std::pair<uint32_t, uint32_t>, int> edge_uses;
  for (size_t t = 0; t < surface.triangles.size(); ++t) {
    const Triangle& tri = surface.triangles[t];
    for (int k = 0; k < 3; ++k)
      if (tri[k] >= n)
        throw std::invalid_argument("tetrahedralizeSurface: triangle " + std::to_string(t) +
                                    " references vertex " + std::to_string(tri[k]) + " (surface has " +
                                    std::to_string(n) + ")");
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0])
      throw std::invalid_argument("tetrahedralizeSurface: triangle " + std::to_string(t) +
                                  " repeats a vertex (degenerate face)");
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri[k], b = tri[(k + 1) % 3];
      ++edge_uses[{std::min(a, b), std::max(a, b)}];
    }
  }
  size_t open = 0;
  std::pair<uint32_t, uint32_t> first{0, 0};
  for (const auto& [edge, uses] : edge_uses)
    if (uses % 2 == 1 && open++ == 0) first = edge;
  if (open > 0)
    throw std::invalid_argument("tetrahedralizeSurface: the surface is not closed: " + std::to_string(open) +
                                " edges are used by an odd number of triangles (first: vertices " +
                                std::to_string(first.first) + ", " + std::to_string(first.second) +
                                "; holes or a boundary)");
}

#if RC_HAVE_TETGEN
std::string tetgenErrorMessage(int code) {
  switch (code) {
    case 1:
      return "out of memory";
    case 2:
      return "internal error (please report to TetGen's author)";
    case 3:
      return "the input surface intersects itself";
    case 4:
      return "a very small input feature was detected (nearly coincident vertices or faces)";
    case 5:
      return "two input facets are very close to each other";
    case 10:
      return "invalid input";
    default:
      return "error code " + std::to_string(code);
  }
}
#endif

// Orients a tetrahedron positively; throws for a flat one.
std::array<int, 4> positiveTetrahedron(const std::vector<Vec3>& nodes, std::array<int, 4> t, size_t index) {
  const Vec3 e1 = nodes[t[1]] - nodes[t[0]], e2 = nodes[t[2]] - nodes[t[0]], e3 = nodes[t[3]] - nodes[t[0]];
  const double det = e1.cross(e2).dot(e3);
  const double scale = std::max({e1.norm(), e2.norm(), e3.norm()});
  if (!(std::abs(det) > 1e-14 * scale * scale * scale))
    throw std::invalid_argument("toPolyhedralMesh: tetrahedron " + std::to_string(index) + " is flat");
  if (det < 0.0) std::swap(t[1], t[2]);
  return t;
}

// ---- .node / .ele parsing
// ----------------------------------------------------------------------------------

class TetgenFileParser {
 public:
  TetgenFileParser(const std::string& path) : path_(path), text_(readFileBytes(path)), lines_(text_) {}

  // The next non-empty line (comments stripped) split into tokens; false at the end.
  bool nextRecord() {
    std::string_view line;
    while (lines_.next(&line)) {
      splitTokens(stripComment(line), &tokens_);
      if (!tokens_.empty()) return true;
    }
    return false;
  }
  void requireRecord(const std::string& what) {
    if (!nextRecord()) throw IoError(path_, "unexpected end of file, expected " + what);
  }
  size_t size() const { return tokens_.size(); }
  void requireTokens(size_t count, const std::string& what) const {
    if (tokens_.size() < count)
      fail(what + " needs " + std::to_string(count) + " fields, found " + std::to_string(tokens_.size()));
  }
  int64_t integer(size_t k, const std::string& what) const {
    int64_t value;
    if (!parseInt64(tokens_[k], &value)) fail(what + ": '" + std::string(tokens_[k]) + "' is not an integer");
    return value;
  }
  double real(size_t k, const std::string& what) const {
    double value;
    if (!parseDouble(tokens_[k], &value) || !std::isfinite(value))
      fail(what + ": '" + std::string(tokens_[k]) + "' is not a finite number");
    return value;
  }
  [[noreturn]] void fail(const std::string& problem) const {
    throw IoError(path_, "line " + std::to_string(lines_.lineNumber()), problem);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_, text_;
  LineReader lines_;
  std::vector<std::string_view> tokens_;
};

}  // namespace

bool tetgenAvailable() {
#if RC_HAVE_TETGEN
  return true;
#else
  return false;
#endif
}

std::string tetgenSwitches(const TetgenOptions& options) {
  std::string s = "pz";
  if (options.max_radius_edge_ratio > 0.0) {
    s += "q" + formatNumber(options.max_radius_edge_ratio);
    if (options.min_dihedral_degrees > 0.0) s += "/" + formatNumber(options.min_dihedral_degrees);
  }
  if (options.max_volume > 0.0) s += "a" + formatNumber(options.max_volume);
  if (options.preserve_surface) s += "Y";
  if (options.quiet) s += "Q";
  return s;
}

TetrahedralMesh tetrahedralizeSurface(const TriangleMesh& surface, const TetgenOptions& options) {
  if (!std::isfinite(options.max_radius_edge_ratio) || !std::isfinite(options.max_volume) ||
      !(options.min_dihedral_degrees >= 0.0 && options.min_dihedral_degrees < 70.6))
    throw std::invalid_argument(
        "tetrahedralizeSurface: bounds must be finite, the dihedral angle in [0, 70.5]");
  checkClosedSurface(surface);
#if RC_HAVE_TETGEN
  tetgenio in, out;  // their destructors free every list (allocated with new[] as TetGen expects)
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(surface.vertices.size());
  in.pointlist = new REAL[3 * surface.vertices.size()];
  for (size_t i = 0; i < surface.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k) in.pointlist[3 * i + k] = surface.vertices.positions[i][k];
  in.numberoffacets = static_cast<int>(surface.triangles.size());
  in.facetlist = new tetgenio::facet[surface.triangles.size()];
  for (size_t t = 0; t < surface.triangles.size(); ++t) {
    tetgenio::facet& facet = in.facetlist[t];
    tetgenio::init(&facet);
    facet.numberofpolygons = 1;
    facet.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&facet.polygonlist[0]);
    facet.polygonlist[0].numberofvertices = 3;
    facet.polygonlist[0].vertexlist = new int[3];
    for (int k = 0; k < 3; ++k)
      facet.polygonlist[0].vertexlist[k] = static_cast<int>(surface.triangles[t][k]);
  }
  std::string switches = tetgenSwitches(options);
  try {
    tetrahedralize(&switches[0], &in, &out);
  } catch (int code) {
    throw std::runtime_error("tetrahedralizeSurface: TetGen failed with switches '" + switches +
                             "': " + tetgenErrorMessage(code));
  }
  if (out.numberoftetrahedra <= 0 || out.numberofcorners != 4)
    throw std::runtime_error("tetrahedralizeSurface: TetGen returned no linear tetrahedra (switches '" +
                             switches + "')");
  TetrahedralMesh mesh;
  mesh.nodes.resize(out.numberofpoints);
  for (int i = 0; i < out.numberofpoints; ++i)
    mesh.nodes[i] = Vec3(out.pointlist[3 * i], out.pointlist[3 * i + 1], out.pointlist[3 * i + 2]);
  mesh.tetrahedra.resize(out.numberoftetrahedra);
  for (int t = 0; t < out.numberoftetrahedra; ++t)
    for (int k = 0; k < 4; ++k) mesh.tetrahedra[t][k] = out.tetrahedronlist[4 * t + k] - out.firstnumber;
  removeUnusedNodes(mesh);
  return mesh;
#else
  throw std::runtime_error(
      "tetrahedralizeSurface: this build lacks TetGen (install libtet1.5-dev and reconfigure)");
#endif
}

int removeUnusedNodes(TetrahedralMesh& mesh) {
  const int n = static_cast<int>(mesh.nodes.size());
  std::vector<int> new_index(n, -1);
  for (const auto& t : mesh.tetrahedra)
    for (int v : t) {
      if (v < 0 || v >= n)
        throw std::invalid_argument("removeUnusedNodes: node id " + std::to_string(v) +
                                    " out of range (mesh has " + std::to_string(n) + " nodes)");
      new_index[v] = 0;
    }
  int kept = 0;
  for (int i = 0; i < n; ++i)
    if (new_index[i] == 0) {
      new_index[i] = kept;
      mesh.nodes[kept++] = mesh.nodes[i];
    }
  mesh.nodes.resize(kept);
  for (auto& t : mesh.tetrahedra)
    for (int& v : t) v = new_index[v];
  return n - kept;
}

PolyhedralMesh toPolyhedralMesh(TetrahedralMesh mesh) {
  removeUnusedNodes(mesh);
  std::vector<PolyhedralMesh::ElementFaces> elements;
  elements.reserve(mesh.tetrahedra.size());
  for (size_t e = 0; e < mesh.tetrahedra.size(); ++e) {
    const std::array<int, 4> t = positiveTetrahedron(mesh.nodes, mesh.tetrahedra[e], e);
    elements.push_back({{t[0], t[2], t[1]}, {t[0], t[1], t[3]}, {t[1], t[2], t[3]}, {t[0], t[3], t[2]}});
  }
  return PolyhedralMesh(std::move(mesh.nodes), std::move(elements));
}

double radiusEdgeRatio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  // Circumcentre o - a solves 2 [b-a; c-a; d-a] (o - a) = (|b-a|^2, |c-a|^2, |d-a|^2).
  Eigen::Matrix3d m;
  m.row(0) = b - a;
  m.row(1) = c - a;
  m.row(2) = d - a;
  const Vec3 rhs(m.row(0).squaredNorm(), m.row(1).squaredNorm(), m.row(2).squaredNorm());
  const double radius = (0.5 * m.partialPivLu().solve(rhs)).norm();
  const double shortest = std::min(
      {(b - a).norm(), (c - a).norm(), (d - a).norm(), (c - b).norm(), (d - b).norm(), (d - c).norm()});
  return radius / shortest;
}

TetrahedralMesh readTetgenMesh(const std::string& node_path, const std::string& ele_path) {
  TetrahedralMesh mesh;
  int64_t base = 0;
  {
    TetgenFileParser file(node_path);
    file.requireRecord("the header '<points> 3 <attributes> <markers>'");
    file.requireTokens(1, "the header");
    const int64_t count = file.integer(0, "point count");
    const int64_t dimension = file.size() > 1 ? file.integer(1, "dimension") : 3;
    const int64_t attributes = file.size() > 2 ? file.integer(2, "attribute count") : 0;
    const int64_t markers = file.size() > 3 ? file.integer(3, "boundary marker flag") : 0;
    if (count <= 0 || count > std::numeric_limits<int>::max())
      file.fail("point count " + std::to_string(count) + " is not positive");
    if (dimension != 3) file.fail("dimension must be 3, got " + std::to_string(dimension));
    if (attributes < 0 || (markers != 0 && markers != 1))
      file.fail("attribute count must be >= 0 and the boundary marker flag 0 or 1");
    const size_t fields = static_cast<size_t>(4 + attributes + markers);
    mesh.nodes.resize(count);
    for (int64_t i = 0; i < count; ++i) {
      file.requireRecord("point " + std::to_string(i + 1) + " of " + std::to_string(count));
      file.requireTokens(fields, "a point line");
      const int64_t index = file.integer(0, "point index");
      if (i == 0) {
        if (index != 0 && index != 1)
          file.fail("the first point index must be 0 or 1, got " + std::to_string(index));
        base = index;
      } else if (index != base + i) {
        file.fail("expected point index " + std::to_string(base + i) + ", got " + std::to_string(index));
      }
      mesh.nodes[i] = Vec3(file.real(1, "x"), file.real(2, "y"), file.real(3, "z"));
    }
    if (file.nextRecord()) file.fail("unexpected data after the " + std::to_string(count) + " points");
  }
  {
    TetgenFileParser file(ele_path);
    file.requireRecord("the header '<tetrahedra> <nodes per tetrahedron> <attributes>'");
    file.requireTokens(2, "the header");
    const int64_t count = file.integer(0, "tetrahedron count");
    const int64_t corners = file.integer(1, "nodes per tetrahedron");
    const int64_t attributes = file.size() > 2 ? file.integer(2, "attribute count") : 0;
    if (count <= 0 || count > std::numeric_limits<int>::max())
      file.fail("tetrahedron count " + std::to_string(count) + " is not positive");
    if (corners != 4)
      file.fail("only linear (4-node) tetrahedra are supported, got " + std::to_string(corners) +
                " nodes per tetrahedron");
    if (attributes < 0) file.fail("attribute count must be >= 0");
    const int64_t num_nodes = static_cast<int64_t>(mesh.nodes.size());
    mesh.tetrahedra.resize(count);
    for (int64_t t = 0; t < count; ++t) {
      file.requireRecord("tetrahedron " + std::to_string(t + 1) + " of " + std::to_string(count));
      file.requireTokens(static_cast<size_t>(5 + attributes), "a tetrahedron line");
      const int64_t index = file.integer(0, "tetrahedron index");
      if (index != t + base)
        file.fail("expected tetrahedron index " + std::to_string(t + base) + ", got " +
                  std::to_string(index));
      for (int k = 0; k < 4; ++k) {
        const int64_t node = file.integer(1 + k, "node id");
        if (node < base || node >= base + num_nodes)
          file.fail("node id " + std::to_string(node) + " is outside " + std::to_string(base) + ".." +
                    std::to_string(base + num_nodes - 1) + " (" + node_path + ")");
        mesh.tetrahedra[t][k] = static_cast<int>(node - base);
      }
    }
    if (file.nextRecord()) file.fail("unexpected data after the " + std::to_string(count) + " tetrahedra");
  }
  return mesh;
}

void writeTetgenMesh(const std::string& basename, const TetrahedralMesh& mesh) {
  std::string node_text = std::to_string(mesh.nodes.size()) + " 3 0 0\n";
  char buffer[128];
  for (size_t i = 0; i < mesh.nodes.size(); ++i) {
    const Vec3& p = mesh.nodes[i];
    std::snprintf(buffer, sizeof(buffer), "%zu %.17g %.17g %.17g\n", i, p.x(), p.y(), p.z());
    node_text += buffer;
  }
  std::string ele_text = std::to_string(mesh.tetrahedra.size()) + " 4 0\n";
  for (size_t t = 0; t < mesh.tetrahedra.size(); ++t) {
    const auto& tet = mesh.tetrahedra[t];
    std::snprintf(buffer, sizeof(buffer), "%zu %d %d %d %d\n", t, tet[0], tet[1], tet[2], tet[3]);
    ele_text += buffer;
  }
  writeFileBytes(basename + ".node", node_text);
  writeFileBytes(basename + ".ele", ele_text);
}

}  // namespace rc
