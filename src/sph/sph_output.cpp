#include "sph/sph_output.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "io/io_error.h"
#include "io/ply_io.h"

namespace rc {

namespace {

bool hostIsLittleEndian() {
  const uint16_t one = 1;
  uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

/// One PointData / Points array of the .vtp file as raw host-order bytes.
struct VtpArray {
  std::string name;
  const char* type;  ///< VTK type name
  int components;
  std::vector<uint8_t> bytes;
  size_t count() const;
};

size_t vtkTypeSize(const char* type) {
  const std::string t = type;
  if (t == "Float64" || t == "Int64") return 8;
  if (t == "Float32" || t == "UInt32") return 4;
  return 1;  // UInt8
}

size_t VtpArray::count() const {
  return bytes.size() / vtkTypeSize(type);
}

template <typename T>
void put(std::vector<uint8_t>& out, T value) {
  const size_t at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &value, sizeof(T));
}

/// Points, connectivity, offsets, then the PointData arrays.
std::vector<VtpArray> vtpArrays(const SphParticles& p, const std::vector<double>* temperatures,
                                const std::vector<uint32_t>* docked_points) {
  const size_t n = p.size();
  VtpArray points{"Points", "Float64", 3, {}}, velocity{"velocity", "Float32", 3, {}};
  VtpArray density{"density", "Float32", 1, {}}, pressure{"pressure", "Float32", 1, {}};
  VtpArray kind{"kind", "UInt8", 1, {}};
  VtpArray temperature{"temperature", "Float32", 1, {}}, phase{"phase", "UInt8", 1, {}};
  VtpArray docked{"docked_points", "UInt32", 1, {}};
  VtpArray connectivity{"connectivity", "Int64", 1, {}}, offsets{"offsets", "Int64", 1, {}};
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      put<double>(points.bytes, p.positions[i][k]);
      put<float>(velocity.bytes, float(p.velocities[i][k]));
    }
    put<float>(density.bytes, float(p.densities[i]));
    put<float>(pressure.bytes, float(p.pressures[i]));
    put<uint8_t>(kind.bytes, uint8_t(p.kinds[i]));
    if (temperatures) {
      put<float>(temperature.bytes, float(i < temperatures->size() ? (*temperatures)[i] : 0.0));
      put<uint8_t>(phase.bytes, p.phases[i]);
    }
    if (docked_points) put<uint32_t>(docked.bytes, i < docked_points->size() ? (*docked_points)[i] : 0u);
    put<int64_t>(connectivity.bytes, int64_t(i));
    put<int64_t>(offsets.bytes, int64_t(i + 1));
  }
  std::vector<VtpArray> arrays = {points, connectivity, offsets, velocity, density, pressure, kind};
  if (temperatures) {
    arrays.push_back(temperature);
    arrays.push_back(phase);
  }
  if (docked_points) arrays.push_back(docked);
  return arrays;
}

/// The values of an array as ascii text (floats with round-trip precision).
std::string asciiValues(const VtpArray& a) {
  std::string out;
  char buf[32];
  const size_t size = vtkTypeSize(a.type), n = a.count();
  const std::string type = a.type;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* v = a.bytes.data() + i * size;
    if (type == "Float64") {
      double d;
      std::memcpy(&d, v, 8);
      std::snprintf(buf, sizeof(buf), "%.17g", d);
    } else if (type == "Float32") {
      float f;
      std::memcpy(&f, v, 4);
      std::snprintf(buf, sizeof(buf), "%.9g", double(f));
    } else if (type == "UInt32") {
      uint32_t k;
      std::memcpy(&k, v, 4);
      std::snprintf(buf, sizeof(buf), "%u", unsigned(k));
    } else if (type == "Int64") {
      int64_t k;
      std::memcpy(&k, v, 8);
      std::snprintf(buf, sizeof(buf), "%lld", (long long)k);
    } else {
      std::snprintf(buf, sizeof(buf), "%u", unsigned(*v));
    }
    out += buf;
    out += (i + 1) % 12 == 0 || i + 1 == n ? '\n' : ' ';
  }
  return out;
}

}  // namespace

