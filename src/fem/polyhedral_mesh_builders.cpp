// The mesh builders of PolyhedralMesh: hexahedral and tetrahedral grids, and the grid cut by random planes.
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "relaxed_connectivity/fem/element_split.h"
#include "relaxed_connectivity/fem/polygon_geometry.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

namespace rc {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("PolyhedralMesh: " + what);
}

void checkGridArguments(const char* builder, const Vec3& lo, const Vec3& hi, int nx, int ny, int nz) {
  if (nx < 1 || ny < 1 || nz < 1)
    fail(std::string(builder) + ": cell counts must be >= 1, got " + std::to_string(nx) + " x " +
         std::to_string(ny) + " x " + std::to_string(nz));
  if (!lo.allFinite() || !hi.allFinite() || !((hi - lo).minCoeff() > 0.0))
    fail(std::string(builder) + ": the box needs finite corners with hi > lo in every coordinate");
}

std::vector<Vec3> gridNodes(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz) {
  std::vector<Vec3> nodes;
  nodes.reserve(static_cast<size_t>(nx + 1) * (ny + 1) * (nz + 1));
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        nodes.push_back(lo + (hi - lo).cwiseProduct(Vec3(double(i) / nx, double(j) / ny, double(k) / nz)));
  return nodes;
}

// Corner c (bits x, y, z) of box (i, j, k).
int gridCorner(int nx, int ny, int i, int j, int k, int c) {
  return (i + (c & 1)) + (nx + 1) * ((j + ((c >> 1) & 1)) + (ny + 1) * (k + ((c >> 2) & 1)));
}

PolyhedralMesh::ElementFaces tetrahedronFaces(const std::vector<Vec3>& nodes, std::array<int, 4> t) {
  const double det =
      (nodes[t[1]] - nodes[t[0]]).cross(nodes[t[2]] - nodes[t[0]]).dot(nodes[t[3]] - nodes[t[0]]);
  if (det < 0.0) std::swap(t[1], t[2]);
  return {{t[0], t[2], t[1]}, {t[0], t[1], t[3]}, {t[1], t[2], t[3]}, {t[0], t[3], t[2]}};
}

std::vector<PolyhedralMesh::ElementFaces> hexahedralCells(int nx, int ny, int nz) {
  std::vector<PolyhedralMesh::ElementFaces> cells;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        // VTK order 0-3 bottom counter-clockwise, 4-7 top, as corner bits.
        const int bits[8] = {0, 1, 3, 2, 4, 5, 7, 6};
        int v[8];
        for (int c = 0; c < 8; ++c) v[c] = gridCorner(nx, ny, i, j, k, bits[c]);
        cells.push_back({{v[0], v[3], v[2], v[1]},
                         {v[4], v[5], v[6], v[7]},
                         {v[0], v[1], v[5], v[4]},
                         {v[1], v[2], v[6], v[5]},
                         {v[2], v[3], v[7], v[6]},
                         {v[3], v[0], v[4], v[7]}});
      }
  return cells;
}

// The two triangles of each square face, its diagonal mirrored across the grid's mid-planes: the diagonal
// from the square's lower corner (in the face's two axes) when the square lies on the same side of both
// mid-planes, the other one otherwise (FaceDiagonals::kMirrorSymmetric).
std::vector<std::vector<std::vector<PolyhedralMesh::Triangle>>> mirroredFaceDiagonals(
    const std::vector<PolyhedralMesh::ElementFaces>& cells, int nx, int ny, int nz) {
  const int counts[3] = {nx, ny, nz};
  auto gridIndex = [&](int id) {
    return std::array<int, 3>{id % (nx + 1), (id / (nx + 1)) % (ny + 1), id / ((nx + 1) * (ny + 1))};
  };
  std::vector<std::vector<std::vector<PolyhedralMesh::Triangle>>> triangles(cells.size());
  for (size_t e = 0; e < cells.size(); ++e)
    for (const PolyhedralMesh::Face& face : cells[e]) {
      std::array<std::array<int, 3>, 4> g;
      for (int q = 0; q < 4; ++q) g[size_t(q)] = gridIndex(face[size_t(q)]);
      int normal = 0;  // the axis along which the face's nodes share their index
      while (!(g[0][size_t(normal)] == g[1][size_t(normal)] && g[0][size_t(normal)] == g[2][size_t(normal)]))
        ++normal;
      const int b = normal == 0 ? 1 : 0, c = normal == 2 ? 1 : 2;
      int low_b = g[0][size_t(b)], low_c = g[0][size_t(c)];
      for (const auto& n : g) low_b = std::min(low_b, n[size_t(b)]), low_c = std::min(low_c, n[size_t(c)]);
      const bool lower_b = 2 * low_b + 1 < counts[b], lower_c = 2 * low_c + 1 < counts[c];
      // The diagonal's start: the lower corner (main diagonal) or the corner low in c, high in b.
      const int start_b = lower_b == lower_c ? low_b : low_b + 1;
      int p = 0;
      while (!(g[size_t(p)][size_t(b)] == start_b && g[size_t(p)][size_t(c)] == low_c)) ++p;
      auto v = [&](int k) { return face[size_t((p + k) % 4)]; };
      triangles[e].push_back({{v(0), v(1), v(2)}, {v(0), v(2), v(3)}});
    }
  return triangles;
}

}  // namespace

