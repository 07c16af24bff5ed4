// The SPH's VTP files (writeSphVtp) read back with VTK's own XML reader, as ParaView does, in both encodings:
// points, one vertex cell per particle and the point data. Built where VTK (its IOXML module) is found;
// elsewhere the case skips, saying so. writeSphState writes by extension.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/sph/sph_output.h"

#if defined(RC_HAVE_VTK)
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>
#endif

namespace rc {
namespace {

TEST(SphVtkReadback, VtpFilesReadBackWithVtk) {
#if !defined(RC_HAVE_VTK)
  GTEST_SKIP() << "built without VTK (libvtk9-dev): no read-back with VTK's reader";
#else
  SphParticles particles;
  for (int i = 0; i < 50; ++i) {
    const size_t k = particles.add(Vec3(0.1 * i, 0.2, -0.3 * i), Vec3(i, -i, 0.5), 1.0,
                                   i % 7 == 0 ? SphParticleKind::kStaticBoundary : SphParticleKind::kFluid);
    particles.densities[k] = 1000.0 + i;
    particles.pressures[k] = 10.0 * i;
  }
  const std::vector<double> temperatures(50, 273.15);
  for (VtpEncoding encoding : {VtpEncoding::kAscii, VtpEncoding::kAppendedRaw}) {
    SCOPED_TRACE(int(encoding));
    const std::string path = ::testing::TempDir() + "sph_readback.vtp";
    writeSphVtp(path, particles, encoding, &temperatures);
    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    ASSERT_EQ(reader->GetErrorCode(), 0u);
    vtkPolyData* data = reader->GetOutput();
    ASSERT_EQ(data->GetNumberOfPoints(), 50);
    EXPECT_EQ(data->GetNumberOfVerts(), 50);
    for (int i = 0; i < 50; ++i) {
      double p[3];
      data->GetPoint(i, p);
      EXPECT_EQ(Vec3(p[0], p[1], p[2]), particles.positions[size_t(i)]);
    }
    vtkPointData* point_data = data->GetPointData();
    for (const char* name : {"velocity", "density", "pressure", "kind", "temperature", "phase"})
      EXPECT_TRUE(point_data->GetArray(name)) << name;
    double v[3];
    point_data->GetArray("velocity")->GetTuple(7, v);
    EXPECT_EQ(Vec3(v[0], v[1], v[2]), Vec3(7, -7, 0.5));
    EXPECT_EQ(point_data->GetArray("density")->GetTuple1(9), 1009.0);
    EXPECT_EQ(point_data->GetArray("kind")->GetTuple1(14), double(uint8_t(SphParticleKind::kStaticBoundary)));
    EXPECT_FLOAT_EQ(float(point_data->GetArray("temperature")->GetTuple1(3)), 273.15f);
    std::filesystem::remove(path);
  }
#endif
}

TEST(SphVtkReadback, StateFilesFollowTheirExtension) {
  // writeSphState (sph_sim's ~save): .ply and .vtp; other extensions are refused naming the supported ones.
  SphParticles particles;
  for (int i = 0; i < 10; ++i) particles.add(Vec3(i, 0, 0), Vec3(0, i, 0), 1.0, SphParticleKind::kFluid);
  const std::string dir = ::testing::TempDir();
  writeSphState(dir + "sph_state.ply", particles);
  EXPECT_EQ(readCloud(dir + "sph_state.ply").size(), 10u);
  writeSphState(dir + "sph_state.vtp", particles);
  EXPECT_TRUE(std::filesystem::exists(dir + "sph_state.vtp"));
  try {
    writeSphState(dir + "sph_state.csv", particles);
    ADD_FAILURE() << "a .csv state was written";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("supported: .ply .vtp"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rc
