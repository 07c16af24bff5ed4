#include "relaxed_connectivity/scan/procedural_models.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

namespace rc {

namespace {

constexpr double kPi = 3.14159265358979323846;

void requireAtLeast(const char* function, const char* name, int value, int minimum) {
  if (value < minimum)
    throw std::invalid_argument(std::string(function) + ": " + name +
                                " must be >= " + std::to_string(minimum) + ", got " + std::to_string(value));
}

void requirePositive(const char* function, const char* name, double value) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw std::invalid_argument(std::string(function) + ": " + name + " must be positive and finite, got " +
                                std::to_string(value));
}

uint8_t toByte(double x) {
  return static_cast<uint8_t>(std::lround(255.0 * std::clamp(x, 0.0, 1.0)));
}

Rgba rgb(double r, double g, double b) {
  return {toByte(r), toByte(g), toByte(b), 255};
}

// Soft rainbow for a hue in [0, 1) (periodic).
Rgba hueColor(double hue) {
  const double h = 2.0 * kPi * hue;
  return rgb(0.55 + 0.4 * std::cos(h), 0.55 + 0.4 * std::cos(h - 2.0 * kPi / 3.0),
             0.55 + 0.4 * std::cos(h + 2.0 * kPi / 3.0));
}

Rgba normalColor(const Vec3& n) {
  return rgb(0.5 + 0.45 * n.x(), 0.5 + 0.45 * n.y(), 0.5 + 0.45 * n.z());
}

uint32_t addVertex(TriangleMesh& mesh, const Vec3& p, const Vec3& n, const Rgba& c) {
  mesh.vertices.positions.push_back(p);
  mesh.vertices.normals.push_back(n);
  mesh.vertices.colors.push_back(c);
  return static_cast<uint32_t>(mesh.vertices.positions.size() - 1);
}

// Two triangles of the quad a-b-c-d (counter-clockwise seen from outside).
void addQuad(TriangleMesh& mesh, uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
  mesh.triangles.push_back({a, b, c});
  mesh.triangles.push_back({a, c, d});
}

// Icosphere on the unit sphere (positions == normals); colours left empty.
TriangleMesh unitGeodesicSphere(int frequency) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const Vec3 base[12] = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  const int faces[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  const int n = frequency;
  TriangleMesh mesh;
  // A lattice point is the integer combination sum w_k * base[v_k] (sum w_k = n); its canonical key (sorted
  // (vertex, weight) pairs with w > 0) is the same on every face that shares it, which welds the faces
  // exactly.
  std::unordered_map<uint64_t, uint32_t> index_of;
  auto vertex = [&](const int v[3], const int w[3]) {
    std::pair<int, int> terms[3] = {{v[0], w[0]}, {v[1], w[1]}, {v[2], w[2]}};
    std::sort(terms, terms + 3);
    uint64_t key = 0;
    int slot = 0;
    Vec3 p = Vec3::Zero();
    for (const auto& term : terms) {
      if (term.second == 0) continue;
      key |= static_cast<uint64_t>(((term.first + 1) << 12) | term.second) << (16 * slot++);
      p += term.second * base[term.first];
    }
    auto found = index_of.find(key);
    if (found != index_of.end()) return found->second;
    p.normalize();
    mesh.vertices.positions.push_back(p);
    mesh.vertices.normals.push_back(p);
    const uint32_t index = static_cast<uint32_t>(mesh.vertices.positions.size() - 1);
    index_of.emplace(key, index);
    return index;
  };
  std::vector<uint32_t> grid((n + 1) * (n + 1));
  for (const auto& face : faces) {
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const int w[3] = {n - i - j, i, j};
        grid[i * (n + 1) + j] = vertex(face, w);
      }
    auto at = [&](int i, int j) { return grid[i * (n + 1) + j]; };
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        if (i + j < n - 1) mesh.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
  }
  return mesh;
}

}  // namespace

TriangleMesh makeIcosphere(double radius, int frequency) {
  requirePositive("makeIcosphere", "radius", radius);
  requireAtLeast("makeIcosphere", "frequency", frequency, 1);
  requireAtLeast("makeIcosphere", "4000 - frequency", 4000 - frequency, 0);
  TriangleMesh mesh = unitGeodesicSphere(frequency);
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    mesh.vertices.colors.push_back(normalColor(mesh.vertices.normals[i]));
    mesh.vertices.positions[i] *= radius;
  }
  return mesh;
}

