// Conversions between raw scalar bytes (rc::ScalarType, host byte order), integers and text; to and from
// doubles: scalarToDouble / doubleToScalar in core/attribute.h.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "relaxed_connectivity/core/attribute.h"

namespace rc {

inline bool hostIsLittleEndian() {
  const uint16_t one = 1;
  uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

inline void reverseBytes(uint8_t* p, size_t n) {
  std::reverse(p, p + n);
}

/// The scalar at `p` as an integer (floating-point values are truncated).
int64_t scalarToInt64(const uint8_t* p, ScalarType type);
/// Parses a text token as `type` into `out`; integers written as "3.0" are accepted. False if not a number.
bool parseScalar(std::string_view token, ScalarType type, uint8_t* out);
/// Appends the scalar at `p` as text that reads back to the same value (shortest round-trip form).
void appendScalarText(const uint8_t* p, ScalarType type, std::string* out);
/// Appends a double in shortest round-trip form.
void appendDoubleText(double value, std::string* out);

}  // namespace rc
