#include "relaxed_connectivity/io/cloud_io.h"

#include "relaxed_connectivity/io/file_bytes.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/obj_io.h"
#include "relaxed_connectivity/io/off_io.h"
#include "relaxed_connectivity/io/pcd_io.h"
#include "relaxed_connectivity/io/ply_io.h"
#include "relaxed_connectivity/io/xyz_io.h"

namespace rc {

namespace {

enum class Format { kPly, kPcd, kOff, kObj, kXyz };

Format formatOf(const std::string& path) {
  const std::string ext = lowerCaseExtension(path);
  if (ext == ".ply") return Format::kPly;
  if (ext == ".pcd") return Format::kPcd;
  if (ext == ".off") return Format::kOff;
  if (ext == ".obj") return Format::kObj;
  if (ext == ".xyz") return Format::kXyz;
  throw IoError(path, "unknown file extension '" + ext + "' (supported: .ply .pcd .off .obj .xyz)");
}

}  // namespace

SurfelCloud readCloud(const std::string& path, const ReadOptions& options) {
  switch (formatOf(path)) {
    case Format::kPly:
      return readPlyCloud(path, options);
    case Format::kPcd:
      return readPcdCloud(path, options);
    case Format::kOff:
      return std::move(readOffMesh(path, options).vertices);
    case Format::kObj:
      return std::move(readObjMesh(path, options).vertices);
    case Format::kXyz:
      return readXyzCloud(path, options);
  }
  return SurfelCloud();
}

TriangleMesh readMesh(const std::string& path, const ReadOptions& options) {
  TriangleMesh mesh;
  switch (formatOf(path)) {
    case Format::kPly:
      return readPlyMesh(path, options);
    case Format::kOff:
      return readOffMesh(path, options);
    case Format::kObj:
      return readObjMesh(path, options);
    case Format::kPcd:
      mesh.vertices = readPcdCloud(path, options);
      break;
    case Format::kXyz:
      mesh.vertices = readXyzCloud(path, options);
      break;
  }
  return mesh;
}

void writeCloud(const std::string& path, const SurfelCloud& cloud, const WriteOptions& options) {
  switch (formatOf(path)) {
    case Format::kPly:
      writePlyCloud(path, cloud, options);
      return;
    case Format::kPcd:
      writePcdCloud(path, cloud, options);
      return;
    case Format::kXyz:
      writeXyzCloud(path, cloud);
      return;
    case Format::kOff:
    case Format::kObj: {
      TriangleMesh mesh;
      mesh.vertices = cloud;
      writeMesh(path, mesh, options);
      return;
    }
  }
}

void writeMesh(const std::string& path, const TriangleMesh& mesh, const WriteOptions& options) {
  switch (formatOf(path)) {
    case Format::kPly:
      writePlyMesh(path, mesh, options);
      return;
    case Format::kOff:
      writeOffMesh(path, mesh);
      return;
    case Format::kObj:
      writeObjMesh(path, mesh);
      return;
    case Format::kPcd:
    case Format::kXyz:
      if (!mesh.triangles.empty())
        throw IoError(path, "this format cannot store the " + std::to_string(mesh.triangles.size()) +
                                " triangles of a mesh (use .ply, .off or .obj)");
      writeCloud(path, mesh.vertices, options);
      return;
  }
}

}  // namespace rc
