// rc_surface smooth as a user runs it on a positions-only scan: each weight projects every point (a clipped
// Gaussian once lost its cut-off and projected none), the sphere fit estimates normals when the file has none
// (and says so), and bad options stop with a message.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include "relaxed_connectivity/io/cloud_io.h"
#include "relaxed_connectivity/surface/analytic_shapes.h"

namespace {

using namespace rc;

#ifdef RC_SURFACE_TOOL
struct ToolRun {
  int status = -1;
  std::string output;  // stdout and stderr
};

ToolRun runTool(const std::string& arguments) {
  ToolRun run;
  const std::string command = std::string(RC_SURFACE_TOOL) + " " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return run;
  std::array<char, 512> buffer;
  while (fgets(buffer.data(), buffer.size(), pipe)) run.output += buffer.data();
  run.status = pclose(pipe);
  return run;
}

#endif

double rmsToSphere(const std::vector<Vec3>& points) {
  double sum = 0;
  for (const Vec3& p : points) sum += (p.norm() - 1.0) * (p.norm() - 1.0);
  return std::sqrt(sum / static_cast<double>(points.size()));
}

TEST(RcSurfaceCli, SmoothsAPositionsOnlyScanWithEveryWeight) {
#ifndef RC_SURFACE_TOOL
  GTEST_SKIP() << "built without the tools (RC_BUILD_TOOLS=OFF)";
#else
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "rc_surface_cli_test";
  std::filesystem::create_directories(dir);
  const AnalyticSphere sphere(Vec3::Zero(), 1.0);
  const size_t n = 4000;
  const double h = sphere.spacing(n);
  SurfelCloud noisy = sphere.sample(n, {SamplingPattern::kUniformRandom, 0.3 * h, 9});
  noisy.normals.clear();
  const std::string in = (dir / "noisy.ply").string(), out = (dir / "smooth.ply").string();
  writeCloud(in, noisy);
  const double input = rmsToSphere(noisy.positions);
  struct Case {
    std::string options;
    const char* says;
  };
  for (const Case& c :
       {Case{"--fit plane", "weight wendland, support"}, Case{"--fit sphere", "normals: refined"},
        Case{"--fit sphere --normals estimated --weight gaussian", "sigma"},
        Case{"--fit sphere --weight clipped_gaussian --clip 2.5 --iterations 1", "normals: refined"},
        Case{"--fit polynomial --weight clipped_gaussian", "clipped_gaussian, sigma"}}) {
    std::filesystem::remove(out);
    const ToolRun run = runTool("smooth " + in + " " + out + " " + c.options);
    ASSERT_EQ(run.status, 0) << c.options << "\n" << run.output;
    EXPECT_NE(run.output.find(c.says), std::string::npos) << c.options << "\n" << run.output;
    EXPECT_NE(run.output.find(", 0 without a valid projection"), std::string::npos) << c.options << "\n"
                                                                                    << run.output;
    const SurfelCloud smooth = readCloud(out);
    ASSERT_EQ(smooth.size(), n) << c.options;
    const double rms = rmsToSphere(smooth.positions);
    std::printf("%-70s rms %.3e (input %.3e)\n", c.options.c_str(), rms, input);
    EXPECT_LT(rms, 0.6 * input) << c.options;
  }
  const ToolRun no_normals = runTool("smooth " + in + " " + out + " --fit sphere --normals input");
  EXPECT_NE(no_normals.status, 0);
  EXPECT_NE(no_normals.output.find("--normals input: the file has no normals"), std::string::npos)
      << no_normals.output;
  const ToolRun bad_clip = runTool("smooth " + in + " " + out + " --weight clipped_gaussian --clip 0");
  EXPECT_NE(bad_clip.status, 0);
  EXPECT_NE(bad_clip.output.find("--clip must be a positive number"), std::string::npos) << bad_clip.output;
  std::filesystem::remove_all(dir);
#endif
}

}  // namespace