TriangleMesh makeUvSphere(double radius, int segments, int rings) {
  requirePositive("makeUvSphere", "radius", radius);
  requireAtLeast("makeUvSphere", "segments", segments, 3);
  requireAtLeast("makeUvSphere", "rings", rings, 2);
  TriangleMesh mesh;
  const uint32_t north = addVertex(mesh, Vec3(0, 0, radius), Vec3::UnitZ(), normalColor(Vec3::UnitZ()));
  for (int r = 1; r < rings; ++r) {
    const double theta = kPi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2.0 * kPi * s / segments;
      const Vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      addVertex(mesh, radius * n, n, normalColor(n));
    }
  }
  const uint32_t south = addVertex(mesh, Vec3(0, 0, -radius), -Vec3::UnitZ(), normalColor(-Vec3::UnitZ()));
  auto ring = [&](int r, int s) { return static_cast<uint32_t>(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) {
    mesh.triangles.push_back({north, ring(1, s), ring(1, s + 1)});
    for (int r = 1; r < rings - 1; ++r)
      addQuad(mesh, ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s + 1));
    mesh.triangles.push_back({south, ring(rings - 1, s + 1), ring(rings - 1, s)});
  }
  return mesh;
}

TriangleMesh makeTorus(double major_radius, double minor_radius, int major_segments, int minor_segments) {
  requirePositive("makeTorus", "major_radius", major_radius);
  requirePositive("makeTorus", "minor_radius", minor_radius);
  if (minor_radius >= major_radius)
    throw std::invalid_argument("makeTorus: minor_radius (" + std::to_string(minor_radius) +
                                ") must be smaller than major_radius (" + std::to_string(major_radius) + ")");
  requireAtLeast("makeTorus", "major_segments", major_segments, 3);
  requireAtLeast("makeTorus", "minor_segments", minor_segments, 3);
  TriangleMesh mesh;
  for (int i = 0; i < major_segments; ++i) {
    const double u = 2.0 * kPi * i / major_segments;
    const Vec3 radial(std::cos(u), std::sin(u), 0.0);
    for (int j = 0; j < minor_segments; ++j) {
      const double v = 2.0 * kPi * j / minor_segments;
      const Vec3 n = std::cos(v) * radial + std::sin(v) * Vec3::UnitZ();
      addVertex(mesh, major_radius * radial + minor_radius * n, n,
                hueColor(static_cast<double>(i) / major_segments));
    }
  }
  auto at = [&](int i, int j) {
    return static_cast<uint32_t>((i % major_segments) * minor_segments + (j % minor_segments));
  };
  for (int i = 0; i < major_segments; ++i)
    for (int j = 0; j < minor_segments; ++j)
      addQuad(mesh, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
  return mesh;
}

TriangleMesh makeBox(const Vec3& size, int subdivisions) {
  for (int k = 0; k < 3; ++k) requirePositive("makeBox", "size component", size[k]);
  requireAtLeast("makeBox", "subdivisions", subdivisions, 1);
  const int n = subdivisions;
  TriangleMesh mesh;
  // Vertices live on the integer lattice {0..n}^3 restricted to the cube surface; keying by lattice
  // coordinates welds the six faces exactly.
  std::unordered_map<uint64_t, uint32_t> index_of;
  const Vec3 lo = -0.5 * size;
  auto vertex = [&](const int c[3]) {
    const uint64_t key = (static_cast<uint64_t>(c[0]) << 42) | (static_cast<uint64_t>(c[1]) << 21) | c[2];
    auto found = index_of.find(key);
    if (found != index_of.end()) return found->second;
    const Vec3 p = lo + Vec3(size.x() * c[0] / n, size.y() * c[1] / n, size.z() * c[2] / n);
    const Vec3 t = (p - lo).cwiseQuotient(size);
    const uint32_t index =
        addVertex(mesh, p, Vec3::Zero(), rgb(0.3 + 0.6 * t.x(), 0.3 + 0.6 * t.y(), 0.3 + 0.6 * t.z()));
    index_of.emplace(key, index);
    return index;
  };
  std::vector<uint32_t> grid((n + 1) * (n + 1));
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;  // (a1, a2, axis) is right-handed
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          int c[3];
          c[axis] = side * n;
          c[a1] = i;
          c[a2] = j;
          grid[i * (n + 1) + j] = vertex(c);
        }
      auto at = [&](int i, int j) { return grid[i * (n + 1) + j]; };
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          // Counter-clockwise in (a1, a2) faces +axis; reverse it on the low side.
          if (side == 1)
            addQuad(mesh, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
          else
            addQuad(mesh, at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
        }
    }
  computeVertexNormals(mesh);
  return mesh;
}

