#include "relaxed_connectivity/io/text_lines.h"

#include <charconv>
#include <cstring>

namespace rc {

namespace {
inline bool isBlank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}
inline std::string_view withoutPlus(std::string_view token) {
  if (token.size() > 1 && token[0] == '+') token.remove_prefix(1);
  return token;
}
}  // namespace

bool LineReader::next(std::string_view* line) {
  if (pos_ >= text_.size()) return false;
  const char* begin = text_.data() + pos_;
  const void* nl = std::memchr(begin, '\n', text_.size() - pos_);
  size_t length = nl ? static_cast<const char*>(nl) - begin : text_.size() - pos_;
  pos_ += length + (nl ? 1 : 0);
  if (length > 0 && begin[length - 1] == '\r') --length;
  *line = std::string_view(begin, length);
  ++next_line_number_;
  return true;
}

void splitTokens(std::string_view line, std::vector<std::string_view>* tokens) {
  tokens->clear();
  size_t i = 0;
  const size_t n = line.size();
  while (i < n) {
    while (i < n && isBlank(line[i])) ++i;
    if (i == n) break;
    const size_t start = i;
    while (i < n && !isBlank(line[i])) ++i;
    tokens->push_back(line.substr(start, i - start));
  }
}

std::string_view stripComment(std::string_view line, char marker) {
  const size_t at = line.find(marker);
  return at == std::string_view::npos ? line : line.substr(0, at);
}

std::string_view trimBlanks(std::string_view line) {
  while (!line.empty() && isBlank(line.front())) line.remove_prefix(1);
  while (!line.empty() && isBlank(line.back())) line.remove_suffix(1);
  return line;
}

bool parseDouble(std::string_view token, double* value) {
  token = withoutPlus(token);
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, *value);
  return result.ec == std::errc() && result.ptr == end;
}

bool parseInt64(std::string_view token, int64_t* value) {
  token = withoutPlus(token);
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, *value);
  return result.ec == std::errc() && result.ptr == end;
}

}  // namespace rc
