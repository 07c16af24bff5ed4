#include "relaxed_connectivity/io/scalar_codec.h"

#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

#include "relaxed_connectivity/io/text_lines.h"

namespace rc {

namespace {
template <typename T>
T load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <typename T>
void store(T v, uint8_t* p) {
  std::memcpy(p, &v, sizeof(T));
}
template <typename T>
bool parseInteger(std::string_view token, uint8_t* out) {
  if (token.size() > 1 && token[0] == '+') token.remove_prefix(1);
  T v;
  const char* end = token.data() + token.size();
  const auto r = std::from_chars(token.data(), end, v);
  if (r.ec == std::errc() && r.ptr == end) {
    store(v, out);
    return true;
  }
  double d;  // "3.0" or "1e3" written for an integer property (within the type's range: found by fuzzing)
  if (!parseDouble(token, &d) || d != std::floor(d)) return false;
  if (!(d >= double(std::numeric_limits<T>::min()) && d <= double(std::numeric_limits<T>::max())))
    return false;
  store(static_cast<T>(d), out);
  return true;
}
template <typename T>
void appendNumber(T v, std::string* out) {
  char buffer[64];
  const auto r = std::to_chars(buffer, buffer + sizeof(buffer), v);
  out->append(buffer, r.ptr);
}
}  // namespace

int64_t scalarToInt64(const uint8_t* p, ScalarType type) {
  // Every integer type up to 32 bits is exact in a double; non-finite floats map to -1, floats beyond the
  // int64 range to its ends (the conversion itself would be undefined).
  const double d = scalarToDouble(p, type);
  if (!std::isfinite(d)) return -1;
  if (d >= 9.2e18) return std::numeric_limits<int64_t>::max();
  if (d <= -9.2e18) return std::numeric_limits<int64_t>::min();
  return static_cast<int64_t>(d);
}

bool parseScalar(std::string_view token, ScalarType type, uint8_t* out) {
  switch (type) {
    case ScalarType::kInt8:
      return parseInteger<int8_t>(token, out);
    case ScalarType::kUInt8:
      return parseInteger<uint8_t>(token, out);
    case ScalarType::kInt16:
      return parseInteger<int16_t>(token, out);
    case ScalarType::kUInt16:
      return parseInteger<uint16_t>(token, out);
    case ScalarType::kInt32:
      return parseInteger<int32_t>(token, out);
    case ScalarType::kUInt32:
      return parseInteger<uint32_t>(token, out);
    case ScalarType::kFloat32: {
      if (token.size() > 1 && token[0] == '+') token.remove_prefix(1);
      float v;
      const char* end = token.data() + token.size();
      const auto r = std::from_chars(token.data(), end, v);
      if (r.ec != std::errc() || r.ptr != end) return false;
      store(v, out);
      return true;
    }
    case ScalarType::kFloat64: {
      double v;
      if (!parseDouble(token, &v)) return false;
      store(v, out);
      return true;
    }
  }
  return false;
}

void appendScalarText(const uint8_t* p, ScalarType type, std::string* out) {
  switch (type) {
    case ScalarType::kInt8:
      appendNumber(static_cast<int>(load<int8_t>(p)), out);
      break;
    case ScalarType::kUInt8:
      appendNumber(static_cast<int>(load<uint8_t>(p)), out);
      break;
    case ScalarType::kInt16:
      appendNumber(load<int16_t>(p), out);
      break;
    case ScalarType::kUInt16:
      appendNumber(load<uint16_t>(p), out);
      break;
    case ScalarType::kInt32:
      appendNumber(load<int32_t>(p), out);
      break;
    case ScalarType::kUInt32:
      appendNumber(load<uint32_t>(p), out);
      break;
    case ScalarType::kFloat32:
      appendNumber(load<float>(p), out);
      break;
    case ScalarType::kFloat64:
      appendNumber(load<double>(p), out);
      break;
  }
}

void appendDoubleText(double value, std::string* out) {
  appendNumber(value, out);
}

}  // namespace rc
