// The FEM's VTU files (writeFemVtu: VTK_POLYHEDRON cells with faces / faceoffsets) read back with VTK's own
// XML reader, as ParaView does, in both encodings: points, cells with their faces, point and cell data. Built
// where VTK (its IOXML module) is found; elsewhere the case skips, saying so.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "relaxed_connectivity/fem/fem_output.h"
#include "relaxed_connectivity/fem/polyhedral_mesh.h"

#if defined(RC_HAVE_VTK)
#include <vtkCellData.h>
#include <vtkCellTypes.h>
#include <vtkDataArray.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#endif

namespace rc {
namespace {

TEST(FemVtkReadback, VtuFilesReadBackWithVtk) {
#if !defined(RC_HAVE_VTK)
  GTEST_SKIP() << "built without VTK (libvtk9-dev): no read-back with VTK's reader";
#else
  // Two bodies: a cube split by random planes (general convex polyhedra) and a tetrahedral grid.
  const PolyhedralMesh cut = PolyhedralMesh::randomPlaneCut(Vec3(0, 0, 0), Vec3(1, 1, 1), 2, 2, 2, 3, 5);
  const PolyhedralMesh tets = PolyhedralMesh::tetrahedralGrid(Vec3(2, 0, 0), Vec3(3, 1, 1), 1, 1, 1);
  std::vector<Eigen::VectorXd> positions, velocities;
  for (const PolyhedralMesh* mesh : {&cut, &tets}) {
    Eigen::VectorXd x(3 * mesh->numNodes()), v(3 * mesh->numNodes());
    for (int i = 0; i < mesh->numNodes(); ++i) {
      x.segment<3>(3 * i) = mesh->node(i) + Vec3(0.01 * i, 0, -0.02);
      v.segment<3>(3 * i) = Vec3(i, 2.0 * i, -1.0);
    }
    positions.push_back(x);
    velocities.push_back(v);
  }
  const std::vector<FemBodyState> bodies = {{&cut, &positions[0], &velocities[0]},
                                            {&tets, &positions[1], &velocities[1]}};
  const int num_points = cut.numNodes() + tets.numNodes();
  const int num_cells = cut.numElements() + tets.numElements();
  for (VtuEncoding encoding : {VtuEncoding::kAscii, VtuEncoding::kAppendedRaw}) {
    SCOPED_TRACE(int(encoding));
    const std::string path = ::testing::TempDir() + "fem_readback.vtu";
    writeFemVtu(path, bodies, encoding);
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    ASSERT_EQ(reader->GetErrorCode(), 0u);
    vtkUnstructuredGrid* grid = reader->GetOutput();
    ASSERT_EQ(grid->GetNumberOfPoints(), num_points);
    ASSERT_EQ(grid->GetNumberOfCells(), num_cells);
    // Points: the current positions, body after body.
    int offset = 0, cell = 0;
    for (size_t b = 0; b < bodies.size(); ++b) {
      const PolyhedralMesh& mesh = *bodies[b].mesh;
      for (int i = 0; i < mesh.numNodes(); ++i) {
        double p[3];
        grid->GetPoint(offset + i, p);
        EXPECT_EQ(Vec3(p[0], p[1], p[2]), Vec3(positions[b].segment<3>(3 * i)));
      }
      // Cells: polyhedra with the element's nodes and faces.
      for (int e = 0; e < mesh.numElements(); ++e, ++cell) {
        EXPECT_EQ(grid->GetCellType(cell), VTK_POLYHEDRON);
        vtkNew<vtkIdList> ids;
        grid->GetCellPoints(cell, ids);
        const auto& element_ids = mesh.element(e).globalNodeIds();
        ASSERT_EQ(ids->GetNumberOfIds(), vtkIdType(element_ids.size()));
        for (size_t k = 0; k < element_ids.size(); ++k)
          EXPECT_EQ(ids->GetId(vtkIdType(k)), offset + element_ids[k]);
        vtkNew<vtkIdList> faces;
        grid->GetFaceStream(cell, faces);
        EXPECT_EQ(faces->GetId(0), vtkIdType(mesh.elementFaces(e).size()));
      }
      offset += mesh.numNodes();
    }
    // Point and cell data as documented.
    vtkDataArray* displacement = grid->GetPointData()->GetArray("displacement");
    vtkDataArray* velocity = grid->GetPointData()->GetArray("velocity");
    vtkDataArray* body = grid->GetCellData()->GetArray("body");
    ASSERT_TRUE(displacement && velocity && body);
    EXPECT_EQ(displacement->GetNumberOfComponents(), 3);
    double u[3], v[3];
    displacement->GetTuple(5, u);
    velocity->GetTuple(5, v);
    EXPECT_FLOAT_EQ(float(u[0]), 0.05f);
    EXPECT_FLOAT_EQ(float(u[2]), -0.02f);
    EXPECT_EQ(v[1], 10.0);
    EXPECT_EQ(body->GetTuple1(0), 0.0);
    EXPECT_EQ(body->GetTuple1(num_cells - 1), 1.0);
    std::filesystem::remove(path);
  }
#endif
}

}  // namespace
}  // namespace rc
