// Keys of lattice indices shared by the elastic solid's neighbourhood assignment and its docking (thesis
// 8.2.1, 8.2.5): a packed 30-bit key and the slot in the keeper table of SphLatticeAssignment.
#pragma once

#include <algorithm>
#include <cstdint>

#include <Eigen/Core>

namespace rc {

/// The keeper table of SphLatticeAssignment spans lattice indices [-8, 8)^3.
inline constexpr int kLatticeTableHalfWidth = 8;

/// Lattice index packed into 30 bits (10 per coordinate, offset 512).
[[gnu::always_inline]] inline uint32_t latticeKey(const Eigen::Vector3i& n) {
  const auto c = [](int v) { return uint32_t(std::clamp(v + 512, 0, 1023)); };
  return (c(n.x()) << 20) | (c(n.y()) << 10) | c(n.z());
}

/// Slot of lattice index n in the keeper table of the indices [-8, 8)^3 (x fastest), -1 outside.
[[gnu::always_inline]] inline int32_t latticeTableSlot(const Eigen::Vector3i& n) {
  constexpr int kHalf = kLatticeTableHalfWidth, kWidth = 2 * kHalf;
  const unsigned ux = unsigned(n.x() + kHalf), uy = unsigned(n.y() + kHalf), uz = unsigned(n.z() + kHalf);
  if (ux >= unsigned(kWidth) || uy >= unsigned(kWidth) || uz >= unsigned(kWidth)) return -1;
  return int32_t((uz * kWidth + uy) * kWidth + ux);
}

}  // namespace rc
