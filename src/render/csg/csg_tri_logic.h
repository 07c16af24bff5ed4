// Three-valued logic of the CSG inside/outside classification (thesis 4.2.2): true, false and unknown, where
// unknown means "no clipping partner of that patch", with the extended AND/OR of (4.9)/(4.10).
#pragma once

#include <cstdint>

namespace rc {

enum class Tri : uint8_t { kFalse = 0, kTrue = 1, kUnknown = 2 };

inline Tri toTri(bool b) {
  return b ? Tri::kTrue : Tri::kFalse;
}

/// Negation; unknown stays unknown (complemented leaves, 4.3).
inline Tri triNot(Tri a) {
  return a == Tri::kUnknown ? Tri::kUnknown : (a == Tri::kTrue ? Tri::kFalse : Tri::kTrue);
}

/// b AND unknown = b (4.10); otherwise the Boolean AND.
inline Tri triAnd(Tri a, Tri b) {
  if (a == Tri::kUnknown) return b;
  if (b == Tri::kUnknown) return a;
  return toTri(a == Tri::kTrue && b == Tri::kTrue);
}

/// b OR unknown = b (4.9); otherwise the Boolean OR.
inline Tri triOr(Tri a, Tri b) {
  if (a == Tri::kUnknown) return b;
  if (b == Tri::kUnknown) return a;
  return toTri(a == Tri::kTrue || b == Tri::kTrue);
}

inline const char* triName(Tri a) {
  return a == Tri::kTrue ? "true" : (a == Tri::kFalse ? "false" : "unknown");
}

}  // namespace rc
