// Particle files of an SPH run: PLY (binary, via the io module) and VTK XML PolyData (.vtp, for ParaView),
// with the fields velocity, density, pressure and kind (plus temperature and phase when temperatures are
// given, and docked_points for solids with fracture, Fig. 8.7 c); io/pvd_io.h lists the frames for ParaView.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/sph/sph_particles.h"

namespace rc {

/// Positions plus attribute columns velocity (float32 x 3), density, pressure (float32) and kind (uint8,
/// SphParticleKind); with `temperatures` (one per particle, e.g. SphThermalModel::temperatures()) also
/// temperature (float32) and phase (uint8); with `docked_points` (one per particle, e.g. from
/// sphDockedPoints) also docked_points (uint32: docked lattice points, 8.2.5; missing entries 0).
SurfelCloud sphParticlesToCloud(const SphParticles& particles,
                                const std::vector<double>* temperatures = nullptr,
                                const std::vector<uint32_t>* docked_points = nullptr);

/// Binary little-endian PLY: x y z (float32), velocity_0..2, density, pressure, kind (temperature, phase)
/// (docked_points). Throws IoError.
void writeSphPly(const std::string& path, const SphParticles& particles,
                 const std::vector<double>* temperatures = nullptr,
                 const std::vector<uint32_t>* docked_points = nullptr);

enum class VtpEncoding { kAscii, kAppendedRaw };

/// VTK XML PolyData: Points (Float64 x 3), one vertex cell per particle (Verts), PointData velocity (Float32
/// x 3), density, pressure (Float32), kind (UInt8), with `temperatures` also temperature (Float32) and phase
/// (UInt8), with `docked_points` also docked_points (UInt32). kAppendedRaw stores the arrays as raw
/// little-endian bytes after the XML (header_type UInt64). Throws IoError if the file cannot be written.
void writeSphVtp(const std::string& path, const SphParticles& particles,
                 VtpEncoding encoding = VtpEncoding::kAppendedRaw,
                 const std::vector<double>* temperatures = nullptr,
                 const std::vector<uint32_t>* docked_points = nullptr);

/// The particles in the format of the file's extension (sph_sim's ~save): .ply (writeSphPly) or .vtp
/// (writeSphVtp). Throws IoError for another extension, naming the supported ones, and like the writers.
void writeSphState(const std::string& path, const SphParticles& particles,
                   const std::vector<double>* temperatures = nullptr);

}  // namespace rc
