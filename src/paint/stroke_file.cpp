#include "relaxed_connectivity/paint/stroke_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace rc {
namespace {

const char* const kHeader = "t,x,y,z,qx,qy,qz,qw,buttons";
constexpr int kColumns = 9;
constexpr double kUnitTolerance = 1e-3;

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

std::vector<std::string> splitColumns(const std::string& line) {
  std::vector<std::string> columns;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) columns.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') columns.push_back("");
  return columns;
}

}  // namespace

std::vector<StrokeSample> parseStroke(const std::string& text, const std::string& source_name) {
  std::vector<StrokeSample> samples;
  std::istringstream in(text);
  std::string raw;
  int line_number = 0;
  bool header_seen = false;
  auto fail = [&](const std::string& problem) {
    throw StrokeFileError(source_name + ":" + std::to_string(line_number) + ": " + problem);
  };
  while (std::getline(in, raw)) {
    ++line_number;
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#') continue;
    if (!header_seen) {
      std::string compact;
      for (char c : line)
        if (c != ' ' && c != '\t') compact += c;
      if (compact != kHeader) fail("expected the header '" + std::string(kHeader) + "', got '" + line + "'");
      header_seen = true;
      continue;
    }
    const std::vector<std::string> columns = splitColumns(line);
    if (int(columns.size()) != kColumns)
      fail("expected " + std::to_string(kColumns) + " columns (" + kHeader + "), got " +
           std::to_string(columns.size()));
    double v[kColumns - 1];
    for (int i = 0; i < kColumns - 1; ++i) {
      const std::string& cell = columns[size_t(i)];
      char* end = nullptr;
      errno = 0;
      v[i] = std::strtod(cell.c_str(), &end);
      if (cell.empty() || *end != '\0' || errno == ERANGE)
        fail("column " + std::to_string(i + 1) + " '" + cell + "' is not a number");
      if (!std::isfinite(v[i])) fail("column " + std::to_string(i + 1) + " is not finite ('" + cell + "')");
    }
    const std::string& bits = columns[kColumns - 1];
    char* end = nullptr;
    errno = 0;
    const unsigned long buttons = std::strtoul(bits.c_str(), &end, 10);
    if (bits.empty() || *end != '\0' || bits[0] == '-' || errno == ERANGE || buttons > 0xffffffffUL)
      fail("buttons '" + bits + "' is not a bitmask (a non-negative integer below 2^32)");
    StrokeSample s;
    s.t = v[0];
    s.position = Vec3(v[1], v[2], v[3]);
    s.orientation = Eigen::Quaterniond(v[7], v[4], v[5], v[6]);
    const double norm = s.orientation.norm();
    if (!(std::abs(norm - 1.0) <= kUnitTolerance))
      fail("quaternion (" + columns[4] + ", " + columns[5] + ", " + columns[6] + ", " + columns[7] +
           ") has length " + std::to_string(norm) + ", not 1");
    s.orientation.normalize();
    s.buttons = uint32_t(buttons);
    if (!samples.empty() && !(s.t > samples.back().t))
      fail("time " + columns[0] + " does not increase (previous sample at " +
           std::to_string(samples.back().t) + ")");
    samples.push_back(s);
  }
  if (!header_seen) fail("no header line '" + std::string(kHeader) + "'");
  if (samples.empty()) fail("no samples");
  return samples;
}

std::vector<StrokeSample> readStrokeFile(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw StrokeFileError(path + ":0: cannot open the stroke file");
  std::stringstream ss;
  ss << file.rdbuf();
  return parseStroke(ss.str(), path);
}

std::string formatStroke(const std::vector<StrokeSample>& samples, const std::string& comment) {
  std::string out;
  std::istringstream lines(comment);
  std::string line;
  while (!comment.empty() && std::getline(lines, line)) out += "# " + line + "\n";
  out += std::string(kHeader) + "\n";
  char buffer[512];
  for (const StrokeSample& s : samples) {
    const Eigen::Quaterniond& q = s.orientation;
    std::snprintf(buffer, sizeof buffer, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%u\n", s.t,
                  s.position.x(), s.position.y(), s.position.z(), q.x(), q.y(), q.z(), q.w(), s.buttons);
    out += buffer;
  }
  return out;
}

void writeStrokeFile(const std::string& path, const std::vector<StrokeSample>& samples,
                     const std::string& comment) {
  std::ofstream file(path);
  file << formatStroke(samples, comment);
  if (!file) throw StrokeFileError(path + ":0: cannot write the stroke file");
}

StrokeSampler::StrokeSampler(std::vector<StrokeSample> samples) : samples_(std::move(samples)) {
  if (samples_.empty()) throw std::invalid_argument("a stroke needs at least one sample");
  for (size_t i = 1; i < samples_.size(); ++i)
    if (!(samples_[i].t > samples_[i - 1].t)) throw std::invalid_argument("stroke times must increase");
}

StrokeSample StrokeSampler::at(double t) const {
  if (!(t > samples_.front().t)) return samples_.front();
  if (t >= samples_.back().t) return samples_.back();
  const auto next = std::upper_bound(samples_.begin(), samples_.end(), t,
                                     [](double time, const StrokeSample& s) { return time < s.t; });
  const StrokeSample& a = *(next - 1);
  const StrokeSample& b = *next;
  const double u = (t - a.t) / (b.t - a.t);
  StrokeSample s;
  s.t = t;
  s.position = (1 - u) * a.position + u * b.position;
  s.orientation = a.orientation.slerp(u, b.orientation);
  s.buttons = a.buttons;
  return s;
}

}  // namespace rc