SurfelCloud sphParticlesToCloud(const SphParticles& p, const std::vector<double>* temperatures,
                                const std::vector<uint32_t>* docked_points) {
  const size_t n = p.size();
  SurfelCloud cloud;
  cloud.positions = p.positions;
  Attribute& velocity = cloud.attributes.add("velocity", ScalarType::kFloat32, 3, n);
  Attribute& density = cloud.attributes.add("density", ScalarType::kFloat32, 1, n);
  Attribute& pressure = cloud.attributes.add("pressure", ScalarType::kFloat32, 1, n);
  Attribute& kind = cloud.attributes.add("kind", ScalarType::kUInt8, 1, n);
  for (size_t i = 0; i < n; ++i) {
    for (uint32_t k = 0; k < 3; ++k) velocity.set(i, p.velocities[i][k], k);
    density.set(i, p.densities[i]);
    pressure.set(i, p.pressures[i]);
    kind.set(i, double(uint8_t(p.kinds[i])));
  }
  if (temperatures) {
    Attribute& temperature = cloud.attributes.add("temperature", ScalarType::kFloat32, 1, n);
    Attribute& phase = cloud.attributes.add("phase", ScalarType::kUInt8, 1, n);
    for (size_t i = 0; i < n; ++i) {
      temperature.set(i, i < temperatures->size() ? (*temperatures)[i] : 0.0);
      phase.set(i, double(p.phases[i]));
    }
  }
  if (docked_points) {
    Attribute& docked = cloud.attributes.add("docked_points", ScalarType::kUInt32, 1, n);
    for (size_t i = 0; i < n; ++i)
      docked.set(i, i < docked_points->size() ? double((*docked_points)[i]) : 0.0);
  }
  return cloud;
}

void writeSphPly(const std::string& path, const SphParticles& particles,
                 const std::vector<double>* temperatures, const std::vector<uint32_t>* docked_points) {
  WriteOptions options;
  options.encoding = Encoding::kBinary;
  writePlyCloud(path, sphParticlesToCloud(particles, temperatures, docked_points), options);
}

void writeSphVtp(const std::string& path, const SphParticles& particles, VtpEncoding encoding,
                 const std::vector<double>* temperatures, const std::vector<uint32_t>* docked_points) {
  const std::vector<VtpArray> arrays = vtpArrays(particles, temperatures, docked_points);
  const bool appended = encoding == VtpEncoding::kAppendedRaw;
  const size_t n = particles.size();
  std::ostringstream xml;
  uint64_t offset = 0;
  auto array = [&](const VtpArray& a) {
    xml << "        <DataArray type=\"" << a.type << "\" Name=\"" << a.name << "\"";
    if (a.components > 1) xml << " NumberOfComponents=\"" << a.components << "\"";
    if (appended) {
      xml << " format=\"appended\" offset=\"" << offset << "\"/>\n";
      offset += sizeof(uint64_t) + a.bytes.size();
    } else {
      xml << " format=\"ascii\">\n" << asciiValues(a) << "        </DataArray>\n";
    }
  };
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\""
      << (hostIsLittleEndian() ? "LittleEndian" : "BigEndian") << "\" header_type=\"UInt64\">\n"
      << "  <PolyData>\n"
      << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfVerts=\"" << n
      << "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n"
      << "      <PointData Scalars=\"density\" Vectors=\"velocity\">\n";
  // Written (and appended) in the order point data, points, connectivity, offsets.
  std::vector<size_t> order;
  for (size_t k = 3; k < arrays.size(); ++k) order.push_back(k);
  order.insert(order.end(), {0, 1, 2});
  for (size_t k = 3; k < arrays.size(); ++k) array(arrays[k]);
  xml << "      </PointData>\n      <Points>\n";
  array(arrays[0]);
  xml << "      </Points>\n      <Verts>\n";
  array(arrays[1]);
  array(arrays[2]);
  xml << "      </Verts>\n    </Piece>\n  </PolyData>\n";
  std::ofstream out(path, std::ios::binary);
  if (!out) throw IoError(path, "cannot open for writing");
  const std::string text = xml.str();
  out.write(text.data(), std::streamsize(text.size()));
  if (appended) {
    out << "  <AppendedData encoding=\"raw\">\n   _";
    for (const size_t k : order) {  // the order of the offsets above
      const uint64_t bytes = arrays[k].bytes.size();
      out.write(reinterpret_cast<const char*>(&bytes), sizeof(bytes));
      out.write(reinterpret_cast<const char*>(arrays[k].bytes.data()), std::streamsize(bytes));
    }
    out << "\n  </AppendedData>\n";
  }
  out << "</VTKFile>\n";
  if (!out) throw IoError(path, "write failed");
}

}  // namespace rc
