// Reading checked values from YAML files with errors that name the file, the line, the column and the
// problem ("scene.yaml:12:5: spacing must be positive, got -1"), shared by the scene loaders.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <initializer_list>
#include <set>
#include <string>
#include <utility>

#include "relaxed_connectivity/core/surfel_cloud.h"

namespace rc {

class YamlReader {
 public:
  /// Throws its argument, "<source>:<line>:<column>: <problem>" (e.g. a loader's own exception type).
  using Raise = void (*)(const std::string& message);

  YamlReader(std::string source_name, Raise raise) : name_(std::move(source_name)), raise_(raise) {}
  const std::string& sourceName() const { return name_; }

  /// The root map of YAML text: a syntax error fails with "<source>:<line>:<column>: YAML syntax: <message>",
  /// a root that is not a map with "<source>:1:1: <not_a_map>".
  YAML::Node parseMap(const std::string& yaml_text, const std::string& not_a_map) const;
  /// The bytes of a file (binary); fails with "<path>: cannot open the file (<errno text>)".
  static std::string readFile(const std::string& path, Raise raise);

  /// "<source>:<line>:<column>" of a node (just "<source>" for one without a position), as fail() names it.
  std::string at(const YAML::Node& node) const;
  [[noreturn]] void fail(const YAML::Node& node, const std::string& problem) const;
  YAML::Node require(const YAML::Node& map, const std::string& key, const std::string& where) const;
  /// Fails for a non-map or for a key outside `keys` (the message lists the known keys).
  void allowKeys(const YAML::Node& map, const std::set<std::string>& keys, const std::string& where) const;

  double number(const YAML::Node& node, const std::string& what) const;
  double positive(const YAML::Node& node, const std::string& what) const;
  double nonNegative(const YAML::Node& node, const std::string& what) const;
  double unitInterval(const YAML::Node& node, const std::string& what) const;
  long integer(const YAML::Node& node, const std::string& what, long lo, long hi) const;
  bool boolean(const YAML::Node& node, const std::string& what) const;
  std::string string(const YAML::Node& node, const std::string& what) const;
  /// [x, y, z].
  Vec3 vec3(const YAML::Node& node, const std::string& what) const;
  /// The closed box {lo: [..], hi: [..]} of a map (keys required; fails where hi lies below lo).
  void box(const YAML::Node& map, const std::string& where, Vec3* lo, Vec3* hi) const;
  /// Components named by letters of xyz, each at most once (e.g. "xz"): which of x, y, z are named.
  std::array<bool, 3> components(const YAML::Node& node, const std::string& what) const;
  /// A name made of letters, digits and _ (a CSV column prefix, a topic word).
  std::string word(const YAML::Node& node, const std::string& what) const;
  /// Calls read(entry, "<what>[k]") for every entry of the list `node`; fails with "<what>: expected a list
  /// of <items>" for anything else.
  template <class Read>
  void forEachEntry(const YAML::Node& node, const std::string& what, const std::string& items,
                    Read&& read) const {
    if (!node.IsSequence()) fail(node, what + ": expected a list of " + items);
    for (size_t k = 0; k < node.size(); ++k) read(node[k], what + "[" + std::to_string(k) + "]");
  }
  /// The value of one of the named choices (an enum); fails with "<what>: unknown '<name>' (known: a, b)".
  template <class Value>
  Value choice(const YAML::Node& node, const std::string& what,
               std::initializer_list<std::pair<const char*, Value>> choices) const {
    const std::string name = string(node, what);
    for (const auto& [known, value] : choices)
      if (name == known) return value;
    fail(node, what + ": unknown '" + name + "' (known: " + knownNames(choices) + ")");
  }

  /// "a, b, c": the names of the choices.
  template <class Value>
  static std::string knownNames(std::initializer_list<std::pair<const char*, Value>> choices) {
    std::string names;
    for (const auto& choice : choices) names += (names.empty() ? "" : ", ") + std::string(choice.first);
    return names;
  }

 private:
  std::string name_;
  Raise raise_;
};

}  // namespace rc