double blobRadius(const Vec3& d, double radius, double amplitude) {
  // A few low-order lobes (combinations of spherical harmonics up to degree 4), |f| <= 1.
  const double f = 0.45 * (d.x() * d.y() * 3.0) + 0.35 * (5.0 * d.z() * d.z() * d.z() - 3.0 * d.z()) / 2.0 +
                   0.2 * (d.x() * d.x() * d.x() * d.x() + d.y() * d.y() * d.y() * d.y() - 0.4) * 2.5;
  return radius * (1.0 + amplitude * std::clamp(f, -1.0, 1.0));
}

TriangleMesh makeBlob(double radius, double amplitude, int frequency) {
  requirePositive("makeBlob", "radius", radius);
  if (!(amplitude >= 0.0 && amplitude < 0.9))
    throw std::invalid_argument("makeBlob: amplitude must be in [0, 0.9), got " + std::to_string(amplitude));
  requireAtLeast("makeBlob", "frequency", frequency, 1);
  requireAtLeast("makeBlob", "4000 - frequency", 4000 - frequency, 0);
  TriangleMesh mesh = unitGeodesicSphere(frequency);
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3 d = mesh.vertices.positions[i];
    const double r = blobRadius(d, radius, amplitude);
    mesh.vertices.positions[i] = r * d;
    const double bump = amplitude > 0.0 ? (r / radius - 1.0) / amplitude : 0.0;  // in [-1, 1]
    mesh.vertices.colors.push_back(hueColor(0.35 + 0.3 * bump));
  }
  computeVertexNormals(mesh);
  return mesh;
}

Vec3 torusKnotPoint(int p, int q, double major_radius, double minor_radius, double s) {
  const double ring = major_radius + minor_radius * std::cos(q * s);
  return Vec3(ring * std::cos(p * s), ring * std::sin(p * s), minor_radius * std::sin(q * s));
}