PolyhedralMesh PolyhedralMesh::hexahedralGrid(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz,
                                              FaceDiagonals diagonals) {
  checkGridArguments("hexahedralGrid", lo, hi, nx, ny, nz);
  std::vector<ElementFaces> cells = hexahedralCells(nx, ny, nz);
  if (diagonals == FaceDiagonals::kFan)
    return PolyhedralMesh(gridNodes(lo, hi, nx, ny, nz), std::move(cells));
  auto triangles = mirroredFaceDiagonals(cells, nx, ny, nz);
  return PolyhedralMesh(gridNodes(lo, hi, nx, ny, nz), std::move(cells), std::move(triangles));
}

PolyhedralMesh PolyhedralMesh::tetrahedralGrid(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz,
                                               TetrahedronSplit split) {
  checkGridArguments("tetrahedralGrid", lo, hi, nx, ny, nz);
  std::vector<Vec3> nodes = gridNodes(lo, hi, nx, ny, nz);
  std::vector<ElementFaces> elements;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        auto corner = [&](int c) { return gridCorner(nx, ny, i, j, k, c); };
        if (split == TetrahedronSplit::kSix) {
          // Kuhn: paths 000 -> 111 along the axes in every order (translation-invariant face diagonals).
          const int orders[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};
          for (const auto& order : orders)
            elements.push_back(tetrahedronFaces(
                nodes, {corner(0), corner(order[0]), corner(order[0] | order[1]), corner(7)}));
        } else {
          // Four corner tetrahedra and a central one; odd cells mirrored in x so face diagonals match.
          const int flip = (i + j + k) % 2 ? 1 : 0;
          auto c = [&](int bits) { return corner(bits ^ flip); };
          elements.push_back(tetrahedronFaces(nodes, {c(0), c(1), c(2), c(4)}));
          elements.push_back(tetrahedronFaces(nodes, {c(3), c(2), c(1), c(7)}));
          elements.push_back(tetrahedronFaces(nodes, {c(5), c(1), c(4), c(7)}));
          elements.push_back(tetrahedronFaces(nodes, {c(6), c(2), c(4), c(7)}));
          elements.push_back(tetrahedronFaces(nodes, {c(1), c(2), c(4), c(7)}));
        }
      }
  return PolyhedralMesh(std::move(nodes), std::move(elements));
}

PolyhedralMesh PolyhedralMesh::randomPlaneCut(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz,
                                              int num_planes, unsigned seed, double min_relative_gap) {
  checkGridArguments("randomPlaneCut", lo, hi, nx, ny, nz);
  if (num_planes < 0) fail("randomPlaneCut: num_planes must be >= 0, got " + std::to_string(num_planes));
  if (!(min_relative_gap > 0.0 && min_relative_gap < 0.2))
    fail("randomPlaneCut: min_relative_gap must be in (0, 0.2), got " + std::to_string(min_relative_gap));
  std::vector<Vec3> nodes = gridNodes(lo, hi, nx, ny, nz);
  std::vector<ElementFaces> cells = hexahedralCells(nx, ny, nz);
  const double gap = min_relative_gap * (hi - lo).norm();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal_dist;
  for (int plane = 0; plane < num_planes; ++plane) {
    // Draw a plane through the box that keeps a gap to every node.
    Vec3 normal, point;
    std::vector<double> distance(nodes.size());
    for (int attempt = 0;; ++attempt) {
      if (attempt == 10000)
        fail("randomPlaneCut: no plane keeps a gap of " + std::to_string(gap) + " to all nodes after " +
             std::to_string(plane) + " planes (lower num_planes or min_relative_gap)");
      normal = Vec3(normal_dist(rng), normal_dist(rng), normal_dist(rng));
      if (normal.norm() < 1e-6) continue;
      normal.normalize();
      point = lo + (hi - lo).cwiseProduct(
                       Vec3(0.1 + 0.8 * unit(rng), 0.1 + 0.8 * unit(rng), 0.1 + 0.8 * unit(rng)));
      bool ok = true;
      for (size_t i = 0; i < nodes.size() && ok; ++i) {
        distance[i] = normal.dot(nodes[i] - point);
        ok = std::abs(distance[i]) >= gap;
      }
      if (ok) break;
    }
    std::vector<int> side(nodes.size());
    for (size_t i = 0; i < nodes.size(); ++i) side[i] = distance[i] > 0.0 ? 1 : -1;
    EdgeCrossingNodes crossing(distance, [&](int a, int b, double t) {
      nodes.push_back((1.0 - t) * nodes[a] + t * nodes[b]);
      distance.push_back(0.0);
      side.push_back(0);
      return static_cast<int>(nodes.size()) - 1;
    });
    const Vec3 e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
    auto sectionOrder = [&](const std::vector<int>& section_nodes) {
      std::vector<Vec3> points;
      for (int v : section_nodes) points.push_back(nodes[v]);
      return counterClockwiseOrder(points,
                                   [&](const Vec3& d) { return Eigen::Vector2d(e1.dot(d), e2.dot(d)); });
    };
    std::vector<ElementFaces> next;
    for (const ElementFaces& cell : cells) {
      if (!elementSides(cell, side).crossed()) {
        next.push_back(cell);
        continue;
      }
      ElementSplit split = splitElement(cell, side, crossing, sectionOrder);
      next.push_back(std::move(split.positive));
      next.push_back(std::move(split.negative));
    }
    cells = std::move(next);
  }
  return PolyhedralMesh(std::move(nodes), std::move(cells));
}

}  // namespace rc
