// Stroke files: round trip, errors naming file:line, deterministic sampling.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

#include "relaxed_connectivity/paint/stroke_file.h"

namespace rc {
namespace {

std::vector<StrokeSample> someStroke() {
  std::vector<StrokeSample> samples;
  for (int k = 0; k < 50; ++k) {
    StrokeSample s;
    s.t = 0.0137 * k + 0.1;
    s.position = Vec3(std::sin(0.3 * k) * 0.04, 1.0 / 3.0 * 0.01 * k, -0.002 * k);
    s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.05 * k, Vec3(1, 2, 3).normalized()));
    s.buttons = k > 10 && k < 40 ? 1u : 0u;
    samples.push_back(s);
  }
  return samples;
}

std::string errorOf(const std::string& text) {
  try {
    parseStroke(text, "s.csv");
  } catch (const StrokeFileError& e) {
    return e.what();
  }
  return "no error";
}

TEST(StrokeFile, RoundTripIsExact) {
  const std::vector<StrokeSample> written = someStroke();
  const std::string path = (std::filesystem::temp_directory_path() / "rc_test_stroke.csv").string();
  writeStrokeFile(path, written, "a test stroke\nsecond comment line");
  const std::vector<StrokeSample> read = readStrokeFile(path);
  ASSERT_EQ(read.size(), written.size());
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(read[i].t, written[i].t);
    EXPECT_EQ(read[i].position, written[i].position);
    EXPECT_EQ(read[i].buttons, written[i].buttons);
    EXPECT_NEAR(read[i].orientation.angularDistance(written[i].orientation), 0, 1e-12);
  }
  std::filesystem::remove(path);
}

TEST(StrokeFile, ErrorsNameFileLineAndProblem) {
  const std::string header = "# comment\nt,x,y,z,qx,qy,qz,qw,buttons\n";
  EXPECT_EQ(errorOf(header + "0,0,0,0,0,0,0,1,0\n0.1,0,0,0,0,0,0,1\n"),
            "s.csv:4: expected 9 columns (t,x,y,z,qx,qy,qz,qw,buttons), got 8");
  EXPECT_EQ(errorOf(header + "0,0,0,0,0,0,0,1,0\n0,0,0,0,0,0,0,1,0\n"),
            "s.csv:4: time 0 does not increase (previous sample at 0.000000)");
  EXPECT_EQ(errorOf(header + "\n0,nan,0,0,0,0,0,1,0\n"), "s.csv:4: column 2 is not finite ('nan')");
  EXPECT_EQ(errorOf(header + "0,0,0,0,0,0,0,1.1,0\n"),
            "s.csv:3: quaternion (0, 0, 0, 1.1) has length 1.100000, not 1");
  EXPECT_EQ(errorOf(header + "0,0,0,0,0,0,0,1,-1\n"),
            "s.csv:3: buttons '-1' is not a bitmask (a non-negative integer below 2^32)");
  EXPECT_EQ(errorOf(header + "0,0,x,0,0,0,0,1,0\n"), "s.csv:3: column 3 'x' is not a number");
  EXPECT_EQ(errorOf("t,x,y,z\n"),
            "s.csv:1: expected the header 't,x,y,z,qx,qy,qz,qw,buttons', got 't,x,y,z'");
  EXPECT_EQ(errorOf(header), "s.csv:2: no samples");
  EXPECT_NE(std::string(errorOf("")).find("no header"), std::string::npos);
  try {
    readStrokeFile("/nonexistent/stroke.csv");
    ADD_FAILURE();
  } catch (const StrokeFileError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/stroke.csv:0: cannot open the stroke file");
  }
}

TEST(StrokeSampler, InterpolatesAndClamps) {
  StrokeSample a, b;
  a.t = 1;
  b.t = 3;
  b.position = Vec3(2, 0, -4);
  b.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Vec3::UnitZ()));
  b.buttons = 1;
  StrokeSampler sampler({a, b});
  const StrokeSample mid = sampler.at(1.5);
  EXPECT_LT((mid.position - Vec3(0.5, 0, -1)).norm(), 1e-15);
  EXPECT_NEAR(mid.orientation.angularDistance(a.orientation), 0.25, 1e-12);
  EXPECT_EQ(mid.buttons, 0u);
  EXPECT_EQ(sampler.at(3.0).buttons, 1u);
  EXPECT_EQ(sampler.at(0.0).position, a.position);
  EXPECT_EQ(sampler.at(9.0).position, b.position);
  EXPECT_EQ(sampler.duration(), 2.0);
}

TEST(StrokeSampler, ReplayingTwiceIsBitwiseIdentical) {
  const std::string text = formatStroke(someStroke());
  auto replay = [&] {
    StrokeSampler sampler(parseStroke(text, "s.csv"));
    std::vector<double> out;
    for (int k = 0; k <= 1000; ++k) {
      const StrokeSample s = sampler.at(sampler.startTime() + k * 1e-3);
      out.insert(out.end(), {s.t, s.position.x(), s.position.y(), s.position.z(), s.orientation.x(),
                             s.orientation.y(), s.orientation.z(), s.orientation.w(), double(s.buttons)});
    }
    return out;
  };
  const std::vector<double> first = replay(), second = replay();
  ASSERT_EQ(first.size(), second.size());
  EXPECT_EQ(std::memcmp(first.data(), second.data(), first.size() * sizeof(double)), 0);
}

TEST(StrokeFile, ShippedStrokesRead) {
  const std::string here = __FILE__;
  const std::filesystem::path dir = here.substr(0, here.rfind("/test/")) + "/config/paint/strokes";
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".csv") continue;
    ++files;
    const std::string name = entry.path().filename().string();
    const std::vector<StrokeSample> samples = readStrokeFile(entry.path().string());
    EXPECT_GT(samples.size(), 100u) << name;
    bool painted = false;
    for (const StrokeSample& s : samples) painted |= (s.buttons & 1u) != 0;
    EXPECT_TRUE(painted) << name;
  }
  EXPECT_GE(files, 4u);  // straight, spiral, edge, session
}

}  // namespace
}  // namespace rc
