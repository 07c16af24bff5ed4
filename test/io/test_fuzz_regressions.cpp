// Inputs the fuzzers found (scripts/fuzz, test/fuzz/regressions/<format>/): each is refused with an IoError
// that names the file, read as a cloud and as a mesh, and nothing crashes or allocates beyond the file's
// size.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/io/io_error.h"

namespace rc {
namespace {

const std::string kRegressions = std::string(RC_SOURCE_DIR) + "/test/fuzz/regressions";

TEST(FuzzRegressions, EveryFoundInputIsRefusedWithAnIoError) {
  size_t inputs = 0;
  for (const auto& format : std::filesystem::directory_iterator(kRegressions))
    for (const auto& input : std::filesystem::directory_iterator(format.path())) {
      SCOPED_TRACE(input.path().string());
      ++inputs;
      int refused = 0;
      for (bool as_mesh : {false, true}) {
        try {  // (a cloud read stops after the vertices: the bad part may lie beyond)
          if (as_mesh) {
            (void)readMesh(input.path().string());
          } else {
            (void)readCloud(input.path().string());
          }
        } catch (const IoError& e) {
          ++refused;
          EXPECT_NE(std::string(e.what()).find(input.path().filename().string()), std::string::npos)
              << e.what();
        }
      }
      EXPECT_GE(refused, 1);
    }
  EXPECT_GE(inputs, 2u);
}

TEST(FuzzRegressions, IntegerTokensOutsideTheirTypeAreRefused) {
  // An ascii PCD with an unsigned 32-bit field holding 1.67e12 (written as a float): refused, not wrapped.
  const std::string path = ::testing::TempDir() + "rc_integer_range.pcd";
  std::ofstream(path) << "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 1\n"
                         "HEIGHT 1\nPOINTS 1\nDATA ascii\n0 0 0 1.67e12\n";
  EXPECT_THROW(readCloud(path), IoError);
  std::ofstream(path) << "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 1\n"
                         "HEIGHT 1\nPOINTS 1\nDATA ascii\n0 0 0 4.0e3\n";
  EXPECT_NO_THROW(readCloud(path));  // an integer written as a float within range stays accepted
}

}  // namespace
}  // namespace rc
