#include "relaxed_connectivity/io/yaml_reader.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rc {

YAML::Node YamlReader::parseMap(const std::string& yaml_text, const std::string& not_a_map) const {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    raise_(name_ + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
           ": YAML syntax: " + e.msg);
    throw;  // raise_ is expected to throw
  }
  if (!root.IsMap()) fail(root, not_a_map);
  return root;
}

std::string YamlReader::readFile(const std::string& path, Raise raise) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    // (scenes, brush presets, paint types, palettes: the reader's caller names what the file is for)
    raise(path + ": cannot open the file (" + std::strerror(errno) + ")");
    throw std::runtime_error(path + ": cannot open the file");
  }
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string YamlReader::at(const YAML::Node& node) const {
  std::ostringstream s;
  s << name_;
  if (node.IsDefined() && node.Mark().line >= 0)
    s << ":" << node.Mark().line + 1 << ":" << node.Mark().column + 1;
  return s.str();
}

void YamlReader::box(const YAML::Node& map, const std::string& where, Vec3* lo, Vec3* hi) const {
  *lo = vec3(require(map, "lo", where), where + ".lo");
  *hi = vec3(require(map, "hi", where), where + ".hi");
  if (!(lo->array() <= hi->array()).all()) fail(map["hi"], where + ": hi must not be below lo");
}

std::array<bool, 3> YamlReader::components(const YAML::Node& node, const std::string& what) const {
  const std::string names = string(node, what);
  std::array<bool, 3> named = {false, false, false};
  if (names.empty()) fail(node, what + ": empty (letters of xyz)");
  for (char k : names) {
    if (k < 'x' || k > 'z') fail(node, what + ": '" + names + "' (letters of xyz, e.g. xz)");
    if (named[size_t(k - 'x')]) fail(node, what + ": '" + names + "' repeats " + k);
    named[size_t(k - 'x')] = true;
  }
  return named;
}

std::string YamlReader::word(const YAML::Node& node, const std::string& what) const {
  const std::string name = string(node, what);
  const bool is_word = !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
  if (!is_word) fail(node, what + ": '" + name + "' (letters, digits and _: a CSV column prefix)");
  return name;
}

void YamlReader::fail(const YAML::Node& node, const std::string& problem) const {
  std::ostringstream s;
  s << at(node) << ": " << problem;
  raise_(s.str());
  throw std::runtime_error(s.str());  // raise_ is expected to throw; never return in any case
}

YAML::Node YamlReader::require(const YAML::Node& map, const std::string& key,
                               const std::string& where) const {
  const YAML::Node value = map[key];
  if (!value) fail(map, where + ": missing '" + key + "'");
  return value;
}

void YamlReader::allowKeys(const YAML::Node& map, const std::set<std::string>& keys,
                           const std::string& where) const {
  if (!map.IsMap()) fail(map, where + ": expected a map");
  for (const auto& kv : map) {
    const std::string key = kv.first.as<std::string>();
    if (!keys.count(key)) {
      std::string known;
      for (const std::string& k : keys) known += (known.empty() ? "" : ", ") + k;
      fail(kv.first, where + ": unknown key '" + key + "' (known: " + known + ")");
    }
  }
}

double YamlReader::number(const YAML::Node& node, const std::string& what) const {
  if (!node.IsScalar()) fail(node, what + ": expected a number");
  double v = 0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    fail(node, what + ": expected a number, got '" + node.Scalar() + "'");
  }
  if (!std::isfinite(v)) fail(node, what + ": must be finite");
  return v;
}

double YamlReader::positive(const YAML::Node& node, const std::string& what) const {
  const double v = number(node, what);
  if (!(v > 0)) fail(node, what + " must be positive, got " + node.Scalar());
  return v;
}

double YamlReader::nonNegative(const YAML::Node& node, const std::string& what) const {
  const double v = number(node, what);
  if (!(v >= 0)) fail(node, what + " must be >= 0, got " + node.Scalar());
  return v;
}

double YamlReader::unitInterval(const YAML::Node& node, const std::string& what) const {
  const double v = number(node, what);
  if (!(v >= 0 && v <= 1)) fail(node, what + " must lie in [0, 1], got " + node.Scalar());
  return v;
}

long YamlReader::integer(const YAML::Node& node, const std::string& what, long lo, long hi) const {
  const double v = number(node, what);
  if (v != std::floor(v) || v < lo || v > hi)
    fail(node, what + " must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                   "], got " + node.Scalar());
  return long(v);
}

bool YamlReader::boolean(const YAML::Node& node, const std::string& what) const {
  if (!node.IsScalar()) fail(node, what + ": expected true or false");
  try {
    return node.as<bool>();
  } catch (const YAML::Exception&) {
    fail(node, what + ": expected true or false, got '" + node.Scalar() + "'");
  }
}

std::string YamlReader::string(const YAML::Node& node, const std::string& what) const {
  if (!node.IsScalar()) fail(node, what + ": expected a string");
  return node.as<std::string>();
}

Vec3 YamlReader::vec3(const YAML::Node& node, const std::string& what) const {
  if (!node.IsSequence() || node.size() != 3) fail(node, what + ": expected [x, y, z]");
  return Vec3(number(node[0], what), number(node[1], what), number(node[2], what));
}

}  // namespace rc
