#include "relaxed_connectivity/fem/fem_mesh_source.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <random>
#include <stdexcept>

#include <Eigen/Geometry>

#include "relaxed_connectivity/fem/convex_polyhedron.h"
#include "relaxed_connectivity/fem/plane_cut.h"
#include "relaxed_connectivity/fem/tetgen_mesh.h"
#include "relaxed_connectivity/io/obj_io.h"
#include "relaxed_connectivity/io/off_io.h"
#include "relaxed_connectivity/io/ply_io.h"
#include "relaxed_connectivity/mesh/surface_closing.h"
#include "relaxed_connectivity/mesh/surface_decimation.h"

namespace rc {

namespace {

TriangleMesh readSurface(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".obj") return readObjMesh(path);
  if (ext == ".off") return readOffMesh(path);
  if (ext == ".ply") return readPlyMesh(path);
  throw std::invalid_argument(path + ": unknown surface format (expected .obj, .off or .ply)");
}

}  // namespace

PolyhedralMesh randomElementSplits(const Vec3& lo, const Vec3& hi, int nx, int ny, int nz, int num_splits,
                                   unsigned seed, double min_relative_gap) {
  PolyhedralMesh mesh = PolyhedralMesh::hexahedralGrid(lo, hi, nx, ny, nz);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gaussian;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double gap = min_relative_gap * (hi - lo).norm();
  for (int split = 0; split < num_splits; ++split) {
    bool done = false;
    for (int attempt = 0; attempt < 1000 && !done; ++attempt) {
      // Element with probability proportional to its volume.
      double pick = uniform(rng) * mesh.volume();
      int e = 0;
      for (; e + 1 < mesh.numElements(); ++e) {
        pick -= mesh.element(e).volume();
        if (pick <= 0) break;
      }
      const ConvexPolyhedron& element = mesh.element(e);
      Vec3 normal(gaussian(rng), gaussian(rng), gaussian(rng));
      if (!(normal.norm() > 1e-6)) continue;
      normal.normalize();
      double min_d = INFINITY, max_d = -INFINITY;
      for (const Vec3& x : element.nodes()) {
        min_d = std::min(min_d, normal.dot(x - element.centroid()));
        max_d = std::max(max_d, normal.dot(x - element.centroid()));
      }
      const Vec3 point =
          element.centroid() + (0.3 * (2.0 * uniform(rng) - 1.0)) * std::min(-min_d, max_d) * normal;
      bool near = false;
      for (const Vec3& x : element.nodes()) near = near || std::abs(normal.dot(x - point)) < gap;
      if (near) continue;
      // A small triangle around the point selects the chosen element only.
      const double inside = -element.maxFacePlaneDistance(point);
      if (!(inside > 4.0 * element.tolerance())) continue;
      const Vec3 e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
      PlaneCutOptions options;
      const double r = 0.25 * inside;
      for (int k = 0; k < 3; ++k) {
        const double angle = 2.0 * M_PI * k / 3.0;
        options.region.push_back(point + r * (std::cos(angle) * e1 + std::sin(angle) * e2));
      }
      try {
        PlaneCutResult cut = cutMeshByPlane(mesh, {}, point, normal, options);
        if (cut.num_split_elements != 1) continue;
        mesh = std::move(cut.mesh);
        done = true;
      } catch (const std::exception&) {
        continue;  // an invalid result (e.g. a near-degenerate part): draw again
      }
    }
    if (!done)
      throw std::runtime_error("randomElementSplits: no admissible plane for split " + std::to_string(split) +
                               " in 1000 draws (lower min_relative_gap)");
  }
  return mesh;
}

PolyhedralMesh buildFemMesh(const FemMeshSource& s) {
  switch (s.type) {
    case FemMeshType::kConvexHull: {
      const ConvexPolyhedron hull = ConvexPolyhedron::convexHull(s.points);
      std::vector<PolyhedralMesh::ElementFaces> elements(1);
      for (const ConvexPolyhedron::Face& f : hull.faces()) elements[0].push_back(f);
      return PolyhedralMesh(hull.nodes(), std::move(elements));
    }
    case FemMeshType::kHexGrid:
      return PolyhedralMesh::hexahedralGrid(s.lo, s.hi, s.cells[0], s.cells[1], s.cells[2], s.face_diagonals);
    case FemMeshType::kTetGrid:
      return PolyhedralMesh::tetrahedralGrid(s.lo, s.hi, s.cells[0], s.cells[1], s.cells[2], s.split);
    case FemMeshType::kRandomPlanes:
      return PolyhedralMesh::randomPlaneCut(s.lo, s.hi, s.cells[0], s.cells[1], s.cells[2], s.planes, s.seed,
                                            s.min_relative_gap);
    case FemMeshType::kRandomSplits:
      return randomElementSplits(s.lo, s.hi, s.cells[0], s.cells[1], s.cells[2], s.planes, s.seed,
                                 s.min_relative_gap);
    case FemMeshType::kTetgenSurface: {
      TriangleMesh surface = readSurface(s.surface);
      if (s.close_holes) surface = closeSurfaceHoles(surface);
      if (s.decimate_vertices > 0) {
        DecimationOptions decimation;
        decimation.target_vertices = s.decimate_vertices;
        surface = decimateSurface(surface, decimation);
      }
      std::vector<Vec3>& x = surface.vertices.positions;
      if (s.size > 0 && !x.empty()) {  // centre the bounding box at the origin, scale its diagonal to size
        Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
        for (const Vec3& p : x) {
          lo = lo.cwiseMin(p);
          hi = hi.cwiseMax(p);
        }
        const double scale = s.size / (hi - lo).norm();
        for (Vec3& p : x) p = (p - 0.5 * (lo + hi)) * scale;
      }
      TetgenOptions options;
      options.max_volume = s.max_volume;
      options.max_radius_edge_ratio = s.max_radius_edge_ratio;
      options.min_dihedral_degrees = s.min_dihedral_degrees;
      return toPolyhedralMesh(tetrahedralizeSurface(surface, options));
    }
    case FemMeshType::kTetgenFiles:
      return toPolyhedralMesh(readTetgenMesh(s.node_file, s.ele_file));
  }
  throw std::invalid_argument("buildFemMesh: unknown mesh type");
}

}  // namespace rc
