// The one exception type of the file I/O module: its message names the file, the place (element/line, when
// known) and the problem, e.g. "bunny.ply: element 'vertex' #12: unexpected end of file".
#pragma once

#include <stdexcept>
#include <string>

namespace rc {

class IoError : public std::runtime_error {
 public:
  IoError(const std::string& file, const std::string& where, const std::string& problem)
      : std::runtime_error(compose(file, where, problem)), file_(file), where_(where), problem_(problem) {}
  IoError(const std::string& file, const std::string& problem) : IoError(file, std::string(), problem) {}

  const std::string& file() const { return file_; }
  /// "element 'vertex' #12", "line 57", ... (empty when the problem concerns the whole file)
  const std::string& where() const { return where_; }
  const std::string& problem() const { return problem_; }

 private:
  static std::string compose(const std::string& file, const std::string& where, const std::string& problem) {
    return where.empty() ? file + ": " + problem : file + ": " + where + ": " + problem;
  }
  std::string file_, where_, problem_;
};

}  // namespace rc
