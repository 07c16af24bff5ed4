#include "relaxed_connectivity/sph/sph_output.h"

#include <cstdint>
#include <utility>

#include "relaxed_connectivity/io/file_bytes.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/ply_io.h"
#include "relaxed_connectivity/io/vtk_xml_writer.h"

namespace rc {

namespace {

/// The PointData arrays, then Points and the vertex cells (connectivity, offsets).
struct VtpArrays {
  std::vector<VtkXmlArray> point_data;
  VtkXmlArray points{"Points", VtkXmlType::kFloat64, 3, {}};
  VtkXmlArray connectivity{"connectivity", VtkXmlType::kInt64, 1, {}};
  VtkXmlArray offsets{"offsets", VtkXmlType::kInt64, 1, {}};
};

VtpArrays vtpArrays(const SphParticles& p, const std::vector<double>* temperatures,
                    const std::vector<uint32_t>* docked_points) {
  const size_t n = p.size();
  VtpArrays arrays;
  VtkXmlArray velocity{"velocity", VtkXmlType::kFloat32, 3, {}};
  VtkXmlArray density{"density", VtkXmlType::kFloat32, 1, {}},
      pressure{"pressure", VtkXmlType::kFloat32, 1, {}};
  VtkXmlArray kind{"kind", VtkXmlType::kUInt8, 1, {}};
  VtkXmlArray temperature{"temperature", VtkXmlType::kFloat32, 1, {}},
      phase{"phase", VtkXmlType::kUInt8, 1, {}};
  VtkXmlArray docked{"docked_points", VtkXmlType::kUInt32, 1, {}};
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      arrays.points.put<double>(p.positions[i][k]);
      velocity.put<float>(float(p.velocities[i][k]));
    }
    density.put<float>(float(p.densities[i]));
    pressure.put<float>(float(p.pressures[i]));
    kind.put<uint8_t>(uint8_t(p.kinds[i]));
    if (temperatures) {
      temperature.put<float>(float(i < temperatures->size() ? (*temperatures)[i] : 0.0));
      phase.put<uint8_t>(p.phases[i]);
    }
    if (docked_points) docked.put<uint32_t>(i < docked_points->size() ? (*docked_points)[i] : 0u);
    arrays.connectivity.put<int64_t>(int64_t(i));
    arrays.offsets.put<int64_t>(int64_t(i + 1));
  }
  arrays.point_data = {std::move(velocity), std::move(density), std::move(pressure), std::move(kind)};
  if (temperatures) {
    arrays.point_data.push_back(std::move(temperature));
    arrays.point_data.push_back(std::move(phase));
  }
  if (docked_points) arrays.point_data.push_back(std::move(docked));
  return arrays;
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
  const VtpArrays arrays = vtpArrays(particles, temperatures, docked_points);
  const std::string n = std::to_string(particles.size());
  VtkXmlSection point_data{"PointData", {{"Scalars", "density"}, {"Vectors", "velocity"}}, {}};
  for (const VtkXmlArray& a : arrays.point_data) point_data.arrays.push_back(&a);
  writeVtkXml(
      path, "PolyData",
      {{"NumberOfPoints", n},
       {"NumberOfVerts", n},
       {"NumberOfLines", "0"},
       {"NumberOfStrips", "0"},
       {"NumberOfPolys", "0"}},
      {point_data, {"Points", {}, {&arrays.points}}, {"Verts", {}, {&arrays.connectivity, &arrays.offsets}}},
      encoding == VtpEncoding::kAscii ? VtkXmlEncoding::kAscii : VtkXmlEncoding::kAppendedRaw);
}

void writeSphState(const std::string& path, const SphParticles& particles,
                   const std::vector<double>* temperatures) {
  const std::string ext = lowerCaseExtension(path);
  if (ext == ".ply")
    writeSphPly(path, particles, temperatures);
  else if (ext == ".vtp")
    writeSphVtp(path, particles, VtpEncoding::kAppendedRaw, temperatures);
  else
    throw IoError(path, "unknown extension '" + ext + "' for SPH particles (supported: .ply .vtp)");
}

}  // namespace rc
