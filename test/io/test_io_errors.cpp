// Bad input gives an IoError that names the file, the place and the problem.
#include <gtest/gtest.h>

#include "io_test_support.h"
#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/io/file_bytes.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/off_io.h"
#include "relaxed_connectivity/io/pcd_io.h"
#include "relaxed_connectivity/io/ply_io.h"

namespace rc {
namespace {

using test::tempPath;
using test::writeText;

// Runs `read` and expects an IoError whose message contains every one of `parts`.
template <typename Read>
void expectIoError(Read read, std::initializer_list<std::string> parts) {
  try {
    read();
    ADD_FAILURE() << "no exception";
  } catch (const IoError& e) {
    const std::string what = e.what();
    for (const std::string& part : parts)
      EXPECT_NE(what.find(part), std::string::npos) << "'" << part << "' not in: " << what;
  }
}

std::string binaryMeshFile() {
  const std::string path = tempPath("small_binary.ply");
  writePlyMesh(path, test::makeOctahedron());  // 6 vertices x 12 bytes, 8 faces x 13 bytes
  return readFileBytes(path);
}

TEST(IoErrors, TruncatedBinaryPly) {
  const std::string full = binaryMeshFile();
  const size_t body = full.find("end_header\n") + 11;
  const std::string path = tempPath("truncated.ply");
  writeText(path, full.substr(0, body + 2 * 12 + 5));  // vertex #2 is cut after 5 bytes
  expectIoError([&] { readPlyMesh(path); },
                {"truncated.ply", "element 'vertex' #2", "unexpected end of file"});
  writeText(path, full.substr(0, full.size() - 3));  // the last face loses its last index
  expectIoError([&] { readPlyMesh(path); }, {"truncated.ply", "element 'face' #7", "unexpected end of file"});
  EXPECT_EQ(readPlyCloud(path).size(), 6u);  // the vertices alone are complete
}

TEST(IoErrors, BadPlyHeaders) {
  const std::string path = tempPath("bad_header.ply");
  writeText(path, "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty flaot x\nend_header\n");
  expectIoError([&] { readPlyCloud(path); },
                {"bad_header.ply", "header line 4", "unknown property type 'flaot'"});
  writeText(path, "PLY?\nformat ascii 1.0\n");
  expectIoError([&] { readPlyCloud(path); }, {"bad_header.ply", "line 1", "not a PLY file"});
  writeText(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
  expectIoError([&] { readPlyCloud(path); }, {"bad_header.ply", "missing end_header"});
  writeText(path,
            "ply\nformat ascii 2.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n");
  expectIoError([&] { readPlyCloud(path); }, {"bad_header.ply", "element 'vertex'", "missing x, y or z"});
  writeText(path, "ply\nformat utf8 1.0\nend_header\n");
  expectIoError([&] { readPlyCloud(path); }, {"bad_header.ply", "header line 2", "unknown format 'utf8'"});
  // (found by fuzz_ply: a second vertex element's indices were checked against the first's count)
  writeText(path,
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nelement vertex 4\nend_header\n");
  expectIoError([&] { readPlyMesh(path); },
                {"bad_header.ply", "header line 5", "element 'vertex' declared twice"});
}

TEST(IoErrors, PlyCountsBeyondTheFileAreRefusedBeforeAllocating) {
  // A header claiming 2^40 vertices (12 TiB of floats) over a body of 12 bytes: refused, nothing allocated (a
  // count up to twice what the file holds is read until the data ends, TruncatedBinaryPly).
  const std::string path = tempPath("huge.ply");
  writeText(path,
            "ply\nformat binary_little_endian 1.0\nelement vertex 1099511627776\nproperty float x\n"
            "property float y\nproperty float z\nend_header\n" +
                std::string(12, '\0'));
  expectIoError([&] { readPlyCloud(path); },
                {"huge.ply", "element 'vertex'", "declares 1099511627776 elements of at least 12 bytes",
                 "12 bytes after its header"});
  writeText(path,
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1000000000\nproperty list uchar int vertex_indices\n"
            "end_header\n0 0 0\n1 1 1\n");
  expectIoError([&] { readPlyMesh(path); }, {"huge.ply", "element 'face'", "declares 1000000000 elements"});
  // The same for PCD (binary and ascii) and OFF.
  const std::string pcd = tempPath("huge.pcd");
  writeText(pcd,
            "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4000000000\nHEIGHT 1\n"
            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4000000000\nDATA binary\n" +
                std::string(12, '\0'));
  expectIoError([&] { readPcdCloud(pcd); }, {"huge.pcd", "POINTS 4000000000 of at least 12 bytes"});
  writeText(pcd,
            "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4000000000\nHEIGHT 1\n"
            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4000000000\nDATA ascii\n1 2 3\n");
  expectIoError([&] { readPcdCloud(pcd); }, {"huge.pcd", "POINTS 4000000000 of at least 6 bytes"});
  const std::string off = tempPath("huge.off");
  writeText(off, "OFF\n4000000000 1 0\n0 0 0\n");
  expectIoError([&] { readOffMesh(off); }, {"huge.off", "counts of 4000000000 vertices"});
  // Exactly as many bytes as declared still reads.
  writeText(path,
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n1 2 3");
  EXPECT_EQ(readPlyCloud(path).size(), 1u);
}

TEST(IoErrors, PlyAsciiValueAndIndexProblems) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string path = tempPath("ascii_bad.ply");
  writeText(path, header + "0 0 0\n1 0 0\n0 1 abc\n3 0 1 2\n3 0 2 7\n");
  expectIoError([&] { readPlyMesh(path); },
                {"ascii_bad.ply", "element 'vertex' #2 (line 12)", "cannot parse 'abc' as float32"});
  writeText(path, header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 7\n");
  expectIoError([&] { readPlyMesh(path); },
                {"ascii_bad.ply", "element 'face' #1", "vertex index 7 out of range [0, 3)"});
  writeText(path, header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expectIoError([&] { readPlyMesh(path); }, {"ascii_bad.ply", "element 'face' #1", "unexpected end of file"});
}

TEST(IoErrors, OffCountsAndIndices) {
  const std::string path = tempPath("bad.off");
  writeText(path, "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n");
  expectIoError([&] { readOffMesh(path); }, {"bad.off", "vertex #3", "expected 4 vertices"});
  writeText(path, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  expectIoError([&] { readOffMesh(path); },
                {"bad.off", "face #0 (line 6)", "vertex index 3 out of range [0, 3)"});
  writeText(path, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n");
  expectIoError([&] { readOffMesh(path); }, {"bad.off", "face #0", "expected 4 vertex indices, found 3"});
  writeText(path, "STOFF\n");
  expectIoError([&] { readOffMesh(path); }, {"bad.off", "unsupported OFF variant 'STOFF'"});
}

TEST(IoErrors, PcdProblems) {
  const std::string path = tempPath("bad.pcd");
  const std::string header =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA "
      "binary\n";
  writeText(path, header + std::string(12 * 2 + 7, '\0'));
  expectIoError([&] { readPcdCloud(path); }, {"bad.pcd", "point #2", "unexpected end of file"});
  writeText(path, "VERSION 0.7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n0 0 0\n");
  expectIoError([&] { readPcdCloud(path); },
                {"bad.pcd", "header line 2", "SIZE has 2 entries but FIELDS has 3"});
  writeText(path, "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n");
  expectIoError([&] { readPcdCloud(path); }, {"bad.pcd", "WIDTH 2 x HEIGHT 2 does not match POINTS 3"});
  writeText(path, "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 2\nDATA ascii\n1 2 3\n4 5\n");
  expectIoError([&] { readPcdCloud(path); }, {"bad.pcd", "point #1 (line 7)", "expected 3 values, found 2"});
  // (found by fuzz_pcd: a COUNT of 8.9e15 made a compressed cloud's reader loop for minutes)
  writeText(path,
            "FIELDS x y z r\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 8888888888888881\nPOINTS 1\n"
            "DATA ascii\n1 2 3 4\n");
  expectIoError([&] { readPcdCloud(path); }, {"bad.pcd", "field 'r' has COUNT 8888888888888881, more than"});
  std::string compressed = header;
  compressed.replace(compressed.find("DATA binary"), 11, "DATA binary_compressed");
  const uint32_t sizes[2] = {4, 35};  // 35 != 3 points x 12 bytes
  compressed.append(reinterpret_cast<const char*>(sizes), 8);
  compressed += std::string(
      "\x03"
      "abcd",
      5);
  writeText(path, compressed);
  expectIoError([&] { readPcdCloud(path); },
                {"bad.pcd", "uncompressed size 35 does not match 3 points x 12 bytes"});
}

TEST(IoErrors, MissingFileAndUnknownExtension) {
  const std::string missing = tempPath("does_not_exist.ply");
  expectIoError([&] { readCloud(missing); }, {missing, "cannot open file"});
  expectIoError([&] { readMesh(tempPath("absent.obj")); }, {"absent.obj", "cannot open file"});
  expectIoError([&] { readCloud("model.stl"); }, {"model.stl", "unknown file extension '.stl'"});
  expectIoError([&] { writeCloud("noext", SurfelCloud()); }, {"noext", "unknown file extension ''"});
  expectIoError([&] { writeMesh(tempPath("mesh.xyz"), test::makeOctahedron()); },
                {"mesh.xyz", "cannot store the 8 triangles"});
}

TEST(CloudIo, DispatchIsCaseInsensitiveAndMeshesDegradeToClouds) {
  const TriangleMesh mesh = test::makeOctahedron();
  for (const char* name : {"UPPER.PLY", "mixed.Off", "obj.OBJ"}) {
    const std::string path = tempPath(name);
    writeMesh(path, mesh);
    EXPECT_EQ(readMesh(path).triangles, mesh.triangles) << name;
    test::expectCloudsEqual(mesh.vertices, readCloud(path));
  }
  for (const char* name : {"cloud.PCD", "cloud.Xyz"}) {
    const std::string path = tempPath(name);
    writeCloud(path, mesh.vertices);
    const TriangleMesh back = readMesh(path);
    EXPECT_TRUE(back.triangles.empty()) << name;
    test::expectCloudsEqual(mesh.vertices, back.vertices);
  }
}

}  // namespace
}  // namespace rc
