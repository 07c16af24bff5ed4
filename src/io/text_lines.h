// Line and token scanning over an in-memory text buffer (no iostreams), with line numbers for error messages.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

namespace rc {

class LineReader {
 public:
  explicit LineReader(std::string_view text, size_t first_line_number = 1)
      : text_(text), next_line_number_(first_line_number) {}

  /// The next line without its terminator ("\n" or "\r\n"); false at the end of the text.
  bool next(std::string_view* line);
  /// Number of the line last returned by next().
  size_t lineNumber() const { return next_line_number_ - 1; }
  /// Byte offset just past the terminator of the line last returned.
  size_t offset() const { return pos_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  size_t next_line_number_;
};

/// Splits `line` at blanks (space, tab, CR, vertical tab, form feed) into `tokens` (cleared first).
void splitTokens(std::string_view line, std::vector<std::string_view>* tokens);
/// `line` up to (excluding) the first `marker`.
std::string_view stripComment(std::string_view line, char marker = '#');
/// `line` without leading and trailing blanks.
std::string_view trimBlanks(std::string_view line);

/// Whole-token number parsing (a leading '+' is accepted); false when the token is not a number.
bool parseDouble(std::string_view token, double* value);
bool parseInt64(std::string_view token, int64_t* value);

}  // namespace rc