TriangleMesh makeTorusKnot(int p, int q, double major_radius, double minor_radius, double tube_radius,
                           int segments_along, int segments_around) {
  requireAtLeast("makeTorusKnot", "p", p, 1);
  requireAtLeast("makeTorusKnot", "q", q, 1);
  requirePositive("makeTorusKnot", "major_radius", major_radius);
  requirePositive("makeTorusKnot", "minor_radius", minor_radius);
  requirePositive("makeTorusKnot", "tube_radius", tube_radius);
  requireAtLeast("makeTorusKnot", "segments_along", segments_along, 3);
  requireAtLeast("makeTorusKnot", "segments_around", segments_around, 3);
  TriangleMesh mesh;
  for (int i = 0; i < segments_along; ++i) {
    const double s = 2.0 * kPi * i / segments_along;
    const Vec3 c = torusKnotPoint(p, q, major_radius, minor_radius, s);
    const double h = 1e-5;
    const Vec3 tangent = (torusKnotPoint(p, q, major_radius, minor_radius, s + h) -
                          torusKnotPoint(p, q, major_radius, minor_radius, s - h))
                             .normalized();
    // Periodic frame: the offset from the torus core circle, made orthogonal to the tangent.
    const Vec3 core = major_radius * Vec3(std::cos(p * s), std::sin(p * s), 0.0);
    Vec3 normal = c - core;
    normal = (normal - normal.dot(tangent) * tangent).normalized();
    const Vec3 binormal = tangent.cross(normal);
    const Rgba color = hueColor(static_cast<double>(i) / segments_along);
    for (int j = 0; j < segments_around; ++j) {
      const double a = 2.0 * kPi * j / segments_around;
      const Vec3 n = std::cos(a) * normal + std::sin(a) * binormal;
      addVertex(mesh, c + tube_radius * n, n, color);
    }
  }
  auto at = [&](int i, int j) {
    return static_cast<uint32_t>((i % segments_along) * segments_around + (j % segments_around));
  };
  // (tangent, normal, binormal) is right-handed, so tangent x binormal = -normal: go +j first, then +i.
  for (int i = 0; i < segments_along; ++i)
    for (int j = 0; j < segments_around; ++j)
      addQuad(mesh, at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
  return mesh;
}

TriangleMesh makeGroundPlane(double height, double half_size, int subdivisions) {
  if (!std::isfinite(height)) throw std::invalid_argument("makeGroundPlane: height must be finite");
  requirePositive("makeGroundPlane", "half_size", half_size);
  requireAtLeast("makeGroundPlane", "subdivisions", subdivisions, 1);
  const int n = subdivisions;
  TriangleMesh mesh;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const Vec3 p(-half_size + 2.0 * half_size * i / n, -half_size + 2.0 * half_size * j / n, height);
      addVertex(mesh, p, Vec3::UnitZ(), rgb(0.7, 0.7, 0.68));
    }
  auto at = [&](int i, int j) { return static_cast<uint32_t>(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) addQuad(mesh, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
  return mesh;
}

void appendMesh(TriangleMesh& dst, const TriangleMesh& src) {
  const uint32_t offset = static_cast<uint32_t>(dst.vertices.size());
  dst.vertices.append(src.vertices);
  dst.triangles.reserve(dst.triangles.size() + src.triangles.size());
  for (const Triangle& t : src.triangles)
    dst.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}

void computeVertexNormals(TriangleMesh& mesh) {
  auto& positions = mesh.vertices.positions;
  std::vector<Vec3> normals(positions.size(), Vec3::Zero());
  for (const Triangle& t : mesh.triangles) {
    // |cross| = twice the area: area weighting.
    const Vec3 n = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
    for (uint32_t i : t) normals[i] += n;
  }
  for (Vec3& n : normals) {
    const double length = n.norm();
    n = length > 0.0 ? Vec3(n / length) : Vec3::UnitZ();
  }
  mesh.vertices.normals = std::move(normals);
}

const std::vector<std::string>& modelNames() {
  static const std::vector<std::string> names = {"icosphere", "uv_sphere", "torus",
                                                 "box",       "blob",      "torus_knot"};
  return names;
}

TriangleMesh makeModel(const std::string& name, int resolution, bool with_ground_plane) {
  const int minimum = (name == "box" || name == "icosphere" || name == "blob") ? 1 : 3;
  TriangleMesh mesh;
  auto checkResolution = [&]() {
    if (resolution < minimum)
      throw std::invalid_argument("makeModel: resolution for '" + name + "' must be >= " +
                                  std::to_string(minimum) + ", got " + std::to_string(resolution));
  };
  if (name == "icosphere") {
    checkResolution();
    mesh = makeIcosphere(0.5, resolution);
  } else if (name == "uv_sphere") {
    checkResolution();
    mesh = makeUvSphere(0.5, 2 * resolution, resolution);
  } else if (name == "torus") {
    checkResolution();
    mesh = makeTorus(0.5, 0.2, 2 * resolution, resolution);
  } else if (name == "box") {
    checkResolution();
    mesh = makeBox(Vec3(0.8, 0.6, 0.4), resolution);
  } else if (name == "blob") {
    checkResolution();
    mesh = makeBlob(0.5, 0.3, resolution);
  } else if (name == "torus_knot") {
    checkResolution();
    mesh = makeTorusKnot(2, 3, 0.4, 0.16, 0.07, 8 * resolution, resolution);
  } else {
    std::string valid;
    for (const std::string& n : modelNames()) valid += (valid.empty() ? "" : ", ") + n;
    throw std::invalid_argument("makeModel: unknown model '" + name + "'; valid names: " + valid);
  }
  if (with_ground_plane) {
    Vec3 lo, hi;
    mesh.vertices.bounds(&lo, &hi);
    const double extent = (hi - lo).maxCoeff();
    // Slightly below the model so that flat bottoms are not coplanar with the ground.
    appendMesh(mesh, makeGroundPlane(lo.z() - 1e-3 * extent, 2.0 * extent, std::max(1, resolution / 4)));
  }
  return mesh;
}

}  // namespace rc
