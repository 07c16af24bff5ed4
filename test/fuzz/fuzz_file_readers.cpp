// libFuzzer target for the file readers (src/io): the input becomes a file with the extension
// RC_FUZZ_EXTENSION (one binary per format: fuzz_ply, fuzz_pcd, fuzz_off, fuzz_obj, fuzz_xyz) and is read as
// a cloud and as a mesh. A reader may refuse the input (IoError or another std::exception with a message); it
// must not crash, hang, or allocate without bound (scripts/fuzz runs with -timeout=1 -rss_limit_mb=2048).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

#include "relaxed_connectivity/io/cloud_io.h"

namespace {

const std::string& inputPath() {
  static const std::string path =
      "/dev/shm/rc_fuzz_" + std::to_string(::getpid()) + std::string(RC_FUZZ_EXTENSION);
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = inputPath();
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  for (bool keep_invalid : {true, false}) {
    rc::ReadOptions options;
    options.keep_invalid = keep_invalid;
    try {
      const rc::SurfelCloud cloud = rc::readCloud(path, options);
      cloud.validate();  // what a reader returns is consistent
    } catch (const std::exception&) {
    }
    try {
      (void)rc::readMesh(path, options);
    } catch (const std::exception&) {
    }
  }
  return 0;
}
