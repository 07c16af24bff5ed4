// dynamic_reconfigure in the rostests: a ~set_parameters request from named values, and the values of the
// node's answer.
#pragma once

#include <dynamic_reconfigure/Reconfigure.h>

#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace rc {

/// A request setting the given doubles, ints and bools (the others keep their values).
inline dynamic_reconfigure::Reconfigure reconfigureRequest(
    const std::vector<std::pair<std::string, double>>& doubles,
    const std::vector<std::pair<std::string, int>>& ints = {},
    const std::vector<std::pair<std::string, bool>>& bools = {}) {
  dynamic_reconfigure::Reconfigure r;
  for (const auto& [name, value] : doubles) {
    dynamic_reconfigure::DoubleParameter p;
    p.name = name;
    p.value = value;
    r.request.config.doubles.push_back(p);
  }
  for (const auto& [name, value] : ints) {
    dynamic_reconfigure::IntParameter p;
    p.name = name;
    p.value = value;
    r.request.config.ints.push_back(p);
  }
  for (const auto& [name, value] : bools) {
    dynamic_reconfigure::BoolParameter p;
    p.name = name;
    p.value = value;
    r.request.config.bools.push_back(p);
  }
  return r;
}

/// A double of a config (NaN if absent).
inline double doubleOf(const dynamic_reconfigure::Config& c, const std::string& name) {
  for (const auto& d : c.doubles)
    if (d.name == name) return d.value;
  return std::numeric_limits<double>::quiet_NaN();
}

/// An int of a config (-1 if absent).
inline int intOf(const dynamic_reconfigure::Config& c, const std::string& name) {
  for (const auto& i : c.ints)
    if (i.name == name) return i.value;
  return -1;
}

/// A bool of a config as 0 / 1 (-1 if absent).
inline int boolOf(const dynamic_reconfigure::Config& c, const std::string& name) {
  for (const auto& b : c.bools)
    if (b.name == name) return int(b.value);
  return -1;
}

}  // namespace rc
