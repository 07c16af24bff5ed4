// Shared by the tests that read the probes' CSV files: rows of comma-separated cells.
#pragma once

#include <istream>
#include <sstream>
#include <string>
#include <vector>

namespace rc::test {

/// The remaining lines of `in`, each split at commas.
inline std::vector<std::vector<std::string>> readCsvRows(std::istream& in) {
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

}  // namespace rc::test
