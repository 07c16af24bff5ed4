#include "relaxed_connectivity/fem/fem_output.h"

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/io/file_bytes.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/vtk_xml_writer.h"

namespace rc {

namespace {

constexpr uint8_t kVtkPolyhedron = 42;

void checkBodies(const std::vector<FemBodyState>& bodies, const char* who) {
  for (size_t b = 0; b < bodies.size(); ++b) {
    const FemBodyState& s = bodies[b];
    const std::string where = std::string(who) + ": body " + std::to_string(b);
    if (!s.mesh || !s.positions) throw std::invalid_argument(where + ": null mesh or positions");
    const Eigen::Index dofs = 3 * Eigen::Index(s.mesh->numNodes());
    if (s.positions->size() != dofs || (s.velocities && s.velocities->size() != dofs))
      throw std::invalid_argument(where + ": positions / velocities need " + std::to_string(dofs) +
                                  " values");
  }
}

}  // namespace

void writeFemVtu(const std::string& path, const std::vector<FemBodyState>& bodies, VtuEncoding encoding) {
  checkBodies(bodies, "writeFemVtu");
  VtkXmlArray points{"Points", VtkXmlType::kFloat64, 3, {}};
  VtkXmlArray displacement{"displacement", VtkXmlType::kFloat32, 3, {}};
  VtkXmlArray velocity{"velocity", VtkXmlType::kFloat32, 3, {}};
  VtkXmlArray body_id{"body", VtkXmlType::kInt32, 1, {}}, node_count{"nodes", VtkXmlType::kInt32, 1, {}};
  VtkXmlArray connectivity{"connectivity", VtkXmlType::kInt64, 1, {}},
      offsets{"offsets", VtkXmlType::kInt64, 1, {}};
  VtkXmlArray types{"types", VtkXmlType::kUInt8, 1, {}}, faces{"faces", VtkXmlType::kInt64, 1, {}};
  VtkXmlArray face_offsets{"faceoffsets", VtkXmlType::kInt64, 1, {}};
  int64_t first_node = 0, connectivity_end = 0, faces_end = 0;
  size_t num_points = 0, num_cells = 0;
  for (size_t b = 0; b < bodies.size(); ++b) {
    const PolyhedralMesh& mesh = *bodies[b].mesh;
    const Eigen::VectorXd& x = *bodies[b].positions;
    for (int i = 0; i < mesh.numNodes(); ++i)
      for (int k = 0; k < 3; ++k) {
        points.put<double>(x[3 * i + k]);
        displacement.put<float>(float(x[3 * i + k] - mesh.node(i)[k]));
        velocity.put<float>(bodies[b].velocities ? float((*bodies[b].velocities)[3 * i + k]) : 0.0f);
      }
    for (int e = 0; e < mesh.numElements(); ++e) {
      const std::vector<int>& ids = mesh.element(e).globalNodeIds();
      for (int id : ids) connectivity.put<int64_t>(first_node + id);
      connectivity_end += int64_t(ids.size());
      offsets.put<int64_t>(connectivity_end);
      types.put<uint8_t>(kVtkPolyhedron);
      const PolyhedralMesh::ElementFaces& element_faces = mesh.elementFaces(e);
      faces.put<int64_t>(int64_t(element_faces.size()));
      faces_end += 1;
      for (const PolyhedralMesh::Face& face : element_faces) {
        faces.put<int64_t>(int64_t(face.size()));
        for (int id : face) faces.put<int64_t>(first_node + id);
        faces_end += 1 + int64_t(face.size());
      }
      face_offsets.put<int64_t>(faces_end);
      body_id.put<int32_t>(int32_t(b));
      node_count.put<int32_t>(int32_t(ids.size()));
    }
    first_node += mesh.numNodes();
    num_points += size_t(mesh.numNodes());
    num_cells += size_t(mesh.numElements());
  }

  writeVtkXml(path, "UnstructuredGrid",
              {{"NumberOfPoints", std::to_string(num_points)}, {"NumberOfCells", std::to_string(num_cells)}},
              {{"PointData", {{"Vectors", "displacement"}}, {&displacement, &velocity}},
               {"CellData", {{"Scalars", "body"}}, {&body_id, &node_count}},
               {"Points", {}, {&points}},
               {"Cells", {}, {&connectivity, &offsets, &types, &faces, &face_offsets}}},
              encoding == VtuEncoding::kAscii ? VtkXmlEncoding::kAscii : VtkXmlEncoding::kAppendedRaw);
}

void writeFemObj(const std::string& path, const std::vector<FemBodyState>& bodies) {
  checkBodies(bodies, "writeFemObj");
  std::ofstream out(path);
  if (!out) throw IoError(path, "cannot open for writing");
  out << "# rc_fem boundary surface: " << bodies.size() << " bodies\n";
  char line[96];
  size_t first_vertex = 1;  // OBJ indices are 1-based
  for (size_t b = 0; b < bodies.size(); ++b) {
    const PolyhedralMesh& mesh = *bodies[b].mesh;
    const Eigen::VectorXd& x = *bodies[b].positions;
    out << "o body" << b << "\n";
    for (int i = 0; i < mesh.numNodes(); ++i) {
      std::snprintf(line, sizeof(line), "v %.9g %.9g %.9g\n", x[3 * i], x[3 * i + 1], x[3 * i + 2]);
      out << line;
    }
    for (const PolyhedralMesh::Triangle& t : mesh.boundaryTriangles())
      out << "f " << first_vertex + size_t(t[0]) << ' ' << first_vertex + size_t(t[1]) << ' '
          << first_vertex + size_t(t[2]) << '\n';
    first_vertex += size_t(mesh.numNodes());
  }
  if (!out) throw IoError(path, "write failed");
}

SurfelCloud femNodesToCloud(const std::vector<FemBodyState>& bodies) {
  size_t n = 0;
  for (const FemBodyState& body : bodies) n += size_t(body.mesh->numNodes());
  SurfelCloud cloud;
  cloud.positions.reserve(n);
  // Added first, looked up after: add() may move the columns added before.
  cloud.attributes.add("velocity", ScalarType::kFloat32, 3, n);
  cloud.attributes.add("displacement", ScalarType::kFloat32, 3, n);
  cloud.attributes.add("body", ScalarType::kUInt32, 1, n);
  Attribute& velocity = *cloud.attributes.find("velocity");
  Attribute& displacement = *cloud.attributes.find("displacement");
  Attribute& body_id = *cloud.attributes.find("body");
  size_t i = 0;
  for (size_t b = 0; b < bodies.size(); ++b) {
    const FemBodyState& body = bodies[b];
    for (int v = 0; v < body.mesh->numNodes(); ++v, ++i) {
      const Vec3 x = body.positions->segment<3>(3 * v);
      const Vec3 u = x - body.mesh->node(v);
      cloud.positions.push_back(x);
      for (uint32_t k = 0; k < 3; ++k) {
        velocity.set(i, body.velocities ? (*body.velocities)[3 * v + k] : 0.0, k);
        displacement.set(i, u[k], k);
      }
      body_id.set(i, double(b));
    }
  }
  return cloud;
}

void writeFemState(const std::string& path, const std::vector<FemBodyState>& bodies) {
  const std::string ext = lowerCaseExtension(path);
  if (ext == ".vtu") {
    writeFemVtu(path, bodies);
  } else if (ext == ".obj") {
    writeFemObj(path, bodies);
  } else if (ext == ".ply" || ext == ".pcd" || ext == ".xyz") {
    writeCloud(path, femNodesToCloud(bodies));
  } else {
    throw IoError(path,
                  "unknown extension '" + ext + "' for an FEM state (supported: .vtu .obj .ply .pcd .xyz)");
  }
}

}  // namespace rc
