#include "fem/fem_output.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "io/io_error.h"

namespace rc {

namespace {

constexpr uint8_t kVtkPolyhedron = 42;

bool hostIsLittleEndian() {
  const uint16_t one = 1;
  uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

enum class ArrayType { kFloat64, kFloat32, kInt64, kInt32, kUInt8 };

const char* typeName(ArrayType t) {
  switch (t) {
    case ArrayType::kFloat64:
      return "Float64";
    case ArrayType::kFloat32:
      return "Float32";
    case ArrayType::kInt64:
      return "Int64";
    case ArrayType::kInt32:
      return "Int32";
    default:
      return "UInt8";
  }
}

size_t typeSize(ArrayType t) {
  switch (t) {
    case ArrayType::kFloat64:
    case ArrayType::kInt64:
      return 8;
    case ArrayType::kFloat32:
    case ArrayType::kInt32:
      return 4;
    default:
      return 1;
  }
}

/// One DataArray as raw host-order bytes.
struct VtuArray {
  std::string name;
  ArrayType type;
  int components;
  std::vector<uint8_t> bytes;

  template <typename T>
  void put(T value) {
    const size_t at = bytes.size();
    bytes.resize(at + sizeof(T));
    std::memcpy(bytes.data() + at, &value, sizeof(T));
  }
  size_t count() const { return bytes.size() / typeSize(type); }
};

std::string asciiValues(const VtuArray& a) {
  std::string out;
  char buf[32];
  const size_t size = typeSize(a.type), n = a.count();
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* v = a.bytes.data() + i * size;
    switch (a.type) {
      case ArrayType::kFloat64: {
        double d;
        std::memcpy(&d, v, 8);
        std::snprintf(buf, sizeof(buf), "%.17g", d);
        break;
      }
      case ArrayType::kFloat32: {
        float f;
        std::memcpy(&f, v, 4);
        std::snprintf(buf, sizeof(buf), "%.9g", double(f));
        break;
      }
      case ArrayType::kInt64: {
        int64_t k;
        std::memcpy(&k, v, 8);
        std::snprintf(buf, sizeof(buf), "%lld", (long long)k);
        break;
      }
      case ArrayType::kInt32: {
        int32_t k;
        std::memcpy(&k, v, 4);
        std::snprintf(buf, sizeof(buf), "%d", int(k));
        break;
      }
      default:
        std::snprintf(buf, sizeof(buf), "%u", unsigned(*v));
    }
    out += buf;
    out += (i + 1) % 12 == 0 || i + 1 == n ? '\n' : ' ';
  }
  return out;
}

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
  VtuArray points{"Points", ArrayType::kFloat64, 3, {}};
  VtuArray displacement{"displacement", ArrayType::kFloat32, 3, {}};
  VtuArray velocity{"velocity", ArrayType::kFloat32, 3, {}};
  VtuArray body_id{"body", ArrayType::kInt32, 1, {}}, node_count{"nodes", ArrayType::kInt32, 1, {}};
  VtuArray connectivity{"connectivity", ArrayType::kInt64, 1, {}},
      offsets{"offsets", ArrayType::kInt64, 1, {}};
  VtuArray types{"types", ArrayType::kUInt8, 1, {}}, faces{"faces", ArrayType::kInt64, 1, {}};
  VtuArray face_offsets{"faceoffsets", ArrayType::kInt64, 1, {}};
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

  const bool appended = encoding == VtuEncoding::kAppendedRaw;
  std::vector<const VtuArray*> order;  // declaration (and appended) order
  std::ostringstream xml;
  uint64_t offset = 0;
  auto array = [&](const VtuArray& a) {
    order.push_back(&a);
    xml << "        <DataArray type=\"" << typeName(a.type) << "\" Name=\"" << a.name << "\"";
    if (a.components > 1) xml << " NumberOfComponents=\"" << a.components << "\"";
    if (appended) {
      xml << " format=\"appended\" offset=\"" << offset << "\"/>\n";
      offset += sizeof(uint64_t) + a.bytes.size();
    } else {
      xml << " format=\"ascii\">\n" << asciiValues(a) << "        </DataArray>\n";
    }
  };
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\""
      << (hostIsLittleEndian() ? "LittleEndian" : "BigEndian") << "\" header_type=\"UInt64\">\n"
      << "  <UnstructuredGrid>\n"
      << "    <Piece NumberOfPoints=\"" << num_points << "\" NumberOfCells=\"" << num_cells << "\">\n"
      << "      <PointData Vectors=\"displacement\">\n";
  array(displacement);
  array(velocity);
  xml << "      </PointData>\n      <CellData Scalars=\"body\">\n";
  array(body_id);
  array(node_count);
  xml << "      </CellData>\n      <Points>\n";
  array(points);
  xml << "      </Points>\n      <Cells>\n";
  for (const VtuArray* a : {&connectivity, &offsets, &types, &faces, &face_offsets}) array(*a);
  xml << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n";

  std::ofstream out(path, std::ios::binary);
  if (!out) throw IoError(path, "cannot open for writing");
  const std::string text = xml.str();
  out.write(text.data(), std::streamsize(text.size()));
  if (appended) {
    out << "  <AppendedData encoding=\"raw\">\n   _";
    for (const VtuArray* a : order) {
      const uint64_t bytes = a->bytes.size();
      out.write(reinterpret_cast<const char*>(&bytes), sizeof(bytes));
      out.write(reinterpret_cast<const char*>(a->bytes.data()), std::streamsize(bytes));
    }
    out << "\n  </AppendedData>\n";
  }
  out << "</VTKFile>\n";
  if (!out) throw IoError(path, "write failed");
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

}  // namespace rc
