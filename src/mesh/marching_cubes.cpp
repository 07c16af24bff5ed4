#include "relaxed_connectivity/mesh/marching_cubes.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

namespace rc {

namespace {

int threadCount(int requested) {
  return requested > 0 ? requested : omp_get_max_threads();
}

// ---------------------------------------------------------------------------------------------------------
// Marching cubes case table, generated once. Cube corner c is at (c & 1, (c >> 1) & 1, (c >> 2) & 1); cube
// edge e = 4 axis + (the two other corner coordinates, lower axis first) joins two corners along `axis`.
// ---------------------------------------------------------------------------------------------------------

// The corners of each face, counter-clockwise seen from outside the cube.
constexpr int kFaceCorners[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                    {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

int cubeEdge(int a, int b) {
  const int diff = a ^ b;
  const int axis = diff == 1 ? 0 : (diff == 2 ? 1 : 2);
  const int lo = std::min(a, b);
  const int x = lo & 1, y = (lo >> 1) & 1, z = (lo >> 2) & 1;
  const int rest = axis == 0 ? y + 2 * z : (axis == 1 ? x + 2 * z : x + 2 * y);
  return 4 * axis + rest;
}

struct McCase {
  int num_triangles = 0;
  std::array<int8_t, 30> edges{};  // at most 12 vertices in loops of >= 3: <= 10 triangles
};

struct McTable {
  std::array<McCase, 256> cases;
  McTable() {
    for (int config = 0; config < 256; ++config) {
      const auto inside = [config](int corner) { return ((config >> corner) & 1) != 0; };
      // On each face, walking its corners counter-clockwise from outside, the crossings alternate between
      // outside->inside and inside->outside; each outside->inside crossing is joined to the next crossing.
      // The segment thus cuts off the run of inside corners between them (ambiguous faces: inside corners
      // separated) and runs with the inside on its left, so the loops are counter-clockwise seen from
      // outside the inside region. Each crossed cube edge starts one segment and ends one.
      int next[12];
      std::fill(next, next + 12, -1);
      for (const auto& face : kFaceCorners) {
        int crossing_edge[4], num_crossings = 0;
        bool enters[4];
        for (int t = 0; t < 4; ++t) {
          const int a = face[t], b = face[(t + 1) % 4];
          if (inside(a) == inside(b)) continue;
          crossing_edge[num_crossings] = cubeEdge(a, b);
          enters[num_crossings] = inside(b);
          ++num_crossings;
        }
        for (int q = 0; q < num_crossings; ++q)
          if (enters[q]) next[crossing_edge[q]] = crossing_edge[(q + 1) % num_crossings];
      }
      McCase& out = cases[config];
      bool visited[12] = {};
      for (int start = 0; start < 12; ++start) {
        if (next[start] < 0 || visited[start]) continue;
        int loop[12], length = 0;
        for (int e = start; !visited[e]; e = next[e]) {
          visited[e] = true;
          loop[length++] = e;
        }
        triangulateLoop(loop, length, &out);
      }
    }
  }

 private:
  // Two cube edges on a common face, also shared by the neighbouring cube: if both cubes joined them by a
  // diagonal, four triangles would share that mesh edge.
  static bool onCommonFace(int edge_a, int edge_b) {
    int same = 7;  // coordinate bits equal at all four corners
    const int first = edgeCorner(edge_a, 0);
    for (int e : {edge_a, edge_b})
      for (int end = 0; end < 2; ++end) same &= ~(edgeCorner(e, end) ^ first);
    return same != 0;
  }
  static int edgeCorner(int edge, int end) {
    const int axis = edge / 4, rest = edge % 4;
    const int other_a = axis == 0 ? 1 : 0, other_b = axis == 2 ? 1 : 2;
    return (end << axis) | ((rest & 1) << other_a) | (((rest >> 1) & 1) << other_b);
  }

  // Triangulates the loop (its orientation kept) with diagonals only between vertices on no common face (a
  // polygon-interval search; a plain fan from loop[0] fails where the loop crosses an ambiguous face twice).
  static void triangulateLoop(const int* loop, int length, McCase* out) {
    int apex[12][12];  // apex[i][j]: third vertex of the triangle on (i, j) in the sub-polygon i..j; -2 none
    for (auto& row : apex) std::fill(row, row + 12, -1);
    const auto diagonalOk = [&](int i, int j) {
      return j - i == 1 || (i == 0 && j == length - 1) || !onCommonFace(loop[i], loop[j]);
    };
    std::function<bool(int, int)> solve = [&](int i, int j) {
      if (j - i < 2) return true;
      if (apex[i][j] != -1) return apex[i][j] >= 0;
      apex[i][j] = -2;
      for (int k = i + 1; k < j; ++k)
        if (diagonalOk(i, k) && diagonalOk(k, j) && solve(i, k) && solve(k, j)) {
          apex[i][j] = k;
          return true;
        }
      return false;
    };
    if (!solve(0, length - 1))
      throw std::logic_error("marching cubes table: loop without a valid triangulation");
    std::function<void(int, int)> emit = [&](int i, int j) {
      if (j - i < 2) return;
      const int k = apex[i][j];
      int8_t* tri = &out->edges[3 * out->num_triangles++];
      tri[0] = int8_t(loop[i]);
      tri[1] = int8_t(loop[k]);
      tri[2] = int8_t(loop[j]);
      emit(i, k);
      emit(k, j);
    };
    emit(0, length - 1);
  }
};

const McTable& mcTable() {
  static const McTable table;
  return table;
}

}  // namespace

void marchingCubes(const ScalarGrid& grid, double iso_value, bool compute_normals, int num_threads,
                   TriangleMesh* mesh) {
  if (!std::isfinite(iso_value))
    throw std::invalid_argument("marchingCubes: iso_value must be finite, got " + std::to_string(iso_value));
  if (grid.values.size() != grid.size())
    throw std::invalid_argument("marchingCubes: grid has " + std::to_string(grid.values.size()) +
                                " values for dims " + std::to_string(grid.dims[0]) + " x " +
                                std::to_string(grid.dims[1]) + " x " + std::to_string(grid.dims[2]));
  if (!(std::isfinite(grid.cell_size) && grid.cell_size > 0.0))
    throw std::invalid_argument("marchingCubes: grid cell_size must be finite and > 0, got " +
                                std::to_string(grid.cell_size));
  mesh->vertices.clear();
  mesh->triangles.clear();
  const size_t nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  if (nx < 2 || ny < 2 || nz < 2) return;
  const double* f = grid.values.data();
  const size_t stride[3] = {1, nx, nx * ny};
  const size_t limit[3] = {nx - 1, ny - 1, nz - 1};
  const int threads = std::max(1, std::min<int>(threadCount(num_threads), int(nz)));

  // 1. Crossed grid edges (endpoints on different sides), counted per z-plane of their lower node.
  const auto crosses = [&](size_t node, int axis) {
    return (f[node] >= iso_value) != (f[node + stride[axis]] >= iso_value);
  };
  std::vector<size_t> plane_vertices(nz + 1, 0);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (long k = 0; k < long(nz); ++k) {
    size_t count = 0;
    for (size_t j = 0; j < ny; ++j)
      for (size_t i = 0; i < nx; ++i) {
        const size_t node = grid.index(i, j, size_t(k));
        const size_t ijk[3] = {i, j, size_t(k)};
        for (int axis = 0; axis < 3; ++axis) count += ijk[axis] < limit[axis] && crosses(node, axis);
      }
    plane_vertices[size_t(k) + 1] = count;
  }
  for (size_t k = 0; k < nz; ++k) plane_vertices[k + 1] += plane_vertices[k];
  const size_t num_vertices = plane_vertices[nz];
  if (num_vertices == 0) return;
  if (num_vertices >= std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("marchingCubes: " + std::to_string(num_vertices) +
                                " vertices exceed 32-bit indices; use a larger cell size");

  // 2. One vertex per crossed edge (edge index 3 node + axis), numbered plane by plane in node order.
  std::vector<uint32_t> edge_vertex(3 * grid.size());
  mesh->vertices.positions.resize(num_vertices);
  if (compute_normals) mesh->vertices.normals.resize(num_vertices);
  const double inv_2cell = 0.5 / grid.cell_size;
  const auto gradient = [&](size_t i, size_t j, size_t k) {  // central differences, one-sided at the border
    const size_t ijk[3] = {i, j, k};
    const size_t node = grid.index(i, j, k);
    Vec3 g;
    for (int a = 0; a < 3; ++a) {
      const size_t below = ijk[a] > 0 ? node - stride[a] : node;
      const size_t above = ijk[a] < limit[a] ? node + stride[a] : node;
      const double span = double((ijk[a] > 0) + (ijk[a] < limit[a]));
      g[a] = (f[above] - f[below]) * inv_2cell * (2.0 / span);
    }
    return g;
  };
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (long kk = 0; kk < long(nz); ++kk) {
    const size_t k = size_t(kk);
    size_t id = plane_vertices[k];
    for (size_t j = 0; j < ny; ++j)
      for (size_t i = 0; i < nx; ++i) {
        const size_t node = grid.index(i, j, k);
        const size_t ijk[3] = {i, j, k};
        for (int axis = 0; axis < 3; ++axis) {
          if (ijk[axis] >= limit[axis] || !crosses(node, axis)) continue;
          const size_t other = node + stride[axis];
          const double t = (iso_value - f[node]) / (f[other] - f[node]);
          Vec3 p = grid.node(i, j, k);
          p[axis] += t * grid.cell_size;
          mesh->vertices.positions[id] = p;
          if (compute_normals) {
            size_t ijk_other[3] = {i, j, k};
            ++ijk_other[axis];
            const Vec3 g =
                (1.0 - t) * gradient(i, j, k) + t * gradient(ijk_other[0], ijk_other[1], ijk_other[2]);
            const double norm = g.norm();
            Vec3 normal = Vec3::Zero();
            if (norm > 0.0) {
              normal = -g / norm;
            } else {  // flat field: along the edge towards the outside endpoint
              normal[axis] = f[node] >= iso_value ? 1.0 : -1.0;
            }
            mesh->vertices.normals[id] = normal;
          }
          edge_vertex[3 * node + size_t(axis)] = uint32_t(id++);
        }
      }
  }

  // 3. Triangles per cube, from the case table, collected per z-layer of cubes and concatenated in order.
  const McTable& table = mcTable();
  size_t corner_offset[8];
  for (int c = 0; c < 8; ++c)
    corner_offset[c] = (c & 1) * stride[0] + ((c >> 1) & 1) * stride[1] + ((c >> 2) & 1) * stride[2];
  size_t edge_slot[12];  // cube edge -> offset of its grid edge index from 3 * (lower corner of the cube)
  for (int e = 0; e < 12; ++e) {
    const int axis = e / 4, rest = e % 4;
    const int other_a = axis == 0 ? 1 : 0, other_b = axis == 2 ? 1 : 2;
    size_t offset = 0;
    if (rest & 1) offset += stride[other_a];
    if (rest & 2) offset += stride[other_b];
    edge_slot[e] = 3 * offset + size_t(axis);
  }
  std::vector<std::vector<Triangle>> layer_triangles(nz - 1);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (long kk = 0; kk < long(nz) - 1; ++kk) {
    std::vector<Triangle>& out = layer_triangles[size_t(kk)];
    for (size_t j = 0; j + 1 < ny; ++j)
      for (size_t i = 0; i + 1 < nx; ++i) {
        const size_t base = grid.index(i, j, size_t(kk));
        int config = 0;
        for (int c = 0; c < 8; ++c) config |= int(f[base + corner_offset[c]] >= iso_value) << c;
        const McCase& cube = table.cases[config];
        for (int t = 0; t < cube.num_triangles; ++t) {
          const int8_t* e = &cube.edges[3 * t];
          out.push_back({edge_vertex[3 * base + edge_slot[e[0]]], edge_vertex[3 * base + edge_slot[e[1]]],
                         edge_vertex[3 * base + edge_slot[e[2]]]});
        }
      }
  }
  size_t num_triangles = 0;
  for (const auto& layer : layer_triangles) num_triangles += layer.size();
  mesh->triangles.reserve(num_triangles);
  for (const auto& layer : layer_triangles)
    mesh->triangles.insert(mesh->triangles.end(), layer.begin(), layer.end());
}

}  // namespace rc
